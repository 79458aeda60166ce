"""The results UI's HTTP side: a standard-library WSGI app, jinja2 pages and their JSON twins.

``GET /<page>`` renders a page of :data:`views.PAGES`, ``GET /api/<page>`` returns the same
values as JSON, ``/static/ui.css`` and ``/static/replay.js`` the style and the replay script,
``/healthz`` answers probes. One read-only database connection serves the requests in turn
(:mod:`wsgiref`'s server handles one at a time), so nothing here needs locks. Errors become
one-line pages: 404 for unknown runs and scenarios, 400 for bad parameters, 503 when the
database cannot answer -- never a traceback.
"""

from __future__ import annotations

import datetime
import importlib.resources
import json
import math
import sys
import urllib.parse
from collections.abc import Callable, Iterable, Mapping
from typing import Any
from wsgiref.simple_server import WSGIRequestHandler, WSGIServer, make_server

import jinja2

from simtest_operator.errors import SimtestError
from simtest_operator.results import plots, reporting
from simtest_operator.results.querying import ReadOnlyDatabase
from simtest_operator.ui import queries, views

StartResponse = Callable[[str, list[tuple[str, str]]], Any]
STATIC_TYPES = {".css": "text/css; charset=utf-8", ".js": "text/javascript; charset=utf-8"}


def _pct(value: float) -> str:
    return f"{100 * value:.0f} %"


def _when(value: datetime.datetime | None) -> str:
    return f"{value:%Y-%m-%d %H:%M} UTC" if value else "—"


def _q(value: object) -> str:
    """A query-string value: every reserved character escaped (scenario ids hold ``/``)."""
    return urllib.parse.quote(str(value), safe="")


def _metric(value: float) -> str:
    if math.isnan(value):
        return "n/a"
    if math.isinf(value):
        return "∞" if value > 0 else "-∞"
    return f"{value:.4g}"


def environment() -> jinja2.Environment:
    """The pages' jinja2 environment (autoescaping on; SVG from :mod:`plots` is inserted raw)."""
    env = jinja2.Environment(
        loader=jinja2.PackageLoader("simtest_operator.ui", "templates"),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
    )
    env.filters.update(pct=_pct, when=_when, metric=_metric, q=_q,
                       local_link=reporting.local_link)  # fmt: skip
    env.globals.update(colours=plots.VERDICT_COLOURS, verdicts=queries.VERDICTS)
    return env


class App:
    """The WSGI application over one read-only database."""

    def __init__(self, db: ReadOnlyDatabase, context: views.Context | None = None) -> None:
        self.db = db
        self.context = context or views.Context()
        self.templates = environment()

    def __call__(
        self, environ: Mapping[str, Any], start_response: StartResponse
    ) -> Iterable[bytes]:
        path = str(environ.get("PATH_INFO", "/")).strip("/")
        query = urllib.parse.parse_qs(str(environ.get("QUERY_STRING", "")))
        params = {key: values[-1] for key, values in query.items()}
        if environ.get("REQUEST_METHOD", "GET") not in ("GET", "HEAD"):
            return _reply(start_response, "405 Method Not Allowed", "text/plain", b"GET only\n")
        if path == "healthz":
            return _reply(start_response, "200 OK", "text/plain", b"ok\n")
        if path.startswith("static/"):
            return self._static(path.removeprefix("static/"), start_response)
        api = path == "api" or path.startswith("api/")
        page = path.removeprefix("api").strip("/") if api else path
        if page not in views.PAGES:
            return self._error(start_response, "404 Not Found", f"no page /{path}", api)
        view, template = views.PAGES[page]
        try:
            values = view(self.db, params, self.context)
        except views.NotFoundError as exc:
            return self._error(start_response, "404 Not Found", str(exc), api)
        except (views.BadRequestError, ValueError) as exc:
            return self._error(start_response, "400 Bad Request", str(exc), api)
        except SimtestError as exc:
            return self._error(start_response, "503 Service Unavailable", str(exc), api)
        if api:
            payload = _finite(queries.as_json(_without_markup(values)))
            body = json.dumps(payload, allow_nan=False, default=str).encode()
            return _reply(start_response, "200 OK", "application/json", body)
        html = self.templates.get_template(template).render(
            current_page=page, params=params, where=self.db.where, **values
        )
        return _reply(start_response, "200 OK", "text/html; charset=utf-8", html.encode())

    def _static(self, name: str, start_response: StartResponse) -> Iterable[bytes]:
        suffix = name[name.rfind(".") :] if "." in name else ""
        # Kept beside the templates as ``*.j2`` (the package data the wheel already ships), served
        # as they are: nothing in them is rendered.
        resource = importlib.resources.files("simtest_operator.ui") / "templates" / f"{name}.j2"
        if "/" in name or suffix not in STATIC_TYPES or not resource.is_file():
            return _reply(start_response, "404 Not Found", "text/plain", b"not found\n")
        return _reply(start_response, "200 OK", STATIC_TYPES[suffix], resource.read_bytes())

    def _error(
        self, start_response: StartResponse, status: str, message: str, api: bool
    ) -> Iterable[bytes]:
        if api:
            body = json.dumps({"error": message}).encode()
            return _reply(start_response, status, "application/json", body)
        html = self.templates.get_template("error.html.j2").render(
            current_page="error", status=status, message=message, where=self.db.where
        )
        return _reply(start_response, status, "text/html; charset=utf-8", html.encode())


def _without_markup(values: Mapping[str, Any]) -> dict[str, Any]:
    """The API leaves out pre-rendered SVG (``*_svg``, charts); it returns the data behind it."""
    return {
        key: value
        for key, value in values.items()
        if not key.endswith(("_svg", "chart")) and key != "timelines"
    }


def _finite(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, list):
        return [_finite(v) for v in value]
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    return value


def _reply(start_response: StartResponse, status: str, kind: str, body: bytes) -> list[bytes]:
    start_response(status, [("Content-Type", kind), ("Content-Length", str(len(body))),
                            ("Cache-Control", "no-store")])  # fmt: skip
    return [body]


class _QuietHandler(WSGIRequestHandler):
    """One short line per request on stderr, not wsgiref's full access log format."""

    def log_message(self, format: str, *args: Any) -> None:
        sys.stderr.write(f"simtest ui: {format % args}\n")


def make(app: App, *, host: str = "127.0.0.1", port: int = 8080) -> WSGIServer:
    """A server bound to ``host:port`` (``port`` 0 picks a free one); call ``serve_forever``."""
    return make_server(host, port, app, handler_class=_QuietHandler)
