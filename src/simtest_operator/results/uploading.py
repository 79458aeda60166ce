"""Artifact storage in an S3-compatible bucket: where a simulator pod's files outlive the pod.

A pod on an ``emptyDir`` loses its recording, log and result file when it is deleted, so with
``spec.artifacts.s3`` the runner uploads them and reports ``s3://bucket/key`` URIs. The one client
is boto3 (the field's standard; MinIO, Ceph RGW and AWS all speak it), built from explicit
values -- endpoint and credentials come from the pod's environment, read once by the runner's
entry point -- never from ambient configuration files.

Uploads are bounded: a file above :attr:`UploadPolicy.max_object_bytes` is refused, each upload is
tried a few times with exponential backoff, and no attempt starts when the caller's time budget
(the pod's deadline) cannot cover it. Every failure is a :class:`ResultsError` naming the file and
the cause; the caller keeps the local path and says so in the reason. Credentials never appear in
a message.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from simtest_operator import redaction
from simtest_operator.errors import ResultsError

SCHEME = "s3://"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class S3Location:
    """A bucket and a key prefix, parsed from ``s3://bucket/prefix``."""

    bucket: str
    prefix: str = ""

    @classmethod
    def parse(cls, uri: str) -> S3Location:
        """Parse an ``s3://`` URI; anything else is a :class:`ResultsError`."""
        if not uri.startswith(SCHEME):
            raise ResultsError(f"not an s3:// URI: {uri!r}")
        parts = urlsplit(uri)
        if not parts.netloc:
            raise ResultsError(f"no bucket in {uri!r}")
        return cls(bucket=parts.netloc, prefix=parts.path.strip("/"))

    def key(self, relative: str) -> str:
        """The object key of ``relative`` below the prefix."""
        relative = relative.strip("/")
        return f"{self.prefix}/{relative}" if self.prefix else relative

    def uri(self, relative: str) -> str:
        """``s3://bucket/<prefix>/<relative>``."""
        return f"{SCHEME}{self.bucket}/{self.key(relative)}"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class S3Credentials:
    """Endpoint and keys (from the Secret ``spec.artifacts.s3.secretRef``, via the pod's env)."""

    endpoint: str
    access_key_id: str = dataclasses.field(repr=False)
    secret_access_key: str = dataclasses.field(repr=False)
    session_token: str = dataclasses.field(default="", repr=False)
    region: str = "us-east-1"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class UploadPolicy:
    """Limits of one upload."""

    max_object_bytes: int = 1 << 30
    """Largest file uploaded (1 GiB): a runaway recording must not stall the pod."""
    attempts: int = 3
    """Tries per file; connection errors and 5xx replies are retried, 4xx are not."""
    first_backoff_seconds: float = 0.5
    """Pause after the first failed try; doubles after each further one."""
    connect_timeout_seconds: float = 5.0
    read_timeout_seconds: float = 20.0
    min_budget_seconds: float = 5.0
    """An upload (or a retry) is not started with less time than this left in the budget."""


class Uploader:
    """Uploads files below one :class:`S3Location`."""

    def __init__(
        self,
        location: S3Location,
        credentials: S3Credentials,
        *,
        policy: UploadPolicy = UploadPolicy(),
        sleep: Callable[[float], None] = time.sleep,
        remaining: Callable[[], float] | None = None,
    ) -> None:
        """``remaining`` returns the seconds left in the caller's budget (None: unlimited)."""
        self.location = location
        self.policy = policy
        self._credentials = credentials
        self._secrets = redaction.Secrets.of(
            credentials.secret_access_key, credentials.session_token
        )
        self._sleep = sleep
        self._remaining = remaining
        self._client: Any = None

    def upload(self, path: Path, relative: str) -> str:
        """Upload ``path`` as ``relative`` below the location; returns its ``s3://`` URI."""
        policy = self.policy
        try:
            size = path.stat().st_size
        except OSError as exc:
            raise ResultsError(f"cannot upload {path.name}: {exc.strerror or exc}") from exc
        if size > policy.max_object_bytes:
            raise ResultsError(
                f"{path.name} not uploaded: {_size(size)} exceeds the "
                f"{_size(policy.max_object_bytes)} upload limit"
            )
        key = self.location.key(relative)
        delay = policy.first_backoff_seconds
        problem = "no attempt made"
        for attempt in range(1, policy.attempts + 1):
            if not self._time_left(delay if attempt > 1 else 0.0):
                raise ResultsError(
                    f"{path.name} not uploaded: no time left before the pod's deadline ({problem})"
                )
            if attempt > 1:
                self._sleep(delay)
                delay *= 2
            try:
                self._put(path, key)
            except _PermanentError as exc:
                raise ResultsError(f"{path.name} not uploaded: {exc}") from None
            except _TransientError as exc:
                problem = str(exc)
                continue
            return self.location.uri(relative)
        raise ResultsError(f"{path.name} not uploaded after {policy.attempts} attempts: {problem}")

    def _time_left(self, pause: float) -> bool:
        if self._remaining is None:
            return True
        return self._remaining() - pause >= self.policy.min_budget_seconds

    def _put(self, path: Path, key: str) -> None:
        import botocore.exceptions

        client = self._client or self._connect()
        # The server's message may quote the request (the session token travels in a header).
        with self._secrets.masking():
            try:
                with path.open("rb") as body:
                    client.put_object(Bucket=self.location.bucket, Key=key, Body=body)
            except botocore.exceptions.ClientError as exc:
                error = exc.response.get("Error", {})
                status = int(exc.response.get("ResponseMetadata", {}).get("HTTPStatusCode", 0))
                text = f"{error.get('Code', 'error')} {error.get('Message', '')}".strip()
                if status >= 500 or status in (408, 429):
                    raise _TransientError(f"HTTP {status} {text}") from None
                bucket = self.location.bucket
                raise _PermanentError(f"HTTP {status} {text} (bucket {bucket!r})") from None
            except (botocore.exceptions.BotoCoreError, OSError) as exc:
                raise _TransientError(f"{type(exc).__name__}: {exc}") from None

    def _connect(self) -> Any:
        import boto3
        import botocore.config

        credentials = self._credentials
        session = boto3.session.Session(
            aws_access_key_id=credentials.access_key_id,
            aws_secret_access_key=credentials.secret_access_key,
            aws_session_token=credentials.session_token or None,
            region_name=credentials.region,
        )
        self._client = session.client(
            "s3",
            endpoint_url=credentials.endpoint,
            config=botocore.config.Config(
                connect_timeout=self.policy.connect_timeout_seconds,
                read_timeout=self.policy.read_timeout_seconds,
                retries={"total_max_attempts": 1},  # retried here, within the time budget
                s3={"addressing_style": "path"},
            ),
        )
        return self._client


def _size(count: int) -> str:
    return f"{count / 2**20:.1f} MiB" if count >= 2**20 else f"{count} bytes"


class _TransientError(ResultsError):
    """Worth another try (connection trouble, 5xx, throttling)."""


class _PermanentError(ResultsError):
    """Retrying cannot help (403 credentials, 404 bucket, 400 request)."""
