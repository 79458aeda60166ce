"""Redirects of source downloads: credentials stay with their origin, loops are one line.

Covers (issue 29): a scenario database's bearer token is not sent to another origin a
redirect leads to (another port of 127.0.0.1 is another origin, as another host is), but still is
after a redirect within the same origin; a redirect loop and a chain longer than the limit are
one-line SourceErrors (urllib's was three lines ending in the reason phrase ``Found``), and so
is a malformed answer (http.client's errors were a traceback).
"""

from __future__ import annotations

import contextlib
import json
import socket
import threading
from pathlib import Path

import pytest

from simtest_operator.errors import SourceError
from simtest_operator.scenarios import (
    FetchContext,
    HttpSource,
    RestSource,
    SecretRef,
    resolve,
)
from simtest_operator.scenarios.downloading import MAX_REDIRECTS, origin
from tests.scenarios.support import Routes, xosc

TOKEN = "tok_2f9c1e"
REF = SecretRef(name="db", key="token")


def items_route(routes: Routes, path: str) -> None:
    body = json.dumps([{"id": "a", "content": xosc()}]).encode()
    routes.get[path] = (200, body, {"Content-Type": "application/json"})


def with_token(tmp_path: Path) -> FetchContext:
    return FetchContext(base_dir=tmp_path, cache_dir=tmp_path / "cache", secrets=lambda r: TOKEN)


def test_the_token_never_follows_a_redirect_to_another_origin(
    tmp_path: Path, server: tuple[str, Routes], other_server: tuple[str, Routes]
) -> None:
    base, routes = server
    other, elsewhere = other_server
    items_route(elsewhere, "/api")
    routes.get["/moved"] = (302, b"", {"Location": f"{other}/api"})
    resolve(RestSource(url=f"{base}/moved", secret=REF), with_token(tmp_path))
    assert routes.requests[-1][2]["Authorization"] == f"Bearer {TOKEN}"
    (method, path, headers) = elsewhere.requests[-1]
    assert (method, path) == ("GET", "/api")
    assert "Authorization" not in headers and TOKEN not in json.dumps(headers)


def test_the_token_follows_a_redirect_within_its_origin(
    tmp_path: Path, server: tuple[str, Routes]
) -> None:
    base, routes = server
    items_route(routes, "/api/v2")
    routes.get["/api"] = (301, b"", {"Location": "/api/v2"})
    resolve(RestSource(url=f"{base}/api", secret=REF), with_token(tmp_path))
    assert [r[1] for r in routes.requests] == ["/api", "/api/v2"]
    assert routes.requests[-1][2]["Authorization"] == f"Bearer {TOKEN}"


def test_origin_is_scheme_host_and_port() -> None:
    assert origin("https://Example.org/a") == origin("https://example.org:443/b")
    assert origin("http://example.org/") != origin("https://example.org/")
    assert origin("http://127.0.0.1:8080/") != origin("http://127.0.0.1:8081/")
    assert origin("http://example.org/") != origin("http://example.org.evil/")


@pytest.mark.parametrize(
    ("routes_given", "message"),
    [
        ({"/loop": "/loop"}, "redirect loop (HTTP 302 back to http://"),
        ({"/loop": "/b", "/b": "/c", "/c": "/b"}, "redirect loop"),
        (
            {"/loop": "/r1", **{f"/r{i}": f"/r{i + 1}" for i in range(1, MAX_REDIRECTS + 2)}},
            f"more than {MAX_REDIRECTS} redirects",
        ),
    ],
    ids=["self", "cycle", "chain"],
)
def test_redirect_loops_and_long_chains_are_one_line(
    tmp_path: Path, server: tuple[str, Routes], routes_given: dict[str, str], message: str
) -> None:
    base, routes = server
    for path, target in routes_given.items():
        routes.get[path] = (302, b"", {"Location": target})
    ctx = FetchContext(base_dir=tmp_path, cache_dir=tmp_path / "cache")
    with pytest.raises(SourceError) as caught:
        resolve(HttpSource(url=f"{base}/loop"), ctx)
    text = str(caught.value)
    assert text.startswith(f"{base}/loop: ") and message in text
    assert "\n" not in text and not text.endswith("Found")
    assert len(routes.requests) <= MAX_REDIRECTS + 1


def test_a_malformed_status_line_is_one_line(tmp_path: Path) -> None:
    """http.client's own errors (here BadStatusLine) were not caught: a traceback."""
    with socket.create_server(("127.0.0.1", 0)) as listener:
        listener.settimeout(10)

        def answer() -> None:
            with contextlib.suppress(OSError):
                connection, _ = listener.accept()
                with connection:
                    connection.recv(65536)
                    connection.sendall(b"HTTP/1.1 abc\r\n\r\n")

        thread = threading.Thread(target=answer, daemon=True)
        thread.start()
        url = f"http://127.0.0.1:{listener.getsockname()[1]}/a.xosc"
        ctx = FetchContext(base_dir=tmp_path, cache_dir=tmp_path / "cache")
        with pytest.raises(SourceError) as caught:
            resolve(HttpSource(url=url), ctx)
        thread.join(timeout=10)
    assert str(caught.value).startswith(f"{url}: transfer failed (")
    assert "\n" not in str(caught.value)
