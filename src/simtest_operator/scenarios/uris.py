"""Source URIs: one string per pinned scenario that says exactly where its file comes from.

The frozen list must let anyone (``simtest run --frozen``, a simulator pod) fetch the very same
bytes again, so a URI carries everything resolution decided (the git commit, the archive member):

=============================================  ==================================================
``file:///abs/dir/a.xosc``                     a local file (path sources)
``git+https://host/repo.git@<commit>#<path>``  a file in a repository at a commit (40 hex digits)
``https://host/suite.tgz#<member>``            a member of an HTTP archive
``https://host/a.xosc``                        a single file over HTTP (no fragment)
``graphql+https://host/graphql#<item id>``     inline content of a GraphQL database item
``rest+https://host/api/scenarios#<item id>``  inline content of a REST database item
``configmap:<name>/<key>``                     a key of a ConfigMap in the campaign's namespace
=============================================  ==================================================

Fragments (paths, ids, keys) are percent-encoded, so ``#`` and ``@`` inside them are unambiguous.
"""

from __future__ import annotations

import dataclasses
import re
import urllib.parse
from pathlib import Path, PurePosixPath

from simtest_operator.errors import SourceError

_GIT = re.compile(r"^git\+(?P<url>.+)@(?P<commit>[0-9a-f]{40})#(?P<path>.*)$")


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class FileUri:
    """A local file."""

    path: Path


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class GitUri:
    """A file in a git repository at a commit."""

    url: str
    commit: str
    path: str
    """Path inside the repository (POSIX)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class HttpUri:
    """A file over HTTP, either the body itself or a member of an archive body."""

    url: str
    member: str | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class GraphqlUri:
    """Inline content of one GraphQL database item."""

    endpoint: str
    item: str


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RestUri:
    """Inline content of one REST database item; ``url`` is the source's URL (query included)."""

    url: str
    item: str


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ConfigMapUri:
    """A key of a ConfigMap."""

    name: str
    key: str


SourceUri = FileUri | GitUri | HttpUri | GraphqlUri | RestUri | ConfigMapUri


def _quote(text: str) -> str:
    return urllib.parse.quote(text, safe="/-._~")


def file_uri(path: Path) -> str:
    """URI of an absolute local path."""
    return path.absolute().as_uri()


def git_uri(url: str, commit: str, path: str) -> str:
    """URI of ``path`` inside the repository at ``url`` and ``commit``."""
    return f"git+{url}@{commit}#{_quote(path)}"


def http_uri(url: str, member: str | None = None) -> str:
    """URI of an HTTP file, or of ``member`` inside the archive at ``url``."""
    base = url.split("#", 1)[0]
    return base if member is None else f"{base}#{_quote(member)}"


def graphql_uri(endpoint: str, item: str) -> str:
    """URI of the inline content of item ``item``."""
    return f"graphql+{endpoint}#{_quote(item)}"


def rest_uri(url: str, item: str) -> str:
    """URI of the inline content of item ``item`` of the REST source at ``url``."""
    return f"rest+{url.split('#', 1)[0]}#{_quote(item)}"


def configmap_uri(name: str, key: str) -> str:
    """URI of a ConfigMap key."""
    return f"configmap:{name}/{_quote(key)}"


def parse(uri: str) -> SourceUri:
    """Split a source URI into its parts; raises SourceError for anything else."""
    if uri.startswith("git+"):
        match = _GIT.match(uri)
        if match is None:
            raise SourceError(f"malformed git source URI {uri!r} (git+URL@COMMIT#PATH expected)")
        path = _checked_relative(urllib.parse.unquote(match["path"]), uri)
        return GitUri(url=match["url"], commit=match["commit"], path=path)
    if uri.startswith("graphql+"):
        endpoint, _, item = uri.removeprefix("graphql+").partition("#")
        if not endpoint.startswith(("http://", "https://")) or not item:
            raise SourceError(f"malformed graphql source URI {uri!r}")
        return GraphqlUri(endpoint=endpoint, item=urllib.parse.unquote(item))
    if uri.startswith("rest+"):
        url, _, item = uri.removeprefix("rest+").partition("#")
        if not url.startswith(("http://", "https://")) or not item:
            raise SourceError(f"malformed rest source URI {uri!r} (rest+URL#ITEM expected)")
        return RestUri(url=url, item=urllib.parse.unquote(item))
    if uri.startswith("configmap:"):
        name, _, key = uri.removeprefix("configmap:").partition("/")
        if not name or not key:
            raise SourceError(f"malformed ConfigMap source URI {uri!r}")
        return ConfigMapUri(name=name, key=urllib.parse.unquote(key))
    parts = urllib.parse.urlsplit(uri)
    if parts.scheme == "file":
        if parts.netloc not in ("", "localhost"):
            raise SourceError(f"file URI {uri!r} names a remote host")
        return FileUri(path=Path(urllib.parse.unquote(parts.path)))
    if parts.scheme in ("http", "https"):
        base = urllib.parse.urlunsplit(parts._replace(fragment=""))
        member = urllib.parse.unquote(parts.fragment) if parts.fragment else None
        if member is not None:
            member = _checked_relative(member, uri)
        return HttpUri(url=base, member=member)
    raise SourceError(f"unknown source URI scheme in {uri!r}")


def sibling(uri: str, path: Path, other: Path) -> str:
    """The URI of ``other``, a file of the same source as ``path`` (whose URI is ``uri``): the
    scenario a distribution names, pinned from the tree the distribution came from. SourceError
    when ``other`` lies outside that source."""
    parsed = parse(uri)
    if isinstance(parsed, FileUri):
        return file_uri(other.resolve())
    root = source_root(path, uri)
    assert root is not None
    try:
        member = other.resolve().relative_to(root.resolve()).as_posix()
    except ValueError:
        raise SourceError(f"{other} is outside the source of {uri}") from None
    if isinstance(parsed, GitUri):
        return git_uri(parsed.url, parsed.commit, member)
    if isinstance(parsed, HttpUri):
        if parsed.member is None:
            raise SourceError(f"{uri} is a single downloaded file: it has no sibling {member}")
        return http_uri(parsed.url, member)
    if isinstance(parsed, ConfigMapUri):
        return configmap_uri(parsed.name, member)
    if isinstance(parsed, GraphqlUri):
        return graphql_uri(parsed.endpoint, member)
    return rest_uri(parsed.url, member)


def _checked_relative(path: str, uri: str) -> str:
    pure = PurePosixPath(path)
    if pure.is_absolute() or ".." in pure.parts or not path:
        raise SourceError(f"source URI {uri!r} names a path outside its source")
    return pure.as_posix()


def source_root(path: Path, uri: str) -> Path | None:
    """The folder ``uri``'s source was materialised into, given the local ``path`` of the file:
    a git tree at its commit, an unpacked archive, a database's or ConfigMap's files. What the
    scenario may reference (roads, catalogs) must stay below it. None for local files
    (``file://``): their tree is the user's own (the loader then confines them to their git work
    tree, and refuses system folders in any case)."""
    parsed = parse(uri)
    if isinstance(parsed, FileUri):
        return None
    if isinstance(parsed, GitUri):
        member = parsed.path
    elif isinstance(parsed, HttpUri):
        member = parsed.member or path.name  # a single file: alone in its download folder
    elif isinstance(parsed, ConfigMapUri):
        member = parsed.key
    else:
        member = parsed.item  # a database item is stored under its id
    depth = len(PurePosixPath(member).parts)
    root = path
    for _ in range(depth):
        root = root.parent
    return root
