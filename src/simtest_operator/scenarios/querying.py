"""Scenario databases: ask, read back a list of ``{id, url | content}`` items.

Two protocols share one item format (and this one parser of it): GraphQL (POST the query; the
list is the one field of ``data`` — ``{"data": {"scenarios": [...]}}`` — or the
``nodes``/``items``/``edges[].node`` of a connection object in that field) and REST (GET the URL;
the list is the document itself or the one ``items``/``scenarios``/``results``/``data`` list of
an object). The response is untrusted like any download (bounded, strictly shaped). A bearer
token comes from an injected secret provider (a Kubernetes Secret in the operator, the pod's
``secretKeyRef`` variable in a simulator pod, an environment variable for ``simtest run``) and
never appears in an error message, even one where the server quotes it back
(:mod:`~simtest_operator.redaction`).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from simtest_operator import redaction
from simtest_operator.errors import SourceError
from simtest_operator.scenarios import downloading
from simtest_operator.scenarios.specs import (
    DatabaseSource,
    GraphqlSource,
    RestSource,
    SecretRef,
    SourceLimits,
)

SecretProvider = Callable[[SecretRef], str]
"""Returns the value of a Secret key; raises SourceError when it is not available."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class DatabaseItem:
    """One scenario named by a database (GraphQL or REST)."""

    id: str
    url: str | None = None
    """Where to download the .xosc file."""
    content: bytes | None = None
    """The .xosc file inline."""


MAX_ERROR_TEXT = 500
"""Characters of a server's error messages quoted in ours (one line)."""
REST_LIST_FIELDS = ("items", "scenarios", "results", "data")
"""Fields of a REST response object that may hold the item list (exactly one of them must)."""


def location(source: DatabaseSource) -> str:
    """The URL a database source is asked at (and its inline items are pinned under)."""
    return source.endpoint if isinstance(source, GraphqlSource) else source.url


def query(
    source: DatabaseSource,
    *,
    limits: SourceLimits,
    scratch: Path,
    secrets: SecretProvider | None,
) -> tuple[DatabaseItem, ...]:
    """Ask the database and return its items in response order."""
    where = location(source)
    headers = {"Accept": "application/json"}
    token = ""
    if source.secret is not None:
        if secrets is None:
            raise SourceError(
                f"{where}: the source needs Secret {source.secret.name}/"
                f"{source.secret.key}, but no secret provider is configured"
            )
        token = secrets(source.secret)
        headers["Authorization"] = f"Bearer {token}"
    body: bytes | None = None
    if isinstance(source, GraphqlSource):
        headers["Content-Type"] = "application/json"
        body = json.dumps({"query": source.query, "variables": dict(source.variables)}).encode()
    # Everything the server answers may quote the request back (an error echoing the
    # Authorization header put the token on stdout): the token is masked in any error.
    with redaction.Secrets.of(token).masking():
        raw = downloading.fetch_bytes(
            where, limits=limits, scratch=scratch, data=body, headers=headers
        )
        try:
            document = json.loads(raw)
        except (ValueError, UnicodeDecodeError, RecursionError) as exc:
            raise SourceError(f"{where}: response is not JSON ({exc})") from exc
        if isinstance(source, RestSource):
            return parse_items(_rest_list(document, where), endpoint=where, limits=limits)
        return parse_response(document, endpoint=where, limits=limits)


def parse_response(
    document: Any, *, endpoint: str, limits: SourceLimits
) -> tuple[DatabaseItem, ...]:
    """The items of a GraphQL response document; SourceError when it has errors or no list."""
    if not isinstance(document, Mapping):
        raise SourceError(f"{endpoint}: response must be a JSON object")
    errors = document.get("errors")
    if errors:
        messages = [
            str(e.get("message", e)) if isinstance(e, Mapping) else str(e)
            for e in (errors if isinstance(errors, list) else [errors])
        ]
        summary = " ".join("; ".join(messages[:3]).split())
        if len(summary) > MAX_ERROR_TEXT:
            summary = summary[: MAX_ERROR_TEXT - 3] + "..."
        raise SourceError(f"{endpoint}: query failed: {summary}")
    return parse_items(_the_list(document.get("data"), endpoint), endpoint=endpoint, limits=limits)


def parse_items(
    rows: list[Any], *, endpoint: str, limits: SourceLimits
) -> tuple[DatabaseItem, ...]:
    """The ``{id, url | content}`` items of a database's list, ids unique; SourceError naming the
    item otherwise."""
    if len(rows) > limits.max_files:
        raise SourceError(f"{endpoint}: more than {limits.max_files} scenarios in the response")
    items: list[DatabaseItem] = []
    seen: set[str] = set()
    for index, row in enumerate(rows):
        item = _item(row, index=index, endpoint=endpoint)
        if item.id in seen:
            raise SourceError(f"{endpoint}: scenario id {item.id!r} appears twice")
        seen.add(item.id)
        items.append(item)
    return tuple(items)


def _the_list(data: Any, endpoint: str) -> list[Any]:
    if not isinstance(data, Mapping) or len(data) != 1:
        raise SourceError(f"{endpoint}: 'data' must hold exactly one field with the scenario list")
    (value,) = data.values()
    if isinstance(value, list):
        return value
    if isinstance(value, Mapping):
        for key in ("nodes", "items"):
            if isinstance(value.get(key), list):
                return list(value[key])
        edges = value.get("edges")
        if isinstance(edges, list):
            return [edge.get("node") if isinstance(edge, Mapping) else edge for edge in edges]
    raise SourceError(f"{endpoint}: the field in 'data' is not a list (or a connection)")


def _rest_list(document: Any, endpoint: str) -> list[Any]:
    if isinstance(document, list):
        return document
    if isinstance(document, Mapping):
        found = [k for k in REST_LIST_FIELDS if isinstance(document.get(k), list)]
        if len(found) == 1:
            return list(document[found[0]])
        if len(found) > 1:
            raise SourceError(
                f"{endpoint}: response has several item lists ({', '.join(found)}); "
                "expected exactly one"
            )
    raise SourceError(
        f"{endpoint}: response must be a JSON list of scenarios or an object with one of the "
        f"list fields {', '.join(REST_LIST_FIELDS)}"
    )


def _item(row: Any, *, index: int, endpoint: str) -> DatabaseItem:
    where = f"{endpoint}: item {index}"
    if not isinstance(row, Mapping):
        raise SourceError(f"{where} is not an object")
    ident = row.get("id")
    if isinstance(ident, bool) or not isinstance(ident, str | int) or str(ident) == "":
        raise SourceError(f"{where} has no string or integer 'id'")
    url, content = row.get("url"), row.get("content")
    if (url is None) == (content is None):
        raise SourceError(f"{where} ({ident}) must have exactly one of 'url' or 'content'")
    if url is not None:
        if not isinstance(url, str):
            raise SourceError(f"{where} ({ident}) has a non-string 'url'")
        try:
            downloading.check_http_url(url)
        except SourceError as exc:
            raise SourceError(f"{where} ({ident}): {exc}") from exc
        return DatabaseItem(id=str(ident), url=url)
    if not isinstance(content, str):
        raise SourceError(f"{where} ({ident}) has a non-string 'content'")
    return DatabaseItem(id=str(ident), content=content.encode("utf-8"))
