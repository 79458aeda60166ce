"""The small spec a ROS 2 repository writes to get its Helm chart (``simtest package ros SPEC``).

A repository knows its image, its entrypoint and its parameter files; everything else has a
default in the K8s-ROS base chart. The spec is untrusted input (it comes from any repository's
CI), so it is checked field by field and every problem names the key it is about::

    name: planner                        # chart name (RFC 1123 label)
    version: 1.4.0                       # chart version (SemVer)
    image: ghcr.io/acme/planner:1.4.0    # or {repository, tag, digest}
    entrypoint: [ros2, run, planner, planner_node]
    params: [config/planner.yaml]        # relative to the spec file
    # optional: appVersion, description, args, kind, ros, dds, resources,
    #           templates (folder of template overrides), values (any base-chart values), base
"""

from __future__ import annotations

import dataclasses
import re
import shlex
from collections.abc import Mapping
from pathlib import PurePosixPath
from typing import Any

import yaml

from simtest_operator.errors import RenderError

DNS_LABEL = re.compile(r"^[a-z0-9]([-a-z0-9]*[a-z0-9])?$")
SEMVER = re.compile(
    r"^v?(0|[1-9]\d*)\.(0|[1-9]\d*)\.(0|[1-9]\d*)"
    r"(-[0-9A-Za-z-]+(\.[0-9A-Za-z-]+)*)?(\+[0-9A-Za-z-]+(\.[0-9A-Za-z-]+)*)?$"
)
PARAMS_NAME = re.compile(r"^[-._a-zA-Z0-9]+$")
DIGEST = re.compile(r"^sha256:[0-9a-f]{64}$")
KINDS = ("Deployment", "Job")
MAX_NAME = 53
"""Helm release and chart names stay short enough for derived object names."""

