"""Uploading artifacts to an S3-compatible server (moto's real HTTP server, boto3 unpatched).

Covers: ``s3://`` URI parsing and key layout; an upload landing under the prefix with its bytes;
the size bound refusing a file before any request; an outage retried with backoff until the
server is back; a missing bucket failing at once (no retry); retries given up when the time budget
is spent; credentials kept out of reprs.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.errors import ResultsError
from simtest_operator.results import uploading
from tests.results.s3server import BUCKET, S3Server, free_port, s3

__all__ = ["s3"]  # the fixture, used by name

LOCATION = uploading.S3Location.parse(f"s3://{BUCKET}/runs/nightly/e0")


def _file(tmp_path: Path, size: int = 100) -> Path:
    path = tmp_path / "recording.mcap"
    path.write_bytes(bytes(range(256)) * (size // 256) + b"x" * (size % 256))
    return path


def test_locations_parse_and_lay_out_keys() -> None:
    assert uploading.S3Location(bucket=BUCKET, prefix="runs/nightly/e0") == LOCATION
    assert LOCATION.uri("a.xosc/run.log") == f"s3://{BUCKET}/runs/nightly/e0/a.xosc/run.log"
    credentials = uploading.S3Credentials(
        endpoint="http://x", access_key_id="id", secret_access_key="very-secret-value"
    )
    assert "very-secret-value" not in repr(credentials)
    bare = uploading.S3Location.parse("s3://bucket")
    assert bare.key("/x/y") == "x/y"
    for bad in ("pvc://claim/x", "s3:///nobucket"):
        with pytest.raises(ResultsError):
            uploading.S3Location.parse(bad)


def test_an_upload_lands_under_the_prefix(tmp_path: Path, s3: S3Server) -> None:
    path = _file(tmp_path, 5000)
    uploader = uploading.Uploader(LOCATION, s3.credentials())
    uri = uploader.upload(path, "a.xosc/recording.mcap")
    assert uri == f"s3://{BUCKET}/runs/nightly/e0/a.xosc/recording.mcap"
    assert s3.read("runs/nightly/e0/a.xosc/recording.mcap") == path.read_bytes()


def test_a_file_above_the_limit_is_refused_before_any_request(tmp_path: Path) -> None:
    dead = uploading.S3Credentials(
        endpoint=f"http://127.0.0.1:{free_port()}", access_key_id="k", secret_access_key="s"
    )
    uploader = uploading.Uploader(
        LOCATION, dead, policy=uploading.UploadPolicy(max_object_bytes=1000)
    )
    with pytest.raises(ResultsError, match="1001 bytes exceeds the 1000 bytes upload limit"):
        uploader.upload(_file(tmp_path, 1001), "a/recording.mcap")


def test_an_outage_is_retried_with_backoff(tmp_path: Path) -> None:
    server = S3Server(port=free_port())
    pauses: list[float] = []

    def sleep(seconds: float) -> None:  # the server comes back while the uploader waits
        pauses.append(seconds)
        if len(pauses) == 2:
            server.start()
            server.client().create_bucket(Bucket=BUCKET)

    uploader = uploading.Uploader(
        LOCATION,
        server.credentials(),
        policy=uploading.UploadPolicy(attempts=4, connect_timeout_seconds=1.0),
        sleep=sleep,
    )
    try:
        uri = uploader.upload(_file(tmp_path), "a/recording.mcap")
        assert uri.endswith("a/recording.mcap")
        assert pauses == [0.5, 1.0]
        assert server.keys() == ["runs/nightly/e0/a/recording.mcap"]
    finally:
        server.stop()


def test_an_outage_that_lasts_gives_up(tmp_path: Path) -> None:
    server = S3Server(port=free_port())
    pauses: list[float] = []
    uploader = uploading.Uploader(
        LOCATION,
        server.credentials(),
        policy=uploading.UploadPolicy(attempts=3, connect_timeout_seconds=1.0),
        sleep=pauses.append,
    )
    with pytest.raises(ResultsError, match="not uploaded after 3 attempts"):
        uploader.upload(_file(tmp_path), "a/recording.mcap")
    assert pauses == [0.5, 1.0]


def test_a_missing_bucket_is_not_retried(tmp_path: Path, s3: S3Server) -> None:
    pauses: list[float] = []
    location = uploading.S3Location.parse("s3://no-such-bucket/x")
    uploader = uploading.Uploader(location, s3.credentials(), sleep=pauses.append)
    with pytest.raises(ResultsError, match="HTTP 404 NoSuchBucket"):
        uploader.upload(_file(tmp_path), "a/recording.mcap")
    assert pauses == []


def test_no_retry_without_time_left(tmp_path: Path) -> None:
    server = S3Server(port=free_port())
    left = iter([30.0, 4.0])
    pauses: list[float] = []
    uploader = uploading.Uploader(
        LOCATION,
        server.credentials(),
        policy=uploading.UploadPolicy(connect_timeout_seconds=1.0),
        sleep=pauses.append,
        remaining=lambda: next(left),
    )
    with pytest.raises(ResultsError, match="no time left before the pod's deadline"):
        uploader.upload(_file(tmp_path), "a/recording.mcap")
    assert pauses == []
