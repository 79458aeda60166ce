"""Bounded HTTP(S) transfers for scenario sources, with the standard library only.

Downloads are untrusted: the body is streamed to disk and cut off at the size limit (a missing or
lying Content-Length does not help), redirects may only lead to http/https, at most
:data:`MAX_REDIRECTS` of them and never in a loop, and a stalled server fails after the network
timeout. A redirect to another origin (scheme, host or port) drops the credentials, as curl and
requests do: a database's bearer token once followed a redirect to another host. Failures become
one-line SourceErrors naming the URL, never the credentials that went with the request.
"""

from __future__ import annotations

import hashlib
import http.client
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


MAX_REDIRECTS = 10
"""Redirects one download may follow (urllib's own limit)."""
CREDENTIAL_HEADERS = ("Authorization", "Cookie")
"""Headers that never follow a redirect to another origin (urllib's capitalised spelling)."""
_DEFAULT_PORTS = {"http": 80, "https": 443}


class _RedirectError(Exception):
    """A redirect this module does not follow; the message says why, in one line."""


class _SafeRedirects(urllib.request.HTTPRedirectHandler):
    """Follow redirects to http(s) only (urllib would also follow ftp), refuse loops and chains
    longer than :data:`MAX_REDIRECTS` in one line (urllib's message is three lines ending in the
    reason phrase), and drop the credentials when the origin changes (urllib keeps them)."""

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
            raise _RedirectError("redirect to a non-HTTP location refused")
        visited: dict[str, int] = getattr(req, "redirect_dict", {})
        if newurl == req.full_url or newurl in visited:
            fp.close()
            raise _RedirectError(f"redirect loop (HTTP {code} back to {newurl})")
        if len(visited) >= MAX_REDIRECTS:
            fp.close()
            raise _RedirectError(f"more than {MAX_REDIRECTS} redirects")
        new = super().redirect_request(req, fp, code, msg, headers, newurl)
        if new is not None and origin(newurl) != origin(req.full_url):
            for name in CREDENTIAL_HEADERS:
                new.remove_header(name)
        return new


def origin(url: str) -> tuple[str, str, int | None]:
    """The (scheme, host, port) a URL's credentials belong to (RFC 6454)."""
    parts = urllib.parse.urlsplit(url)
    scheme = parts.scheme.lower()
    try:
        port = parts.port
    except ValueError:
        port = None
    return scheme, (parts.hostname or "").lower(), port or _DEFAULT_PORTS.get(scheme)


def _opener() -> urllib.request.OpenerDirector:
    return urllib.request.build_opener(_SafeRedirects())


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
    except _RedirectError as exc:
        raise SourceError(f"{url}: {exc}") from None
    except urllib.error.HTTPError as exc:
        exc.close()
        raise SourceError(f"{url}: HTTP {exc.code} {_one_line(exc.reason)}") from exc
    except urllib.error.URLError as exc:
        raise SourceError(f"{url}: cannot connect ({_one_line(exc.reason)})") from exc
    except (TimeoutError, OSError, http.client.HTTPException) as exc:
        # HTTPException: a malformed status line or headers, or a body cut short.
        raise SourceError(f"{url}: transfer failed ({_one_line(exc)})") from exc
    finally:
        partial.unlink(missing_ok=True)
    return digest.hexdigest()


def _one_line(reason: object) -> str:
    return " ".join(str(reason).split())


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
