"""Fetching stored artifacts back: a run's artifact URI -> a local file to read.

Runs store their artifacts as paths relative to the output folder (``simtest run``), absolute
paths, ``file://`` URIs, ``s3://bucket/key`` (a cluster with ``spec.artifacts.s3``) or
``pvc://claim/path`` (a cluster volume, readable here only when mounted: ``pvc_root``). S3
objects are downloaded with boto3 into a scratch folder; the endpoint and keys come from the
usual AWS environment (``AWS_ENDPOINT_URL_S3`` / ``AWS_ENDPOINT_URL``, ``AWS_ACCESS_KEY_ID``,
``AWS_SECRET_ACCESS_KEY``), as for the runner's uploads; path-style addressing for MinIO/Ceph.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any
from urllib.parse import unquote, urlsplit

from simtest_operator.errors import ResultsError
from simtest_operator.results.uploading import SCHEME as S3_SCHEME
from simtest_operator.results.uploading import S3Location


class Fetcher:
    """Resolves artifact URIs to local files (downloading S3 objects once each)."""

    def __init__(
        self, *, base_dir: Path | None, scratch: Path, pvc_root: Path | None = None
    ) -> None:
        self._base = base_dir
        self._scratch = scratch
        self._pvc_root = pvc_root
        self._client: Any = None

    def local(self, uri: str) -> Path:
        """A readable local path for ``uri``; :class:`ResultsError` when it cannot be had."""
        if uri.startswith(S3_SCHEME):
            return self._download(uri)
        if uri.startswith("pvc://"):
            if self._pvc_root is None:
                raise ResultsError(f"{uri} is on a cluster volume; mount it and pass --pvc-root")
            parts = urlsplit(uri)
            return self._existing(self._pvc_root / parts.netloc / unquote(parts.path).lstrip("/"))
        if uri.startswith("file://"):
            return self._existing(Path(unquote(urlsplit(uri).path)))
        if "://" in uri:
            raise ResultsError(f"cannot fetch {uri}: unsupported scheme")
        path = Path(uri)
        if not path.is_absolute():
            if self._base is None:
                raise ResultsError(
                    f"relative artifact path {uri} needs the run's output folder (--artifacts)"
                )
            path = self._base / path
        return self._existing(path)

    @staticmethod
    def _existing(path: Path) -> Path:
        if not path.is_file():
            raise ResultsError(f"artifact {path} does not exist")
        return path

    def _download(self, uri: str) -> Path:
        location = S3Location.parse(uri)
        target = self._scratch / location.bucket / location.prefix
        if target.is_file():
            return target
        target.parent.mkdir(parents=True, exist_ok=True)
        try:
            import boto3
            import botocore.config
            import botocore.exceptions

            if self._client is None:
                endpoint = os.environ.get("AWS_ENDPOINT_URL_S3") or os.environ.get(
                    "AWS_ENDPOINT_URL"
                )
                self._client = boto3.session.Session().client(
                    "s3",
                    endpoint_url=endpoint or None,
                    config=botocore.config.Config(
                        connect_timeout=5, read_timeout=30, s3={"addressing_style": "path"}
                    ),
                )
            self._client.download_file(location.bucket, location.prefix, str(target))
        except (botocore.exceptions.BotoCoreError, botocore.exceptions.ClientError) as exc:
            raise ResultsError(f"cannot download {uri}: {exc}") from None
        except OSError as exc:
            raise ResultsError(f"cannot download {uri}: {exc}") from None
        return target
