"""Rendering the HTML report: the view model through the package's jinja2 templates.

The page is one file with its CSS, JavaScript and SVG inline, so it can be archived as a CI
artifact and opened offline. Autoescaping is on; only the SVG markup built (and escaped) by
:mod:`.plots` is inserted raw.
"""

from __future__ import annotations

import urllib.parse
from pathlib import Path, PurePosixPath

import jinja2

from simtest_operator.errors import ResultsError
from simtest_operator.results import reportmodel

TEMPLATE = "report.html.j2"


def _environment() -> jinja2.Environment:
    environment = jinja2.Environment(
        loader=jinja2.PackageLoader("simtest_operator.results", "templates"),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
        trim_blocks=False,
        lstrip_blocks=False,
    )
    environment.filters["local_link"] = local_link
    environment.globals["anchor"] = reportmodel.anchor
    return environment


def local_link(uri: str) -> str:
    """An href for an artifact: relative paths stay relative to the report, absolute paths
    become ``file://`` URLs, web URLs stay; other schemes (``s3://``) get no link."""
    parsed = urllib.parse.urlparse(uri)
    if parsed.scheme in ("http", "https", "file"):
        return uri
    if parsed.scheme and len(parsed.scheme) > 1:
        return ""
    path = PurePosixPath(uri)
    if path.is_absolute():
        return "file://" + urllib.parse.quote(str(path))
    return urllib.parse.quote(str(path))


def render(report: reportmodel.Report, *, source: str = "") -> str:
    """The complete HTML document."""
    try:
        template = _environment().get_template(TEMPLATE)
        return template.render(report=report, source=source or "the results store")
    except jinja2.TemplateError as exc:
        raise ResultsError(f"cannot render the report: {exc}") from exc


def write(path: Path, document: str) -> Path:
    """Write the document atomically (a browser or CI upload never sees half a page)."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        partial = path.with_name(f".{path.name}.partial")
        partial.write_text(document, encoding="utf-8")
        partial.replace(path)
    except OSError as exc:
        raise ResultsError(f"cannot write the report {path}: {exc}") from exc
    return path
