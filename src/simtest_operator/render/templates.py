"""Environment templates: folders of jinja2 files under ``helm-templates/``.

A template folder holds ``values.yaml.j2`` (the per-scenario Helm values of every release),
``pod.yaml.j2`` (the simulator pod of the direct provisioner) and optionally ``helmfile.yaml.j2``
(the run-specific helmfile). Templates are trusted (they ship with the operator); everything that
comes from a custom resource enters them as data through the ``json``/``toyaml`` filters, never
as template source, so a manifest cannot inject markup. Filters: ``json``, ``toyaml``, ``merge``
(Helm-style deep merge), ``release`` (``env.name | release("sut")``: a Helm release name of at
most 53 characters) and ``required`` (``x | required("what to set")``: a RenderError saying so
when ``x`` is missing or empty). A folder may include files of another
(``{% include "default/..." %}``).
"""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path
from typing import Any

import jinja2

from simtest_operator.errors import RenderError
from simtest_operator.render import documents, naming

VALUES_FILE = "values.yaml.j2"
POD_FILE = "pod.yaml.j2"
HELMFILE_FILE = "helmfile.yaml.j2"
_NAME = re.compile(r"^[a-z0-9]([-a-z0-9]*[a-z0-9])?$")


def _defined(value: Any) -> Any:
    if isinstance(value, jinja2.Undefined):
        value._fail_with_undefined_error()  # raises UndefinedError naming the missing value
    return value


def _json_filter(value: Any) -> str:
    return json.dumps(_defined(value), sort_keys=True, ensure_ascii=False)


def _yaml_filter(value: Any) -> str:
    return documents.to_yaml(_defined(value)).rstrip("\n")


def _required(value: Any, message: str) -> Any:
    """Helm's ``required``: the value, or a RenderError with ``message`` when it is missing or
    empty, so a template states what a campaign must set instead of failing on an attribute."""
    if isinstance(value, jinja2.Undefined) or value is None or value in ("", [], {}):
        raise RenderError(message)
    return value


@dataclasses.dataclass(frozen=True, slots=True)
class TemplateSet:
    """The compiled files of one template folder."""

    name: str
    values: jinja2.Template
    pod: jinja2.Template
    helmfile: jinja2.Template | None


class TemplateLibrary:
    """All template folders below one root; compiled templates are cached per library."""

    __slots__ = ("_cache", "_env", "root")

    def __init__(self, root: Path) -> None:
        self.root = root
        self._env = jinja2.Environment(
            loader=jinja2.FileSystemLoader(str(root)),
            undefined=jinja2.StrictUndefined,
            autoescape=False,
            keep_trailing_newline=True,
            trim_blocks=True,
            lstrip_blocks=True,
        )
        self._env.filters["json"] = _json_filter
        self._env.filters["toyaml"] = _yaml_filter
        self._env.filters["merge"] = documents.deep_merge
        self._env.filters["release"] = naming.release_name
        self._env.filters["required"] = _required
        self._cache: dict[str, TemplateSet] = {}

    def names(self) -> tuple[str, ...]:
        """Template folders available (those with a values template)."""
        if not self.root.is_dir():
            return ()
        return tuple(sorted(p.name for p in self.root.iterdir() if (p / VALUES_FILE).is_file()))

    def load(self, name: str) -> TemplateSet:
        """Compile (once) and return the template folder ``name``."""
        cached = self._cache.get(name)
        if cached is not None:
            return cached
        if not _NAME.match(name):
            raise RenderError(f"template name {name!r} must be a DNS label (a folder name)")
        folder = self.root / name
        if not (folder / VALUES_FILE).is_file() or not (folder / POD_FILE).is_file():
            known = ", ".join(self.names()) or "none"
            raise RenderError(
                f"environment template {name!r} not found under {self.root} "
                f"(needs {VALUES_FILE} and {POD_FILE}; available: {known})"
            )
        try:
            helmfile = (
                self._env.get_template(f"{name}/{HELMFILE_FILE}")
                if (folder / HELMFILE_FILE).is_file()
                else None
            )
            loaded = TemplateSet(
                name=name,
                values=self._env.get_template(f"{name}/{VALUES_FILE}"),
                pod=self._env.get_template(f"{name}/{POD_FILE}"),
                helmfile=helmfile,
            )
        except jinja2.TemplateError as exc:
            raise RenderError(f"environment template {name!r} does not compile: {exc}") from exc
        self._cache[name] = loaded
        return loaded
