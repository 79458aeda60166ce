"""Resolving sources: turn each source entry into a local folder of files plus their source URIs.

Every kind ends the same way: a root folder on the local disk (the manifest's folder, an exported
git tree, an unpacked archive, or files written from a database or ConfigMap) and the list of
files below it with the URI that fetches each one again. Selection, header reading and pinning
then work on that uniform shape. Downloads land in the cache, never in the output folder; trees
are keyed by commit or content hash, so resolving twice does not fetch twice.
"""

from __future__ import annotations

import dataclasses
import os
import tempfile
import urllib.parse
from collections.abc import Callable, Mapping
from pathlib import Path, PurePosixPath

from simtest_operator.errors import SourceError
from simtest_operator.scenarios import archives, downloading, gitfetching, querying, uris
from simtest_operator.scenarios.pinned import ResolvedSourceInfo, sha256_hex
from simtest_operator.scenarios.specs import (
    ConfigMapSource,
    GitSource,
    GraphqlSource,
    HttpSource,
    PathSource,
    RestSource,
    SourceLimits,
    SourceSpec,
)

ConfigMapReader = Callable[[str], Mapping[str, bytes]]
"""Returns a ConfigMap's data (key -> bytes) by name; raises SourceError when it is missing."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class FetchContext:
    """What resolution may use: folders, limits and injected readers for secrets and ConfigMaps."""

    base_dir: Path
    """Folder relative paths are resolved against (the manifest's folder)."""
    cache_dir: Path
    """Where downloads, git mirrors and unpacked trees go (``<cache>/sources``)."""
    limits: SourceLimits = dataclasses.field(default_factory=SourceLimits)
    secrets: querying.SecretProvider | None = None
    config_maps: ConfigMapReader | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ResolvedSource:
    """One source, materialised."""

    info: ResolvedSourceInfo
    root: Path
    files: tuple[str, ...]
    """Relative POSIX paths below ``root``, sorted."""
    uris: Mapping[str, str]
    """File path -> source URI."""

    def uri_for(self, path: Path) -> str:
        """The source URI of ``path``, a file of this source (e.g. the scenario a distribution
        names); SourceError when it lies outside the source and cannot be pinned."""
        absolute = path.resolve()
        root = self.root.resolve()
        if absolute.is_relative_to(root):
            found = self.uris.get(absolute.relative_to(root).as_posix())
            if found is not None:
                return found
        if self.info.kind == "path" and absolute.is_file():
            return uris.file_uri(absolute)
        raise SourceError(
            f"{path} is not a file of the {self.info.kind} source {self.info.location}; "
            "a referenced scenario must come from the same source"
        )


def resolve(source: SourceSpec, ctx: FetchContext) -> ResolvedSource:
    """Materialise ``source`` and list its files."""
    if isinstance(source, PathSource):
        return _path(source, ctx)
    if isinstance(source, GitSource):
        return _git(source, ctx)
    if isinstance(source, HttpSource):
        return _http(source, ctx)
    if isinstance(source, GraphqlSource | RestSource):
        return _database(source, ctx)
    return _configmap(source, ctx)


def list_files(root: Path, *, limits: SourceLimits) -> tuple[str, ...]:
    """Regular files below ``root`` (symlinks followed only when they stay inside), sorted."""
    real_root = root.resolve()
    found: list[str] = []
    for folder, dirs, files in os.walk(root):
        here = Path(folder)
        dirs[:] = sorted(d for d in dirs if not (here / d).is_symlink() and not d.startswith("."))
        for name in files:
            path = here / name
            if path.is_symlink() and not path.resolve().is_relative_to(real_root):
                continue
            if not path.is_file():
                continue
            found.append(path.relative_to(root).as_posix())
            if len(found) > limits.max_files:
                raise SourceError(f"{root}: more than {limits.max_files} files")
    return tuple(sorted(found))


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class HttpBody:
    """A downloaded body, materialised in the cache."""

    root: Path
    """An archive's unpacked tree, or a folder holding the single file."""
    sha256: str
    archive: bool


def materialise_http(url: str, ctx: FetchContext, *, sha256: str | None = None) -> HttpBody:
    """Download ``url`` into the cache; archives are unpacked, a single file is stored under its
    URL's base name. Folders are keyed by the body's sha256, so equal bodies are shared."""
    downloads = ctx.cache_dir / "http"
    downloads.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=downloads) as scratch:
        body = Path(scratch) / "body"
        digest = downloading.download(url, body, limits=ctx.limits)
        if sha256 is not None and digest != sha256:
            raise SourceError(f"{url}: sha256 {digest} differs from the expected {sha256}")
        with body.open("rb") as handle:
            archive = archives.sniff(handle.read(512)) is not None
        root = downloads / digest
        if root.is_dir():
            return HttpBody(root=root, sha256=digest, archive=archive)
        staging = Path(scratch) / "root"
        if archive:
            archives.extract(body, staging, limits=ctx.limits, name=url)
        else:
            staging.mkdir()
            body.rename(staging / http_file_name(url))
        _publish(staging, root)
    return HttpBody(root=root, sha256=digest, archive=archive)


