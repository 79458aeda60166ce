"""Git sources through the ``git`` command: resolve a revision to a commit, export that tree.

A repository is fetched into a bare mirror in the cache (shallow where the server allows it) and
the commit's tree is exported with ``git archive`` and unpacked by the safe extractor, because a
repository is as untrusted as any archive (it may hold symlinks to ``/etc``). Trees are cached by
commit and never change, so a pinned ``git+URL@COMMIT#PATH`` always yields the same bytes.
Local repositories are fetched through ``file://`` like remote ones: reading them never runs
their hooks or honours their config. Only the https, http, ssh, git and file transports are
allowed (``ext::`` would run commands); git runs in its own session, so it cannot prompt.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import re
import shutil
import subprocess
import tempfile
import urllib.parse
from collections.abc import Sequence
from pathlib import Path
from typing import IO

from simtest_operator import redaction
from simtest_operator.errors import SourceError
from simtest_operator.scenarios import archives
from simtest_operator.scenarios.specs import SourceLimits

_PINNED = "refs/simtest/pinned"
_COMMIT = re.compile(r"^[0-9a-f]{40}$")
_SCP_LIKE = re.compile(r"^[A-Za-z0-9._-]+@[A-Za-z0-9.-]+:")
_ALLOWED = ("https", "http", "ssh", "git", "file")
_SAFETY = [
    "-c", "protocol.allow=never",
    *[arg for scheme in _ALLOWED for arg in ("-c", f"protocol.{scheme}.allow=always")],
    "-c", "core.hooksPath=/dev/null",
    "-c", "advice.detachedHead=false",
]  # fmt: skip


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class GitTree:
    """A repository's tree at one commit, unpacked in the cache."""

    url: str
    """Normalised clone URL (local paths become ``file://`` URLs)."""
    commit: str
    root: Path
    """Folder of the whole tree."""


def normalise_url(url: str, *, base_dir: Path) -> str:
    """A clone URL for ``url``: URLs stay, local paths (relative to ``base_dir``) become file://."""
    if url.startswith("-"):
        raise SourceError(f"git URL {url!r} must not start with '-'")
    scheme = urllib.parse.urlsplit(url).scheme
    if "://" in url:
        if scheme not in _ALLOWED:
            raise SourceError(
                f"git URL {redact(url)!r} uses {scheme!r}; allowed: {', '.join(_ALLOWED)}"
            )
        return url
    if _SCP_LIKE.match(url):
        return url
    path = (base_dir / url).resolve()
    if not path.exists():
        raise SourceError(f"git repository {url!r} not found (looked in {path})")
    return path.as_uri()


def redact(url: str) -> str:
    """``url`` without a password or token in its user-info part (over http(s) a user name
    alone is a token: ``https://TOKEN@host/repo``)."""
    secrets = url_secrets(url)
    if not secrets.forms:
        return url
    parts = urllib.parse.urlsplit(url)
    userinfo, _, hostport = parts.netloc.rpartition("@")
    user, colon, _ = userinfo.partition(":")
    shown = f"{user}:{redaction.MASK}" if colon else redaction.MASK
    return urllib.parse.urlunsplit(parts._replace(netloc=f"{shown}@{hostport}"))


def url_secrets(url: str) -> redaction.Secrets:
    """The secrets in ``url``'s user info: the password, or an http(s) user name alone."""
    parts = urllib.parse.urlsplit(url)
    if parts.password is not None:
        return redaction.Secrets.of(parts.password)
    if parts.username and parts.scheme in ("http", "https"):
        return redaction.Secrets.of(parts.username)
    return redaction.Secrets()


def fetch_tree(url: str, revision: str, *, cache: Path, limits: SourceLimits) -> GitTree:
    """Resolve ``revision`` of the (normalised) ``url`` and return its unpacked tree."""
    mirror = cache / "repos" / hashlib.sha256(url.encode()).hexdigest()[:24]
    if not (mirror / "HEAD").exists():
        mirror.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=mirror.parent) as scratch:
            _git(["init", "--bare", "--quiet", scratch], limits=limits, url=url)
            with contextlib.suppress(OSError):  # a concurrent run created it first: use theirs
                Path(scratch).rename(mirror)
    commit = _resolve(mirror, url, revision, limits=limits)
    root = export_tree(mirror, url, commit, cache=cache, limits=limits)
    return GitTree(url=url, commit=commit, root=root)


