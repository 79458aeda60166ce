"""Locating pinned scenarios: from a source URI back to a local file with the frozen bytes.

``simtest run --frozen`` and a resumed run do not resolve sources again; they fetch each pinned
URI and verify its sha256, so a file that changed since it was frozen is an error instead of a
silently different test. One :class:`Locator` serves a whole run and fetches each git commit,
archive or query once.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path

from simtest_operator.errors import SourceError
from simtest_operator.scenarios import gitfetching, resolving, uris
from simtest_operator.scenarios.pinned import PinnedScenario, sha256_hex
from simtest_operator.scenarios.specs import ConfigMapSource, GraphqlSource


@dataclasses.dataclass(slots=True)
class Locator:
    """Fetches pinned URIs, remembering what it fetched (one instance per run, not shared)."""

    ctx: resolving.FetchContext
    graphql_sources: Sequence[GraphqlSource] = ()
    """The campaign's GraphQL sources, queried again for items pinned by inline content."""
    _http: dict[str, resolving.HttpBody] = dataclasses.field(default_factory=dict)
    _graphql: dict[str, dict[str, Path]] = dataclasses.field(default_factory=dict)
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
        if isinstance(parsed, uris.GraphqlUri):
            return self._graphql_item(parsed, uri)
        return self._configmap_key(parsed)

    def _graphql_item(self, parsed: uris.GraphqlUri, uri: str) -> Path:
        for index, source in enumerate(self.graphql_sources):
            if source.endpoint != parsed.endpoint:
                continue
            key = f"{index}:{source.endpoint}"
            if key not in self._graphql:
                resolved = resolving.resolve(source, self.ctx)
                self._graphql[key] = {
                    source_uri: resolved.root / rel for rel, source_uri in resolved.uris.items()
                }
            found = self._graphql[key].get(uri)
            if found is not None:
                return found
        raise SourceError(
            f"{uri}: no GraphQL source of the campaign returns item {parsed.item!r} any more"
        )

    def _configmap_key(self, parsed: uris.ConfigMapUri) -> Path:
        if parsed.name not in self._configmaps:
            resolved = resolving.resolve(ConfigMapSource(name=parsed.name), self.ctx)
            self._configmaps[parsed.name] = resolved.root
        path = self._configmaps[parsed.name] / parsed.key
        if not path.is_file():
            # The key does not end in .xosc, so the default listing skipped it: read it directly.
            resolved = resolving.resolve(
                ConfigMapSource(name=parsed.name, keys=(parsed.key,)), self.ctx
            )
            path = resolved.root / parsed.key
        return path