def _publish(staging: Path, root: Path) -> None:
    """Move a finished tree into place; a concurrent run that got there first wins."""
    try:
        staging.rename(root)
    except OSError:
        if not root.is_dir():
            raise


def http_file_name(url: str) -> str:
    """The local name of a single file downloaded from ``url``."""
    name = PurePosixPath(urllib.parse.unquote(urllib.parse.urlsplit(url).path)).name
    safe = "".join(c if c.isalnum() or c in "._-" else "_" for c in name).lstrip(".")
    return safe if safe.endswith(".xosc") else (safe or "scenario") + ".xosc"


def _path(source: PathSource, ctx: FetchContext) -> ResolvedSource:
    target = (ctx.base_dir / source.path).absolute()
    if not target.exists():
        raise SourceError(f"scenario path {source.path!r} does not exist (looked in {target})")
    files: tuple[str, ...]
    if target.is_file():
        root, files = target.parent, (target.name,)
    else:
        root, files = target, list_files(target, limits=ctx.limits)
    info = ResolvedSourceInfo(kind="path", location=str(target), files=len(files))
    mapping = {rel: uris.file_uri(root / rel) for rel in files}
    return ResolvedSource(info=info, root=root, files=files, uris=mapping)


def _git(source: GitSource, ctx: FetchContext) -> ResolvedSource:
    url = gitfetching.normalise_url(source.url, base_dir=ctx.base_dir)
    tree = gitfetching.fetch_tree(
        url, source.revision, cache=ctx.cache_dir / "git", limits=ctx.limits
    )
    sub = archives.checked_member(source.path, gitfetching.redact(url)) if source.path else ""
    root = tree.root / sub if sub else tree.root
    if not root.is_dir():
        raise SourceError(
            f"{gitfetching.redact(url)}@{tree.commit}: folder {source.path!r} does not exist"
        )
    files = list_files(root, limits=ctx.limits)
    prefix = f"{sub}/" if sub else ""
    info = ResolvedSourceInfo(
        kind="git", location=gitfetching.redact(url), revision=tree.commit, files=len(files)
    )
    mapping = {rel: uris.git_uri(url, tree.commit, prefix + rel) for rel in files}
    return ResolvedSource(info=info, root=root, files=files, uris=mapping)


def _http(source: HttpSource, ctx: FetchContext) -> ResolvedSource:
    body = materialise_http(source.url, ctx, sha256=source.sha256)
    files = list_files(body.root, limits=ctx.limits)
    mapping = {
        rel: uris.http_uri(source.url, rel) if body.archive else uris.http_uri(source.url)
        for rel in files
    }
    info = ResolvedSourceInfo(
        kind="http", location=source.url, revision=body.sha256, files=len(files)
    )
    return ResolvedSource(info=info, root=body.root, files=files, uris=mapping)


