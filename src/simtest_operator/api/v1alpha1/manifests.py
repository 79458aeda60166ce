"""Whole manifests: apiVersion, kind, metadata and spec, validated as the API server would.

``simtest run`` and ``simtest submit`` read manifests through here, so a manifest the cluster would
reject is rejected locally with the same field path, before anything runs.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping
from typing import Any, Generic

import pydantic

from simtest_operator.api.v1alpha1 import common, kinds
from simtest_operator.errors import ScenarioError

DNS1123_SUBDOMAIN = re.compile(r"^[a-z0-9]([-a-z0-9]*[a-z0-9])?(\.[a-z0-9]([-a-z0-9]*[a-z0-9])?)*$")
OBJECT_META_STRINGS = frozenset(
    {"name", "generateName", "namespace", "uid", "resourceVersion", "selfLink",
     "creationTimestamp", "deletionTimestamp"}
)  # fmt: skip
"""ObjectMeta fields the API server types as strings (timestamps are RFC 3339 text)."""
OBJECT_META_OTHERS = frozenset(
    {"labels", "annotations", "finalizers", "generation", "deletionGracePeriodSeconds",
     "ownerReferences", "managedFields"}
)  # fmt: skip
"""The other ObjectMeta fields; anything else in ``metadata`` is refused, as the API server's
strict field validation (kubectl's default) does."""


SHOWN_PROBLEMS = 5
"""Problems a :class:`ManifestError` message names; the rest are counted. 150,000 unknown keys
once made one 3.49 MB error line (issue 29)."""
SHOWN_CHARACTERS = 120
"""A field path or message longer than this (a megabyte-long key) is cut in the message."""


class ManifestError(ScenarioError):
    """A manifest does not validate; ``problems`` lists ``(field path, message)`` pairs."""

    def __init__(self, source: str, problems: list[tuple[str, str]]) -> None:
        self.problems = problems
        lines = "; ".join(
            f"{_brief(path)}: {_brief(message)}" for path, message in problems[:SHOWN_PROBLEMS]
        )
        if len(problems) > SHOWN_PROBLEMS:
            lines += f"; and {len(problems) - SHOWN_PROBLEMS:,} more ({len(problems):,} in all)"
        super().__init__(f"invalid manifest: {lines}", file=source)


def _brief(text: str) -> str:
    flat = " ".join(text.split())
    return flat if len(flat) <= SHOWN_CHARACTERS else flat[: SHOWN_CHARACTERS - 1] + "…"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Manifest(Generic[kinds.SpecT]):
    """A validated custom resource."""

    kind: kinds.ResourceKind[kinds.SpecT]
    name: str
    namespace: str | None
    labels: Mapping[str, str]
    spec: kinds.SpecT
    raw: Mapping[str, Any]
    """The document as read, for applying it unchanged to a cluster."""


def parse(document: Any, *, source: str = "<manifest>") -> Manifest[Any]:
    """Validate one manifest document of any of the three kinds."""
    if not isinstance(document, Mapping):
        raise ManifestError(source, [("", "a manifest must be a mapping")])
    problems: list[tuple[str, str]] = []
    api_version = document.get("apiVersion")
    if api_version != common.API_VERSION:
        problems.append(("apiVersion", f"must be {common.API_VERSION!r}, got {api_version!r}"))
    kind_name = document.get("kind")
    kind = next((k for k in kinds.KINDS if k.kind == kind_name), None)
    if kind is None:
        known = ", ".join(k.kind for k in kinds.KINDS)
        problems.append(("kind", f"must be one of {known}, got {kind_name!r}"))
    metadata = document.get("metadata")
    name, namespace, labels = _check_metadata(metadata, kind, problems)
    # str(): YAML keys need not be strings (``? [a]``, an empty key is None) and must not crash.
    unknown = sorted(
        str(key) for key in set(document) - {"apiVersion", "kind", "metadata", "spec", "status"}
    )
    problems.extend((key, "unknown field") for key in unknown)
    spec_doc = document.get("spec")
    if spec_doc is None:
        problems.append(("spec", "required field is missing"))
    spec: Any = None
    if kind is not None and spec_doc is not None:
        try:
            spec = kind.spec.model_validate(spec_doc)
        except pydantic.ValidationError as exc:
            problems.extend(_pydantic_problems(exc, prefix="spec"))
    if problems or kind is None:
        raise ManifestError(source, problems)
    return Manifest(
        kind=kind, name=name, namespace=namespace, labels=labels, spec=spec, raw=document
    )


def parse_campaign(
    document: Any, *, source: str = "<manifest>"
) -> Manifest[kinds.TestCampaignSpec]:
    """Validate a TestCampaign manifest; any other kind is an error."""
    manifest = parse(document, source=source)
    if manifest.kind is not kinds.TEST_CAMPAIGN:
        raise ManifestError(source, [("kind", f"expected TestCampaign, got {manifest.kind.kind}")])
    return manifest


def _check_metadata(
    metadata: Any, kind: kinds.ResourceKind[Any] | None, problems: list[tuple[str, str]]
) -> tuple[str, str | None, Mapping[str, str]]:
    if not isinstance(metadata, Mapping):
        problems.append(("metadata", "required field is missing"))
        return "", None, {}
    name = metadata.get("name")
    if not isinstance(name, str) or not name:
        problems.append(("metadata.name", "required field is missing"))
        name = ""
    elif len(name) > 253 or not DNS1123_SUBDOMAIN.match(name):
        problems.append(
            (
                "metadata.name",
                f"{name!r} is not a lowercase RFC 1123 subdomain "
                "(lower-case alphanumerics, '-' or '.', starting and ending alphanumeric)",
            )
        )
    elif kind is kinds.TEST_CAMPAIGN and (
        len(name) > kinds.CAMPAIGN_NAME_MAX or not re.fullmatch(common.DNS1123_LABEL, name)
    ):
        problems.append(
            (
                "metadata.name",
                f"a TestCampaign name must be an RFC 1123 label of at most "
                f"{kinds.CAMPAIGN_NAME_MAX} characters (child objects derive their names from it)",
            )
        )
    _check_meta_types(metadata, problems)
    namespace = metadata.get("namespace")
    labels = metadata.get("labels")
    return (
        name,
        namespace if isinstance(namespace, str) else None,
        labels if isinstance(labels, Mapping) and _is_string_map(labels) else {},
    )


def _check_meta_types(metadata: Mapping[Any, Any], problems: list[tuple[str, str]]) -> None:
    """ObjectMeta's field names and types, as strict as the API server's decoder."""
    for key in sorted(metadata, key=str):
        value, path = metadata[key], f"metadata.{key}"
        if key in OBJECT_META_STRINGS:
            if value is not None and not isinstance(value, str):
                problems.append((path, f"must be a string, got {type(value).__name__}"))
        elif key in ("labels", "annotations"):
            if value is not None and not _is_string_map(value):
                problems.append((path, "must be a mapping of strings to strings"))
        elif key == "finalizers":
            if value is not None and not (
                isinstance(value, list) and all(isinstance(v, str) for v in value)
            ):
                problems.append((path, "must be a list of strings"))
        elif key in ("generation", "deletionGracePeriodSeconds"):
            if value is not None and (isinstance(value, bool) or not isinstance(value, int)):
                problems.append((path, f"must be an integer, got {type(value).__name__}"))
        elif key not in OBJECT_META_OTHERS:
            problems.append((path, "unknown field"))


def _is_string_map(value: Any) -> bool:
    return value is None or (
        isinstance(value, Mapping)
        and all(isinstance(k, str) and isinstance(v, str) for k, v in value.items())
    )


def _pydantic_problems(exc: pydantic.ValidationError, *, prefix: str) -> list[tuple[str, str]]:
    problems = []
    for error in exc.errors():
        location = [str(part) for part in error["loc"] if not str(part).startswith("function-")]
        path = prefix
        for part in location:
            path += f"[{part}]" if part.isdigit() else f".{part}"
        message = error["msg"]
        if error["type"] == "extra_forbidden":
            message = "unknown field"
        elif error["type"] == "missing":
            message = "required field is missing"
        problems.append((path, message.removeprefix("Value error, ")))
    return problems
