"""Bounded HTTP(S) transfers for scenario sources, with the standard library only.

Downloads are untrusted: the body is streamed to disk and cut off at the size limit (a missing or
lying Content-Length does not help), redirects may only lead to http/https, and a stalled server
fails after the network timeout. Failures become SourceError naming the URL, never the
credentials that went with the request.
"""

from __future__ import annotations

import hashlib
import shutil
import urllib.error
import urllib.parse
import urllib.request
from collections.abc import Mapping
from pathlib import Path
from typing import IO, Any

from simtest_operator.errors import SourceError
from simtest_operator.scenarios.specs import SourceLimits

_CHUNK = 256 * 1024
USER_AGENT = "simtest-operator/scenario-source"


class _HttpOnlyRedirects(urllib.request.HTTPRedirectHandler):
    """Follow redirects to http and https only (urllib would also follow ftp)."""

    def redirect_request(
        self,
        req: urllib.request.Request,
        fp: IO[bytes],
        code: int,
        msg: str,
        headers: Any,
        newurl: str,
    ) -> urllib.request.Request | None:
        if urllib.parse.urlsplit(newurl).scheme not in ("http", "https"):
            fp.close()
            raise SourceError(f"{req.full_url}: redirect to a non-HTTP location refused")
        return super().redirect_request(req, fp, code, msg, headers, newurl)


def _opener() -> urllib.request.OpenerDirector:
    return urllib.request.build_opener(_HttpOnlyRedirects())


def check_http_url(url: str) -> None:
    """Raise SourceError unless ``url`` is an http(s) URL with a host."""
    parts = urllib.parse.urlsplit(url)
    if parts.scheme not in ("http", "https") or not parts.netloc:
        raise SourceError(f"{url!r} is not an http(s) URL")


def download(
    url: str,
    target: Path,
    *,
    limits: SourceLimits,
    data: bytes | None = None,
    headers: Mapping[str, str] | None = None,
) -> str:
    """GET (or POST ``data``) ``url`` into ``target``; return the body's sha256 hex digest."""
    check_http_url(url)
    request = urllib.request.Request(
        url.split("#", 1)[0],
        data=data,
        headers={"User-Agent": USER_AGENT, **(headers or {})},
        method="POST" if data is not None else "GET",
    )
    digest = hashlib.sha256()
    size = 0
    target.parent.mkdir(parents=True, exist_ok=True)
    partial = target.with_name(target.name + ".part")
    try:
        with _opener().open(request, timeout=limits.network_timeout) as response:
            declared = response.headers.get("Content-Length")
            if declared and declared.isdigit() and int(declared) > limits.max_download_bytes:
                raise SourceError(
                    f"{url}: download of {declared} bytes exceeds the "
                    f"{limits.max_download_bytes} byte limit"
                )
            with partial.open("wb") as sink:
                while chunk := response.read(_CHUNK):
                    size += len(chunk)
                    if size > limits.max_download_bytes:
                        raise SourceError(
                            f"{url}: download exceeds the {limits.max_download_bytes} byte limit"
                        )
                    digest.update(chunk)
                    sink.write(chunk)
        shutil.move(partial, target)
    except urllib.error.HTTPError as exc:
        exc.close()
        raise SourceError(f"{url}: HTTP {exc.code} {exc.reason}") from exc
    except urllib.error.URLError as exc:
        raise SourceError(f"{url}: cannot connect ({exc.reason})") from exc
    except (TimeoutError, OSError) as exc:
        raise SourceError(f"{url}: transfer failed ({exc})") from exc
    finally:
        partial.unlink(missing_ok=True)
    return digest.hexdigest()


def fetch_bytes(
    url: str,
    *,
    limits: SourceLimits,
    scratch: Path,
    data: bytes | None = None,
    headers: Mapping[str, str] | None = None,
) -> bytes:
    """A bounded request whose (small) body is returned in memory; ``scratch`` is a temp folder."""
    target = scratch / "body"
    download(url, target, limits=limits, data=data, headers=headers)
    try:
        return target.read_bytes()
    finally:
        target.unlink(missing_ok=True)