def _database(source: GraphqlSource | RestSource, ctx: FetchContext) -> ResolvedSource:
    """Query a scenario database: items with a URL are downloaded and pinned by that URL, inline
    items are pinned under the database (``graphql+``/``rest+``), so a fetcher asks it again."""
    where = querying.location(source)
    graphql = isinstance(source, GraphqlSource)
    kind = "graphql" if graphql else "rest"
    scratch_parent = ctx.cache_dir / kind
    scratch_parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=scratch_parent) as scratch:
        items = querying.query(
            source, limits=ctx.limits, scratch=Path(scratch), secrets=ctx.secrets
        )
        staging = Path(scratch) / "root"
        mapping: dict[str, str] = {}
        for item in items:
            rel = graphql_file_name(item.id, where)
            if rel in mapping:
                raise SourceError(f"{where}: items {item.id!r} and another share the file {rel}")
            target = staging / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            if item.url is not None:
                downloading.download(item.url, target, limits=ctx.limits)
                mapping[rel] = uris.http_uri(item.url)
            else:
                content = item.content or b""
                if len(content) > ctx.limits.max_scenario_bytes:
                    raise SourceError(
                        f"{where}: item {item.id!r} is larger than "
                        f"{ctx.limits.max_scenario_bytes} bytes"
                    )
                target.write_bytes(content)
                inline = uris.graphql_uri if graphql else uris.rest_uri
                mapping[rel] = inline(where, item.id)
        staging.mkdir(exist_ok=True)
        listing = "\n".join(
            f"{rel} {mapping[rel]} {sha256_hex((staging / rel).read_bytes())}"
            for rel in sorted(mapping)
        )
        root = scratch_parent / sha256_hex(listing.encode())
        if not root.is_dir():
            _publish(staging, root)
    files = tuple(sorted(mapping))
    info = ResolvedSourceInfo(kind=kind, location=where, files=len(files))
    return ResolvedSource(info=info, root=root, files=files, uris=mapping)


def graphql_file_name(item_id: str, endpoint: str) -> str:
    """The relative path a database item is stored under (its id, ending in ``.xosc``)."""
    rel = archives.checked_member(item_id, endpoint)
    if not rel:
        raise SourceError(f"{endpoint}: item id {item_id!r} is not usable as a file name")
    return rel if rel.endswith(".xosc") else rel + ".xosc"


def _configmap(source: ConfigMapSource, ctx: FetchContext) -> ResolvedSource:
    if ctx.config_maps is None:
        raise SourceError(
            f"configMap source {source.name!r} needs a Kubernetes cluster; run the campaign "
            "with `simtest submit`, or copy the files to a folder and use a path source"
        )
    data = ctx.config_maps(source.name)
    keys = source.keys or tuple(sorted(k for k in data if k.endswith(".xosc")))
    missing = [key for key in keys if key not in data]
    if missing:
        raise SourceError(f"ConfigMap {source.name!r} has no key(s) {', '.join(missing)}")
    names = [archives.checked_member(key, f"ConfigMap {source.name}") for key in keys]
    digest = sha256_hex(b"".join(sha256_hex(data[k]).encode() + k.encode() for k in keys))
    root = ctx.cache_dir / "configmap" / digest
    if not root.is_dir():
        root.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=root.parent) as scratch:
            staging = Path(scratch) / "root"
            for key, name in zip(keys, names, strict=True):
                (staging / name).parent.mkdir(parents=True, exist_ok=True)
                (staging / name).write_bytes(data[key])
            _publish(staging, root)
    info = ResolvedSourceInfo(kind="configMap", location=source.name, files=len(names))
    pairs = zip(keys, names, strict=True)
    mapping = {name: uris.configmap_uri(source.name, key) for key, name in pairs}
    return ResolvedSource(info=info, root=root, files=tuple(sorted(names)), uris=mapping)
