"""Locating pinned scenarios: from a source URI back to a local file with the frozen bytes.

``simtest run --frozen`` and a resumed run do not resolve sources again; they fetch each pinned
URI and verify its sha256, so a file that changed since it was frozen is an error instead of a
silently different test. One :class:`Locator` serves a whole run and fetches each git commit,
archive or query once. :func:`needs` says what a Locator must be given to fetch a set of URIs
(the operator mounts those ConfigMaps into a simulator pod and hands it those databases).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Sequence
from pathlib import Path

from simtest_operator.errors import SourceError
from simtest_operator.scenarios import gitfetching, querying, resolving, uris
from simtest_operator.scenarios.pinned import PinnedScenario, sha256_hex
from simtest_operator.scenarios.specs import (
    ConfigMapSource,
    DatabaseSource,
    GraphqlSource,
    RestSource,
    SourceSpec,
)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Needs:
    """What fetching some pinned URIs takes beyond network reach."""

    config_maps: tuple[str, ...] = ()
    """ConfigMap names (sorted) the URIs read keys of."""
    databases: tuple[DatabaseSource, ...] = ()
    """The campaign's database sources (in campaign order) that must be asked again for inline
    items; a URI names its database by URL only, so every source at that URL is included."""


def needs(source_uris: Iterable[str], sources: Sequence[SourceSpec]) -> Needs:
    """What a :class:`Locator` needs to fetch ``source_uris`` of a campaign with ``sources``;
    URIs that do not parse are left to the Locator to report."""
    config_maps: set[str] = set()
    graphql: set[str] = set()
    rest: set[str] = set()
    for uri in source_uris:
        try:
            parsed = uris.parse(uri)
        except SourceError:
            continue
        if isinstance(parsed, uris.ConfigMapUri):
            config_maps.add(parsed.name)
        elif isinstance(parsed, uris.GraphqlUri):
            graphql.add(parsed.endpoint)
        elif isinstance(parsed, uris.RestUri):
            rest.add(parsed.url)
    databases = tuple(
        source
        for source in sources
        if (isinstance(source, GraphqlSource) and _without_fragment(source.endpoint) in graphql)
        or (isinstance(source, RestSource) and _without_fragment(source.url) in rest)
    )
    return Needs(config_maps=tuple(sorted(config_maps)), databases=databases)


def _without_fragment(url: str) -> str:
    return url.split("#", 1)[0]


@dataclasses.dataclass(slots=True)
class Locator:
    """Fetches pinned URIs, remembering what it fetched (one instance per run, not shared)."""

    ctx: resolving.FetchContext
    graphql_sources: Sequence[DatabaseSource] = ()
    """The campaign's scenario databases (GraphQL and REST; the name predates REST), queried
    again for items pinned by inline content."""
    _http: dict[str, resolving.HttpBody] = dataclasses.field(default_factory=dict)
    _databases: dict[str, dict[str, Path]] = dataclasses.field(default_factory=dict)
    _configmaps: dict[str, Path] = dataclasses.field(default_factory=dict)

    def locate(self, scenario: PinnedScenario) -> Path:
        """The local file of ``scenario``; SourceError when unreachable or changed."""
        path = self.fetch(scenario.source)
        try:
            data = path.read_bytes()
        except OSError as exc:
            raise SourceError(f"{scenario.id}: cannot read {path}: {exc.strerror}") from exc
        if sha256_hex(data) != scenario.sha256:
            raise SourceError(
                f"{scenario.id}: file content changed since the list was frozen "
                f"(sha256 {sha256_hex(data)[:12]}..., pinned {scenario.sha256[:12]}...); "
                "resolve the campaign again instead of reusing the frozen list"
            )
        return path

    def fetch(self, uri: str) -> Path:
        """The local file behind ``uri`` (not verified)."""
        parsed = uris.parse(uri)
        if isinstance(parsed, uris.FileUri):
            return parsed.path
        if isinstance(parsed, uris.GitUri):
            tree = gitfetching.fetch_commit(
                parsed.url, parsed.commit, cache=self.ctx.cache_dir / "git", limits=self.ctx.limits
            )
            return tree.root / parsed.path
        if isinstance(parsed, uris.HttpUri):
            body = self._http.get(parsed.url)
            if body is None:
                body = resolving.materialise_http(parsed.url, self.ctx)
                self._http[parsed.url] = body
            if parsed.member is None:
                if body.archive:
                    raise SourceError(f"{uri}: the download is an archive; name a member (#path)")
                return body.root / resolving.http_file_name(parsed.url)
            return body.root / parsed.member
        if isinstance(parsed, uris.GraphqlUri | uris.RestUri):
            return self._database_item(parsed, uri)
        return self._configmap_key(parsed)

    def _database_item(self, parsed: uris.GraphqlUri | uris.RestUri, uri: str) -> Path:
        graphql = isinstance(parsed, uris.GraphqlUri)
        wanted = parsed.endpoint if isinstance(parsed, uris.GraphqlUri) else parsed.url
        kind = "GraphQL" if graphql else "REST"
        asked = 0
        for index, source in enumerate(self.graphql_sources):
            if isinstance(source, GraphqlSource) != graphql:
                continue
            if _without_fragment(querying.location(source)) != wanted:
                continue
            asked += 1
            key = f"{index}:{querying.location(source)}"
            if key not in self._databases:
                resolved = resolving.resolve(source, self.ctx)
                self._databases[key] = {
                    source_uri: resolved.root / rel for rel, source_uri in resolved.uris.items()
                }
            found = self._databases[key].get(uri)
            if found is not None:
                return found
        if not asked:
            raise SourceError(f"{uri}: no {kind} source at {wanted} was given to fetch it from")
        raise SourceError(
            f"{uri}: no {kind} source of the campaign returns item {parsed.item!r} any more"
        )

    def _configmap_key(self, parsed: uris.ConfigMapUri) -> Path:
        """The key's file, beside every other key of the ConfigMap: a scenario may name a road
        network or catalog stored as a sibling key (``LogicFile filepath="road.xodr"``)."""
        if parsed.name not in self._configmaps:
            reader = self.ctx.config_maps
            keys = tuple(sorted(reader(parsed.name))) if reader is not None else ()
            resolved = resolving.resolve(ConfigMapSource(name=parsed.name, keys=keys), self.ctx)
            self._configmaps[parsed.name] = resolved.root
        path = self._configmaps[parsed.name] / parsed.key
        if not path.is_file():
            raise SourceError(f"ConfigMap {parsed.name!r} has no key {parsed.key!r} any more")
        return path