def export_tree(mirror: Path, url: str, commit: str, *, cache: Path, limits: SourceLimits) -> Path:
    """Unpack ``commit`` from ``mirror`` into ``<cache>/trees/<commit>`` (once) and return it."""
    tree = cache / "trees" / commit
    if tree.is_dir():
        return tree
    tree.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=tree.parent) as scratch:
        tar = Path(scratch) / "tree.tar"
        with tar.open("wb") as sink:
            archive = ["-C", str(mirror), "archive", "--format=tar", commit]
            _git(archive, limits=limits, url=url, stdout=sink)
        unpacked = Path(scratch) / "tree"
        archives.extract(tar, unpacked, limits=limits, name=f"{redact(url)}@{commit}")
        try:
            unpacked.rename(tree)
        except OSError:
            if not tree.is_dir():
                raise
    return tree


def fetch_commit(url: str, commit: str, *, cache: Path, limits: SourceLimits) -> GitTree:
    """The tree of a pinned commit (cached, or fetched again and verified to be that commit)."""
    tree = cache / "trees" / commit
    if tree.is_dir():
        return GitTree(url=url, commit=commit, root=tree)
    fetched = fetch_tree(url, commit, cache=cache, limits=limits)
    if fetched.commit != commit:
        raise SourceError(f"{redact(url)}: revision {commit} resolved to {fetched.commit}")
    return fetched


def _resolve(mirror: Path, url: str, revision: str, *, limits: SourceLimits) -> str:
    if _COMMIT.match(revision) and _has_commit(mirror, revision, limits=limits):
        return revision
    fetch = ["-C", str(mirror), "fetch", "--quiet", "--no-tags", "--no-write-fetch-head"]
    refspec = f"+{revision}:{_PINNED}"
    try:
        _git([*fetch, "--depth=1", "--", url, refspec], limits=limits, url=url)
    except SourceError:
        if not _COMMIT.match(revision):
            # Servers without shallow support (git's "dumb" HTTP: a repository served as plain
            # files) refuse --depth: fetch the whole history of the ref instead.
            _git([*fetch, "--", url, refspec], limits=limits, url=url)
            return _pinned(mirror, url, limits=limits)
        # Some servers refuse fetching a bare commit; fetch every branch and tag instead.
        everything = ["+refs/heads/*:refs/simtest/heads/*", "+refs/tags/*:refs/simtest/tags/*"]
        _git([*fetch, "--", url, *everything], limits=limits, url=url)
        if not _has_commit(mirror, revision, limits=limits):
            raise SourceError(f"{redact(url)}: commit {revision} not found") from None
        return revision
    return _pinned(mirror, url, limits=limits)


def _pinned(mirror: Path, url: str, *, limits: SourceLimits) -> str:
    """The commit the last fetch pinned."""
    resolved = _git(
        ["-C", str(mirror), "rev-parse", "--verify", f"{_PINNED}^{{commit}}"],
        limits=limits,
        url=url,
    )
    return resolved.strip()


def _has_commit(mirror: Path, commit: str, *, limits: SourceLimits) -> bool:
    try:
        _git(["-C", str(mirror), "cat-file", "-e", f"{commit}^{{commit}}"], limits=limits, url="")
    except SourceError:
        return False
    return True


def _git(
    args: Sequence[str], *, limits: SourceLimits, url: str, stdout: IO[bytes] | None = None
) -> str:
    git = shutil.which("git")
    if git is None:
        raise SourceError("git sources need the 'git' command; install git")
    try:
        done = subprocess.run(
            [git, *_SAFETY, *args],
            stdin=subprocess.DEVNULL,
            stdout=stdout if stdout is not None else subprocess.PIPE,
            stderr=subprocess.PIPE,
            timeout=limits.git_timeout,
            start_new_session=True,
            check=False,
        )
    except subprocess.TimeoutExpired as exc:
        raise SourceError(
            f"git {args[0] if args[0] != '-C' else args[2]} of {redact(url)} took longer than "
            f"{limits.git_timeout:.0f} s"
        ) from exc
    if done.returncode != 0:
        message = stderr_summary(done.stderr.decode(errors="replace")) or (
            f"exit code {done.returncode}"
        )
        if url:
            # git quotes the URL as given or re-encoded: mask the whole, then the secret alone.
            message = url_secrets(url).redact(message.replace(url, redact(url)))
        raise SourceError(f"git failed for {redact(url) or 'the cache'}: {message}")
    return done.stdout.decode() if stdout is None else ""


_MESSAGE_PREFIXES = ("fatal:", "error:", "remote:", "ssh:", "warning:")
_MAX_MESSAGE = 500


def stderr_summary(stderr: str) -> str:
    """git's diagnostics as one line: its ``fatal:``/``error:``/``remote:`` lines (all lines if
    there are none), joined. The last line alone was often advice ("and the repository exists.")
    rather than the cause (issue 12)."""
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    chosen = [line for line in lines if line.lower().startswith(_MESSAGE_PREFIXES)] or lines
    unique = list(dict.fromkeys(chosen))
    joined = "; ".join(unique)
    return joined if len(joined) <= _MAX_MESSAGE else joined[: _MAX_MESSAGE - 3] + "..."
