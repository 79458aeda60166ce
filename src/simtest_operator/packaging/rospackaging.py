"""Generate a repository's Helm chart from its package spec (the paper's K8s-ROS packaging step).

The generated chart is a thin *wrapper*: its ``Chart.yaml`` depends on the versioned K8s-ROS base
chart, its ``values.yaml`` holds the repository's settings (image, entrypoint, parameter files
inlined as text) under the ``k8s-ros`` key, and its ``templates/`` holds the repository's optional
template overrides. The base chart is vendored into ``charts/k8s-ros/`` by default, so the result
renders offline and byte-identically in CI; with a base repository it can instead be fetched by
``helm dependency update``. Why a wrapper and not a copy: see docs/ros-packaging.md.

:func:`chart_files` is pure (inputs in, ``{path: bytes}`` out); :func:`load_inputs` and
:func:`write` are the only functions touching the file system.
"""

from __future__ import annotations

import dataclasses
import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path, PurePosixPath
from typing import Any

import yaml

from simtest_operator.errors import RenderError
from simtest_operator.packaging import rosspecs

BASE_CHART_NAME = "k8s-ros"
VALUES_KEY = BASE_CHART_NAME
"""The wrapper passes values to the base chart under the dependency's name."""
TEMPLATE_SUFFIXES = (".yaml", ".yml", ".tpl", ".txt")
MAX_PARAMS_BYTES = 512 * 1024
"""Parameter files end up in one ConfigMap (1 MiB limit with metadata and DDS config)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class PackageInputs:
    """Everything a chart is generated from, already read from disk."""

    spec: rosspecs.RosPackageSpec
    params: Mapping[str, str]
    """Parameter file name -> text, in the spec's order."""
    overrides: Mapping[str, bytes]
    """Template override path (relative to ``templates/``) -> content."""
    base_chart: Mapping[str, bytes]
    """The K8s-ROS base chart's files (relative path -> content)."""


def load_inputs(spec_path: Path, base_chart_dir: Path) -> PackageInputs:
    """Read the spec, its parameter files, its template overrides and the base chart."""
    try:
        text = spec_path.read_text(encoding="utf-8")
    except OSError as exc:
        raise RenderError(f"cannot read package spec {spec_path}: {exc}") from exc
    spec = rosspecs.parse(text, source=str(spec_path))
    root = spec_path.resolve().parent
    params = {}
    for relative in spec.params:
        path = _inside(root, relative, spec_path)
        params[relative.name] = _params_text(path, spec_path)
    overrides: dict[str, bytes] = {}
    if spec.templates is not None:
        folder = _inside(root, spec.templates, spec_path)
        if not folder.is_dir():
            raise RenderError(f"{spec_path}: templates {spec.templates} is not a folder")
        for path in sorted(folder.rglob("*")):
            if path.is_file():
                _inside(root, PurePosixPath(path.relative_to(root).as_posix()), spec_path)
                overrides[path.relative_to(folder).as_posix()] = path.read_bytes()
    return PackageInputs(
        spec=spec, params=params, overrides=overrides, base_chart=read_chart(base_chart_dir)
    )


def read_chart(chart_dir: Path) -> dict[str, bytes]:
    """A chart folder's files (hidden files other than ``.helmignore`` left out)."""
    if not (chart_dir / "Chart.yaml").is_file():
        raise RenderError(f"{chart_dir} is not a Helm chart (no Chart.yaml)")
    files = {}
    for path in sorted(chart_dir.rglob("*")):
        relative = path.relative_to(chart_dir)
        hidden = any(part.startswith(".") for part in relative.parts)
        if path.is_file() and (not hidden or relative.as_posix() == ".helmignore"):
            files[relative.as_posix()] = path.read_bytes()
    return files


def chart_files(inputs: PackageInputs, *, vendor: bool = True) -> dict[str, bytes]:
    """The generated chart: relative path -> content, in a stable order."""
    spec = inputs.spec
    base_meta = _chart_meta(inputs.base_chart)
    base_version = spec.base.version or str(base_meta["version"])
    if vendor and base_version != str(base_meta["version"]):
        raise RenderError(
            f"{spec.name}: base.version {base_version} differs from the base chart being "
            f"vendored ({base_meta['version']}); drop base.version or package with --no-vendor"
        )
    if not vendor and not spec.base.repository:
        raise RenderError(
            f"{spec.name}: without vendoring, base.repository must say where k8s-ros comes from"
        )
    for relative in inputs.overrides:
        if not relative.endswith(TEMPLATE_SUFFIXES):
            raise RenderError(
                f"{spec.name}: template override {relative} must end with one of "
                f"{', '.join(TEMPLATE_SUFFIXES)}"
            )
    files: dict[str, bytes] = {
        "Chart.yaml": _dump(_chart_yaml(spec, base_version)),
        "values.yaml": _values_text(spec, inputs.params),
        ".helmignore": inputs.base_chart.get(".helmignore", b""),
        "README.md": _readme(spec, base_version).encode("utf-8"),
    }
    for relative, content in sorted(inputs.overrides.items()):
        files[f"templates/{relative}"] = content
    if vendor:
        for relative, content in sorted(inputs.base_chart.items()):
            files[f"charts/{BASE_CHART_NAME}/{relative}"] = content
    return files


