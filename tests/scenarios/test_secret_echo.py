"""Servers that quote a credential back in their answer (issue 29): the secret never shows.

Covers: ``simtest run`` over a GraphQL database whose error echoes the request's Authorization
header exits 2 with the error and the token masked, and no file written anywhere holds the token;
a REST database that names an item by the header; an S3-compatible server whose error quotes the
session token of the upload.
"""

from __future__ import annotations

import http.server
import json
import threading
import urllib.parse
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from simtest_operator.cli.main import cli
from simtest_operator.errors import ResultsError, SourceError
from simtest_operator.redaction import MASK
from simtest_operator.results import uploading
from simtest_operator.scenarios import FetchContext, RestSource, SecretRef, gitfetching, resolve
from tests.scenarios.support import Routes

pytestmark = pytest.mark.timeout(120)

TOKEN = "tok_5e3b9a71"


def files_holding(root: Path, secret: str) -> list[Path]:
    return [p for p in root.rglob("*") if p.is_file() and secret.encode() in p.read_bytes()]


def test_simtest_run_masks_a_token_the_graphql_server_echoes(
    tmp_path: Path, server: tuple[str, Routes]
) -> None:
    base, routes = server

    def deny(path: str, headers: dict[str, str], payload: Any) -> tuple[int, bytes]:
        message = f"denied for {headers.get('Authorization')}\n(check the token)"
        return 200, json.dumps({"errors": [{"message": message}]}).encode()

    routes.post = deny
    manifest = tmp_path / "campaign.yaml"
    manifest.write_text(f"""apiVersion: simtest.dev/v1alpha1
kind: TestCampaign
metadata:
  name: echo
spec:
  scenarios:
    sources:
      - graphql:
          endpoint: "{base}/graphql"
          query: "{{ scenarios {{ id content }} }}"
          secretRef: {{name: scenario-db, key: token}}
""")
    env = {"SIMTEST_CACHE_DIR": str(tmp_path / "cache"), "SIMTEST_SECRET_SCENARIO_DB_TOKEN": TOKEN}
    args = ["run", str(manifest), "-o", str(tmp_path / "out"), "--engine", "fake", "--plain"]
    result = CliRunner().invoke(cli, args, env=env)
    assert result.exit_code == 2, result.output
    assert routes.requests[-1][2]["Authorization"] == f"Bearer {TOKEN}", "the token was sent"
    assert f"query failed: denied for Bearer {MASK} (check the token)" in result.output
    assert TOKEN not in result.output
    assert files_holding(tmp_path, TOKEN) == []


def test_a_rest_item_named_by_the_token_is_masked(
    tmp_path: Path, server: tuple[str, Routes]
) -> None:
    base, routes = server
    routes.get["/api"] = (200, json.dumps([{"id": f"Bearer {TOKEN}"}]).encode(), {})
    ctx = FetchContext(base_dir=tmp_path, cache_dir=tmp_path / "cache", secrets=lambda r: TOKEN)
    source = RestSource(url=f"{base}/api", secret=SecretRef(name="db", key="token"))
    with pytest.raises(SourceError) as caught:
        resolve(source, ctx)
    assert str(caught.value) == (
        f"{base}/api: item 0 (Bearer {MASK}) must have exactly one of 'url' or 'content'"
    )


@pytest.fixture
def echoing_s3() -> Iterator[str]:
    """An S3-compatible endpoint that refuses every request, quoting its security token."""

    class Handler(http.server.BaseHTTPRequestHandler):
        def log_message(self, format: str, *args: object) -> None:
            del format, args

        def do_PUT(self) -> None:
            length = int(self.headers.get("Content-Length", "0"))
            self.rfile.read(length)
            token = self.headers.get("X-Amz-Security-Token", "")
            body = (
                "<?xml version='1.0'?><Error><Code>AccessDenied</Code>"
                f"<Message>token {token} is not allowed</Message></Error>"
            ).encode()
            self.send_response(403)
            self.send_header("Content-Type", "application/xml")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=httpd.serve_forever, args=(0.05,), daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}"
    finally:
        httpd.shutdown()
        httpd.server_close()
        thread.join(timeout=5)


def test_an_s3_error_quoting_the_session_token_is_masked(tmp_path: Path, echoing_s3: str) -> None:
    credentials = uploading.S3Credentials(
        endpoint=echoing_s3, access_key_id="key", secret_access_key="s3cr3t", session_token=TOKEN
    )
    location = uploading.S3Location.parse("s3://bucket/runs")
    uploader = uploading.Uploader(location, credentials, sleep=lambda seconds: None)
    recording = tmp_path / "recording.mcap"
    recording.write_bytes(b"x" * 10)
    with pytest.raises(ResultsError) as caught:
        uploader.upload(recording, "a/recording.mcap")
    assert f"HTTP 403 AccessDenied token {MASK} is not allowed" in str(caught.value)
    assert TOKEN not in str(caught.value)


@pytest.mark.parametrize(
    ("url", "shown"),
    [
        ("https://user:p%40ss@example.org/r.git", f"https://user:{MASK}@example.org/r.git"),
        ("https://ghp_tok3n@example.org:8443/r.git", f"https://{MASK}@example.org:8443/r.git"),
        ("ssh://git@example.org/r.git", "ssh://git@example.org/r.git"),
        ("https://example.org/r.git", "https://example.org/r.git"),
    ],
)
def test_git_urls_are_shown_without_their_secret(url: str, shown: str) -> None:
    assert gitfetching.redact(url) == shown
    # git quotes a URL back decoded or re-encoded: the secret alone is masked too.
    secret = url.partition("//")[2].partition("@")[0].rpartition(":")[2]
    if shown != url:
        assert gitfetching.url_secrets(url).redact(f"fatal: {urllib.parse.unquote(secret)}") == (
            f"fatal: {MASK}"
        )
