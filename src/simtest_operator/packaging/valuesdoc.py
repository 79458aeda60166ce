"""A chart's values reference, read from the ``# --`` comments of its ``values.yaml`` (helm-docs).

Each documented key is one row: dotted path, type, default, description. docs/install.md embeds the
operator chart's table between two markers; a test regenerates it and fails on drift, so the
documentation cannot fall behind the chart. A ``# --`` comment documents the key that follows it;
undocumented leaves under a documented key are described by that key's row.
"""

from __future__ import annotations

import dataclasses
import json
import re
from collections.abc import Iterator
from typing import Any

import yaml

from simtest_operator.errors import RenderError

BEGIN = "<!-- values-table:begin -->"
END = "<!-- values-table:end -->"
_KEY = re.compile(r"^(?P<indent> *)(?P<key>[A-Za-z_][A-Za-z0-9_.-]*):(?:\s|$)")
_DOC = re.compile(r"^ *# -- ?(?P<text>.*)$")
_MORE = re.compile(r"^ *# ?(?P<text>.*)$")


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ValueDoc:
    """One documented key."""

    path: str
    type: str
    default: str
    description: str


def documented(values_text: str) -> list[ValueDoc]:
    """Every ``# --`` documented key of a values file, in file order."""
    values = yaml.safe_load(values_text) or {}
    rows = []
    for path, description in _comments(values_text):
        rows.append(
            ValueDoc(
                path=path,
                type=_type(_lookup(values, path)),
                default=_default(_lookup(values, path)),
                description=description,
            )
        )
    return rows


def undocumented(values_text: str) -> list[str]:
    """Leaf keys with no ``# --`` comment on themselves or on an enclosing key."""
    values = yaml.safe_load(values_text) or {}
    covered = {path for path, _ in _comments(values_text)}
    missing = []
    for path in _leaves(values):
        parts = path.split(".")
        if not any(".".join(parts[:n]) in covered for n in range(1, len(parts) + 1)):
            missing.append(path)
    return missing


def table(rows: list[ValueDoc]) -> str:
    """A Markdown table of the rows."""
    lines = ["| key | type | default | description |", "|---|---|---|---|"]
    for row in rows:
        default = row.default.replace("|", "\\|")
        description = row.description.replace("|", "\\|")
        lines.append(f"| `{row.path}` | {row.type} | `{default}` | {description} |")
    return "\n".join(lines) + "\n"


def embed(document: str, rows: list[ValueDoc]) -> str:
    """``document`` with the text between the two markers replaced by :func:`table`."""
    start = document.find(BEGIN)
    stop = document.find(END)
    if start < 0 or stop < start:
        raise RenderError(f"the document has no {BEGIN} ... {END} block")
    return document[: start + len(BEGIN)] + "\n" + table(rows) + document[stop:]


def _comments(text: str) -> Iterator[tuple[str, str]]:
    stack: list[tuple[int, str]] = []
    pending: list[str] | None = None
    for line in text.splitlines():
        doc = _DOC.match(line)
        if doc:
            pending = [doc["text"].strip()]
            continue
        more = _MORE.match(line)
        if more and pending is not None and line.strip().startswith("#"):
            pending.append(more["text"].strip())
            continue
        key = _KEY.match(line)
        if key is None:
            if line.strip() and not line.strip().startswith("#"):
                pending = None
            continue
        indent = len(key["indent"])
        while stack and stack[-1][0] >= indent:
            stack.pop()
        stack.append((indent, key["key"]))
        if pending is not None:
            yield ".".join(name for _, name in stack), " ".join(part for part in pending if part)
            pending = None


def _lookup(values: Any, path: str) -> Any:
    node = values
    for part in path.split("."):
        if not isinstance(node, dict) or part not in node:
            raise RenderError(f"documented key {path} is not in the values")
        node = node[part]
    return node


def _leaves(node: Any, prefix: str = "") -> Iterator[str]:
    if isinstance(node, dict) and node:
        for key, value in node.items():
            yield from _leaves(value, f"{prefix}.{key}" if prefix else str(key))
    elif prefix:
        yield prefix


def _type(value: Any) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "int"
    if isinstance(value, float):
        return "float"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list):
        return "list"
    return "object"


def _default(value: Any) -> str:
    return json.dumps(value, sort_keys=False, separators=(", ", ": "))
