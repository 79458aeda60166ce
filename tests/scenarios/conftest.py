"""Fixtures for source tests: a real local HTTP server, scenario files, a fetch context."""

from __future__ import annotations

import contextlib
import http.server
import json
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from simtest_operator.scenarios import FetchContext
from tests.scenarios.support import Routes


@pytest.fixture
def server() -> Iterator[tuple[str, Routes]]:
    """A threaded HTTP server on 127.0.0.1 with programmable routes; yields (base URL, routes)."""
    with _serving() as served:
        yield served


@pytest.fixture
def other_server() -> Iterator[tuple[str, Routes]]:
    """A second server like ``server`` on another port: another origin."""
    with _serving() as served:
        yield served


@contextlib.contextmanager
def _serving() -> Iterator[tuple[str, Routes]]:
    routes = Routes()

    class Handler(http.server.BaseHTTPRequestHandler):
        def log_message(self, format: str, *args: object) -> None:
            del format, args

        def do_GET(self) -> None:
            routes.requests.append(("GET", self.path, dict(self.headers)))
            status, body, headers = routes.get.get(self.path, (404, b"not found", {}))
            self.send_response(status)
            for key, value in headers.items():
                if value != "omit":
                    self.send_header(key, value)
            if "Content-Length" not in headers:
                self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def do_POST(self) -> None:
            length = int(self.headers.get("Content-Length", "0"))
            payload = json.loads(self.rfile.read(length))
            routes.requests.append(("POST", self.path, dict(self.headers)))
            assert routes.post is not None
            status, body = routes.post(self.path, dict(self.headers), payload)
            self.send_response(status)
            self.send_header("Content-Length", str(len(body)))
            self.send_header("Content-Type", "application/json")
            self.end_headers()
            self.wfile.write(body)

    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=httpd.serve_forever, args=(0.05,), daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}", routes
    finally:
        httpd.shutdown()
        httpd.server_close()
        thread.join(timeout=5)


@pytest.fixture
def ctx(tmp_path: Path) -> FetchContext:
    """A fetch context with the manifest folder and cache in the test's temp folder."""
    base = tmp_path / "manifest"
    base.mkdir()
    return FetchContext(base_dir=base, cache_dir=tmp_path / "cache")