_KNOWN = frozenset(
    {
        "name", "version", "appVersion", "description", "image", "entrypoint", "args", "kind",
        "params", "ros", "dds", "resources", "templates", "values", "base",
    }
)  # fmt: skip
_SECTION_VALUES = ("ros", "dds", "resources")
"""Spec keys copied verbatim into the base chart's values (the chart's schema checks them)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class BaseChart:
    """Which K8s-ROS base chart the generated chart depends on."""

    version: str | None = None
    """Base chart version; None takes the version of the base chart being vendored."""
    repository: str = ""
    """Chart repository (``oci://...``, ``https://...``) for ``helm dependency update``; empty
    means the base chart is vendored into ``charts/`` and needs no repository."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RosPackageSpec:
    """A validated package spec."""

    name: str
    version: str
    app_version: str
    description: str
    image: str | Mapping[str, str]
    entrypoint: tuple[str, ...]
    args: tuple[str, ...]
    kind: str
    params: tuple[PurePosixPath, ...]
    """Parameter files, relative to the spec's folder."""
    templates: PurePosixPath | None
    """Folder of template overrides, relative to the spec's folder."""
    sections: Mapping[str, Any]
    """``ros``, ``dds`` and ``resources`` as written."""
    values: Mapping[str, Any]
    """Further base-chart values, merged last."""
    base: BaseChart


def parse(text: str, *, source: str = "spec") -> RosPackageSpec:
    """Parse and check a spec; raises :class:`RenderError` naming the offending key."""
    try:
        raw = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise RenderError(f"{source}: not valid YAML: {exc}") from exc
    if not isinstance(raw, dict):
        raise RenderError(f"{source}: must be a mapping with at least name, version and image")
    unknown = sorted(set(map(str, raw)) - _KNOWN)
    if unknown:
        raise RenderError(f"{source}: unknown keys {unknown}; known: {sorted(_KNOWN)}")
    name = _string(raw, "name", source, required=True)
    if not DNS_LABEL.match(name) or len(name) > MAX_NAME:
        raise RenderError(
            f"{source}: name {name!r} must be a lower-case RFC 1123 label of at most "
            f"{MAX_NAME} characters"
        )
    version = _string(raw, "version", source, required=True)
    if not SEMVER.match(version):
        raise RenderError(f"{source}: version {version!r} is not a SemVer version (e.g. 1.2.0)")
    kind = _string(raw, "kind", source) or "Deployment"
    if kind not in KINDS:
        raise RenderError(f"{source}: kind must be one of {list(KINDS)}, got {kind!r}")
    sections = {}
    for key in _SECTION_VALUES:
        if key in raw:
            sections[key] = _mapping(raw, key, source)
    return RosPackageSpec(
        name=name,
        version=version,
        app_version=_string(raw, "appVersion", source) or version,
        description=_string(raw, "description", source)
        or f"ROS 2 application {name}, packaged on the K8s-ROS base chart",
        image=_image(raw.get("image"), source),
        entrypoint=_words(raw, "entrypoint", source),
        args=_words(raw, "args", source),
        kind=kind,
        params=_params(raw.get("params", []), source),
        templates=_relative(raw["templates"], "templates", source) if "templates" in raw else None,
        sections=sections,
        values=_mapping(raw, "values", source) if "values" in raw else {},
        base=_base(raw.get("base", {}), source),
    )


def _string(raw: Mapping[str, Any], key: str, source: str, *, required: bool = False) -> str:
    value = raw.get(key)
    if value is None:
        if required:
            raise RenderError(f"{source}: {key} is required")
        return ""
    if isinstance(value, bool) or not isinstance(value, str | int | float):
        raise RenderError(f"{source}: {key} must be a string, got {type(value).__name__}")
    return str(value)


def _mapping(raw: Mapping[str, Any], key: str, source: str) -> dict[str, Any]:
    value = raw.get(key)
    if not isinstance(value, dict):
        raise RenderError(f"{source}: {key} must be a mapping, got {type(value).__name__}")
    return value


def _words(raw: Mapping[str, Any], key: str, source: str) -> tuple[str, ...]:
    value = raw.get(key)
    if value is None:
        return ()
    if isinstance(value, str):
        try:
            return tuple(shlex.split(value))
        except ValueError as exc:
            raise RenderError(f"{source}: {key}: {exc}") from exc
    if isinstance(value, list) and all(isinstance(item, str | int | float) for item in value):
        return tuple(str(item) for item in value)
    raise RenderError(f"{source}: {key} must be a list of strings or one command line")


def _image(value: Any, source: str) -> str | Mapping[str, str]:
    if isinstance(value, str) and value.strip():
        if any(ch.isspace() for ch in value):
            raise RenderError(f"{source}: image {value!r} contains whitespace")
        return value
    if isinstance(value, dict):
        allowed = {"repository", "tag", "digest", "pullPolicy"}
        unknown = sorted(set(value) - allowed)
        if unknown:
            raise RenderError(f"{source}: image has unknown keys {unknown}")
        if not isinstance(value.get("repository"), str) or not value["repository"]:
            raise RenderError(f"{source}: image.repository is required")
        digest = value.get("digest", "")
        if digest and not DIGEST.match(str(digest)):
            raise RenderError(f"{source}: image.digest must look like sha256:<64 hex digits>")
        return {key: str(value[key]) for key in sorted(value)}
    raise RenderError(f"{source}: image is required (a `repository:tag` string or a mapping)")


def _relative(value: Any, key: str, source: str) -> PurePosixPath:
    if not isinstance(value, str) or not value:
        raise RenderError(f"{source}: {key} must be a relative path")
    path = PurePosixPath(value)
    if path.is_absolute() or ".." in path.parts:
        raise RenderError(f"{source}: {key} {value!r} must stay inside the spec's folder")
    return path


def _params(value: Any, source: str) -> tuple[PurePosixPath, ...]:
    if not isinstance(value, list):
        raise RenderError(f"{source}: params must be a list of file paths")
    paths = tuple(_relative(item, "params", source) for item in value)
    names = [path.name for path in paths]
    for name in names:
        if not PARAMS_NAME.match(name):
            raise RenderError(f"{source}: params file name {name!r} is not a valid ConfigMap key")
    duplicates = sorted({name for name in names if names.count(name) > 1})
    if duplicates:
        raise RenderError(f"{source}: params files share a file name: {duplicates}")
    return paths


def _base(value: Any, source: str) -> BaseChart:
    if not isinstance(value, dict) or set(value) - {"version", "repository"}:
        raise RenderError(f"{source}: base must be a mapping with version and/or repository")
    version = value.get("version")
    if version is not None and not SEMVER.match(str(version)):
        raise RenderError(f"{source}: base.version {version!r} is not a SemVer version")
    repository = str(value.get("repository", ""))
    if repository and not re.match(r"^(oci|https?|file)://", repository):
        raise RenderError(f"{source}: base.repository must be an oci://, https:// or file:// URL")
    return BaseChart(version=None if version is None else str(version), repository=repository)
