"""The results UI's HTTP side: a WSGI app of jinja2 pages and their JSON twins, served by waitress.

``GET /<page>`` renders a page of :data:`views.PAGES`, ``GET /api/<page>`` returns the same
values as JSON, ``/static/ui.css`` and ``/static/replay.js`` the style and the replay script,
``/healthz`` answers probes. Errors become one-line pages: 404 for unknown runs and scenarios,
400 for bad parameters, 503 when the database cannot answer -- never a traceback.

:class:`Server` serves the app with `waitress <https://docs.pylons.org/projects/waitress/>`_:
the standard library's ``wsgiref`` answered one request at a time, so one client keeping a
half-sent request open stopped every page and ``/healthz`` (issue 29) -- in a pod behind a
Service, an outage. waitress reads requests on one event loop and hands only complete ones to a
few threads, closes idle connections and bounds headers and bodies (:class:`ServerLimits`). The
threads share the one read-only database connection, which serialises its queries.
"""

from __future__ import annotations

import dataclasses
import datetime
import importlib.resources
import json
import math
import socket
import sys
import urllib.parse
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import jinja2
from waitress.server import create_server

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


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ServerLimits:
    """What the UI's server allows a client (waitress's adjustments of the same names)."""

    threads: int = 4
    """Requests rendered at once; a slow client never holds one (requests are read first)."""
    channel_timeout: int = 30
    """Seconds a connection may stay idle, a half-sent request included, before it is closed
    (waitress: 120; a page takes well under a second)."""
    cleanup_interval: int = 5
    """Seconds between the checks for idle connections."""
    connection_limit: int = 100
    """Connections open at once; more wait in the listen backlog."""
    max_request_header_size: int = 64 * 1024
    """Bytes of request line and headers (waitress: 256 KiB; the UI's URLs are short)."""
    max_request_body_size: int = 64 * 1024
    """Bytes of a request body: the UI answers GET and HEAD only (waitress: 1 GiB)."""


class Server:
    """``app`` served on ``host:port`` (``port`` 0 picks a free one): listening once made;
    :meth:`run` serves until interrupted, :meth:`close` releases the socket."""

    def __init__(
        self, app: App, *, host: str, port: int, limits: ServerLimits = ServerLimits()
    ) -> None:
        # Bound here, not by waitress, so a busy port is an OSError before any thread starts.
        family, _, _, _, address = socket.getaddrinfo(
            host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE
        )[0]
        listener = socket.socket(family, socket.SOCK_STREAM)
        try:
            listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            listener.bind(address)
            self._server = create_server(
                _logged(app), sockets=[listener], ident="simtest-ui", **dataclasses.asdict(limits)
            )
        except BaseException:
            listener.close()
            raise
        self.port: int = listener.getsockname()[1]

    def run(self) -> None:
        """Serve until SIGINT (waitress stops its loop on KeyboardInterrupt)."""
        self._server.run()

    def close(self) -> None:
        """Stop listening and end the worker threads."""
        self._server.close()


def _logged(app: App) -> Callable[[Mapping[str, Any], StartResponse], Iterable[bytes]]:
    """One short line per request on stderr (waitress writes no access log)."""

    def logged(environ: Mapping[str, Any], start_response: StartResponse) -> Iterable[bytes]:
        def start(status: str, headers: list[tuple[str, str]]) -> Any:
            line = f"{environ.get('REQUEST_METHOD')} {environ.get('REQUEST_URI', '')} {status}"
            printable = "".join(c if c.isprintable() else f"\\x{ord(c):02x}" for c in line)
            sys.stderr.write(f"simtest ui: {printable}\n")
            return start_response(status, headers)

        return app(environ, start)

    return logged
