"""A real S3-compatible server for tests: moto's standalone server on a free loopback port.

moto's ``ThreadedMotoServer`` serves the S3 REST API over HTTP (signatures, buckets, objects,
error replies), so the uploader talks to it exactly as to MinIO or AWS -- nothing in boto3 is
patched. Each server starts empty; :func:`s3` yields one with a bucket ``artifacts``.
"""

from __future__ import annotations

import dataclasses
import socket
import urllib.request
from collections.abc import Iterator
from typing import Any

import pytest

from simtest_operator.results import uploading

BUCKET = "artifacts"
CREDENTIALS = {"access_key_id": "test-key", "secret_access_key": "test-secret"}


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@dataclasses.dataclass(slots=True)
class S3Server:
    """A moto server that can be started late and stopped early (outage tests)."""

    port: int
    _server: Any = None

    @property
    def endpoint(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def start(self) -> None:
        from moto.server import ThreadedMotoServer

        self._server = ThreadedMotoServer(ip_address="127.0.0.1", port=self.port, verbose=False)
        self._server.start()
        # moto keeps its buckets per process, not per server: start every server empty.
        reset = urllib.request.Request(f"{self.endpoint}/moto-api/reset", method="POST")
        with urllib.request.urlopen(reset, timeout=10):
            pass

    def stop(self) -> None:
        if self._server is not None:
            self._server.stop()
            self._server = None

    def credentials(self) -> uploading.S3Credentials:
        return uploading.S3Credentials(endpoint=self.endpoint, **CREDENTIALS)

    def client(self) -> Any:
        import boto3

        return boto3.client(
            "s3",
            endpoint_url=self.endpoint,
            aws_access_key_id=CREDENTIALS["access_key_id"],
            aws_secret_access_key=CREDENTIALS["secret_access_key"],
            region_name="us-east-1",
        )

    def read(self, key: str, bucket: str = BUCKET) -> bytes:
        body: bytes = self.client().get_object(Bucket=bucket, Key=key)["Body"].read()
        return body

    def keys(self, bucket: str = BUCKET) -> list[str]:
        listing = self.client().list_objects_v2(Bucket=bucket)
        return sorted(item["Key"] for item in listing.get("Contents", ()))


@pytest.fixture
def s3() -> Iterator[S3Server]:
    """A running server with an empty bucket ``artifacts``."""
    server = S3Server(port=free_port())
    server.start()
    try:
        server.client().create_bucket(Bucket=BUCKET)
        yield server
    finally:
        server.stop()