def write(files: Mapping[str, bytes], out_dir: Path, name: str) -> Path:
    """Replace ``out_dir/name`` with exactly ``files`` (built aside, then renamed into place)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    target = out_dir / name
    staging = Path(tempfile.mkdtemp(prefix=f".{name}-", dir=out_dir))
    try:
        for relative, content in files.items():
            path = staging / relative
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(content)
        if target.exists():
            shutil.rmtree(target)
        staging.replace(target)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return target


def _chart_yaml(spec: rosspecs.RosPackageSpec, base_version: str) -> dict[str, Any]:
    return {
        "apiVersion": "v2",
        "name": spec.name,
        "description": spec.description,
        "type": "application",
        "version": spec.version,
        "appVersion": spec.app_version,
        "dependencies": [
            {
                "name": BASE_CHART_NAME,
                "version": base_version,
                "repository": spec.base.repository,
            }
        ],
        "annotations": {
            "simtest.dev/generated-by": "simtest package ros",
            "simtest.dev/base-chart": f"{BASE_CHART_NAME}-{base_version}",
        },
    }


def base_values(spec: rosspecs.RosPackageSpec, params: Mapping[str, str]) -> dict[str, Any]:
    """The base chart's values the spec stands for (before ``values`` is merged over them)."""
    # nameOverride: objects and the container are named after the application, not "k8s-ros".
    values: dict[str, Any] = {
        "nameOverride": spec.name,
        "kind": spec.kind,
        "image": _plain(spec.image),
    }
    if spec.entrypoint:
        values["command"] = list(spec.entrypoint)
    if spec.args:
        values["args"] = list(spec.args)
    for key, section in spec.sections.items():
        values[key] = _plain(section)
    if params:
        values["params"] = dict(params)
    return _merge(values, spec.values)


def _values_text(spec: rosspecs.RosPackageSpec, params: Mapping[str, str]) -> bytes:
    header = (
        f"# Values of {spec.name}, generated by `simtest package ros` from its package spec.\n"
        "# Everything under `k8s-ros:` goes to the K8s-ROS base chart (see its values.yaml);\n"
        "# a run-specific helmfile can override any of it per run.\n"
    )
    return header.encode("utf-8") + _dump({VALUES_KEY: base_values(spec, params)})


def _readme(spec: rosspecs.RosPackageSpec, base_version: str) -> str:
    return (
        f"# {spec.name}\n\n{spec.description}\n\n"
        f"Generated by `simtest package ros` on the K8s-ROS base chart {base_version}; "
        "regenerate rather than edit.\n\n"
        "```bash\n"
        f"helm template {spec.name} .                       # inspect\n"
        f"helm install {spec.name} . --set k8s-ros.ros.domainId=7\n"
        "```\n"
    )


def _chart_meta(files: Mapping[str, bytes]) -> dict[str, Any]:
    raw = files.get("Chart.yaml")
    meta = yaml.safe_load(raw) if raw else None
    if not isinstance(meta, dict) or meta.get("name") != BASE_CHART_NAME or "version" not in meta:
        raise RenderError(f"the base chart is not {BASE_CHART_NAME} (check its Chart.yaml)")
    return meta


def _params_text(path: Path, spec_path: Path) -> str:
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise RenderError(f"{spec_path}: cannot read params file {path}: {exc}") from exc
    if len(data) > MAX_PARAMS_BYTES:
        raise RenderError(f"{spec_path}: params file {path} exceeds {MAX_PARAMS_BYTES} bytes")
    try:
        text = data.decode("utf-8")
        parsed = yaml.safe_load(text)
    except (UnicodeDecodeError, yaml.YAMLError) as exc:
        raise RenderError(f"{spec_path}: params file {path} is not UTF-8 YAML: {exc}") from exc
    if not isinstance(parsed, dict) or not _has_ros_parameters(parsed):
        raise RenderError(
            f"{spec_path}: params file {path} is not a ROS 2 parameter file "
            "(expected `<node>: {ros__parameters: {...}}`)"
        )
    return text


def _has_ros_parameters(node: Any) -> bool:
    if not isinstance(node, dict):
        return False
    return "ros__parameters" in node or any(_has_ros_parameters(v) for v in node.values())


def _inside(root: Path, relative: PurePosixPath, spec_path: Path) -> Path:
    path = (root / relative).resolve()
    if path != root and root not in path.parents:
        raise RenderError(f"{spec_path}: {relative} resolves outside the spec's folder")
    return path


def _merge(base: Mapping[str, Any], override: Mapping[str, Any]) -> dict[str, Any]:
    """Helm-style: mappings merge recursively, everything else replaces, ``None`` deletes."""
    merged = {key: _plain(value) for key, value in base.items()}
    for key, value in override.items():
        if value is None:
            merged.pop(key, None)
        elif isinstance(value, Mapping) and isinstance(merged.get(key), Mapping):
            merged[key] = _merge(merged[key], value)
        else:
            merged[key] = _plain(value)
    return merged


def _plain(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


class _Dumper(yaml.SafeDumper):
    """Multi-line strings (parameter files) as literal blocks, so values.yaml stays readable."""


def _represent_str(dumper: yaml.SafeDumper, value: str) -> yaml.Node:
    style = "|" if "\n" in value else None
    return dumper.represent_scalar("tag:yaml.org,2002:str", value, style=style)


_Dumper.add_representer(str, _represent_str)


def _dump(value: Any) -> bytes:
    text = yaml.dump(
        value, Dumper=_Dumper, sort_keys=False, default_flow_style=False, allow_unicode=True,
        width=100,
    )  # fmt: skip
    return text.encode("utf-8")
