"""REST scenario databases, the mounted-ConfigMap reader and what a pod's Locator needs.

Covers: a GET of JSON (a top-level list, or an object with one of items/scenarios/results/data)
resolves like GraphQL (inline items pinned as ``rest+URL#id``, URL items as their http URI), with
the bearer token from the secret provider and never in an error; malformed responses are one-line
SourceErrors naming the URL and item; the Locator asks the REST source again for an inline item
(and says which source is missing); ``needs`` picks the ConfigMaps and databases a set of URIs
needs; MountedConfigMaps reads a kubelet-style configMap volume (``..data`` symlinks) bounded,
skipping what is not a key and refusing links out of the folder; a located key has every other
key of its ConfigMap beside it (a road network stored as a sibling key).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from simtest_operator.errors import SourceError
from simtest_operator.scenarios import (
    ConfigMapSource,
    FetchContext,
    GraphqlSource,
    HttpSource,
    Locator,
    MountedConfigMaps,
    PinnedScenario,
    RestSource,
    SecretRef,
    SourceLimits,
    needs,
    resolve,
    sha256_hex,
    uris,
)
from tests.scenarios.support import Routes, xosc


def json_route(routes: Routes, path: str, document: Any) -> None:
    routes.get[path] = (200, json.dumps(document).encode(), {"Content-Type": "application/json"})


@pytest.mark.parametrize("wrap", ["list", "items", "scenarios", "results", "data"])
def test_rest_items_inline_and_by_url(
    ctx: FetchContext, server: tuple[str, Routes], wrap: str
) -> None:
    base, routes = server
    routes.get["/files/b.xosc"] = (200, xosc("by url").encode(), {})
    items = [
        {"id": "cut-in/001", "content": xosc("inline")},
        {"id": 7, "url": f"{base}/files/b.xosc"},
    ]
    json_route(routes, "/api/scenarios?tag=x", items if wrap == "list" else {wrap: items, "n": 2})
    source = RestSource(url=f"{base}/api/scenarios?tag=x")
    resolved = resolve(source, ctx)
    assert resolved.files == ("7.xosc", "cut-in/001.xosc")
    assert resolved.uris["cut-in/001.xosc"] == f"rest+{base}/api/scenarios?tag=x#cut-in/001"
    assert resolved.uris["7.xosc"] == f"{base}/files/b.xosc"
    assert (resolved.root / "cut-in/001.xosc").read_text() == xosc("inline")
    assert resolved.info.kind == "rest" and resolved.info.files == 2
    method, path, headers = routes.requests[0]
    assert (method, path) == ("GET", "/api/scenarios?tag=x")
    assert headers["Accept"] == "application/json" and "Authorization" not in headers


def test_rest_bearer_token_and_never_in_errors(tmp_path: Path, server: tuple[str, Routes]) -> None:
    base, routes = server
    json_route(routes, "/api", [{"id": "a", "content": xosc()}])
    ref = SecretRef(name="db", key="token")
    ctx = FetchContext(
        base_dir=tmp_path, cache_dir=tmp_path / "cache", secrets=lambda r: f"s3cr3t-{r.key}"
    )
    resolve(RestSource(url=f"{base}/api", secret=ref), ctx)
    assert routes.requests[-1][2]["Authorization"] == "Bearer s3cr3t-token"
    routes.get["/api"] = (403, b"denied s3cr3t-token", {})
    with pytest.raises(SourceError) as caught:
        resolve(RestSource(url=f"{base}/api", secret=ref), ctx)
    assert "HTTP 403" in str(caught.value) and "s3cr3t" not in str(caught.value)
    bare = FetchContext(base_dir=tmp_path, cache_dir=tmp_path / "cache")
    with pytest.raises(SourceError, match="needs Secret db/token, but no secret provider"):
        resolve(RestSource(url=f"{base}/api", secret=ref), bare)


@pytest.mark.parametrize(
    ("body", "message"),
    [
        (b"<html>", "response is not JSON"),
        (b'{"items": [], "results": []}', "several item lists \\(items, results\\)"),
        (b'{"rows": []}', "one of the list fields items, scenarios, results, data"),
        (b'"text"', "must be a JSON list of scenarios"),
        (b'[{"id": "a"}]', "item 0 \\(a\\) must have exactly one of 'url' or 'content'"),
        (b'[{"content": "x"}]', "item 0 has no string or integer 'id'"),
        (b'[{"id": "a", "url": "ftp://h/a"}]', "is not an http\\(s\\) URL"),
        (b'[{"id": "a", "content": "x"}, {"id": "a", "content": "y"}]', "appears twice"),
        (b'[{"id": "a", "content": "x"}, {"id": "a.xosc", "content": "y"}]', "share the file"),
        (b'[{"id": "../a", "content": "x"}]', "outside"),
    ],
)
def test_rest_bad_responses(
    ctx: FetchContext, server: tuple[str, Routes], body: bytes, message: str
) -> None:
    base, routes = server
    routes.get["/api"] = (200, body, {})
    with pytest.raises(SourceError, match=message) as caught:
        resolve(RestSource(url=f"{base}/api"), ctx)
    assert str(caught.value).startswith(f"{base}/api") or "outside" in message
    assert "\n" not in str(caught.value)


def test_rest_response_and_items_are_bounded(tmp_path: Path, server: tuple[str, Routes]) -> None:
    base, routes = server
    json_route(routes, "/api", [{"id": f"s{i}", "content": "x" * 100} for i in range(5)])
    small = FetchContext(
        base_dir=tmp_path, cache_dir=tmp_path / "c", limits=SourceLimits(max_files=3)
    )
    with pytest.raises(SourceError, match="more than 3 scenarios"):
        resolve(RestSource(url=f"{base}/api"), small)
    tight = FetchContext(
        base_dir=tmp_path, cache_dir=tmp_path / "c", limits=SourceLimits(max_scenario_bytes=50)
    )
    with pytest.raises(SourceError, match="item 's0' is larger than 50 bytes"):
        resolve(RestSource(url=f"{base}/api"), tight)
    capped = FetchContext(
        base_dir=tmp_path, cache_dir=tmp_path / "c", limits=SourceLimits(max_download_bytes=200)
    )
    with pytest.raises(SourceError, match="exceeds the 200 byte limit"):
        resolve(RestSource(url=f"{base}/api"), capped)


def test_rest_uris_round_trip() -> None:
    uri = uris.rest_uri("https://db.example/api?tag=a b#ignored", "cut-in/#1")
    assert uri == "rest+https://db.example/api?tag=a b#cut-in/%231"
    assert uris.parse(uri) == uris.RestUri(url="https://db.example/api?tag=a b", item="cut-in/#1")
    with pytest.raises(SourceError, match="malformed rest source URI"):
        uris.parse("rest+ftp://x#a")
    with pytest.raises(SourceError, match="malformed rest source URI"):
        uris.parse("rest+https://x/api")


def pin(uri: str, content: str, ident: str = "a.xosc") -> PinnedScenario:
    return PinnedScenario(id=ident, source=uri, sha256=sha256_hex(content.encode()))


def test_locator_asks_the_rest_source_again(tmp_path: Path, server: tuple[str, Routes]) -> None:
    base, routes = server
    json_route(routes, "/api", {"scenarios": [{"id": "a", "content": xosc("inline")}]})
    source = RestSource(url=f"{base}/api")
    pinned = pin(f"rest+{base}/api#a", xosc("inline"))
    elsewhere = FetchContext(base_dir=tmp_path, cache_dir=tmp_path / "pod-cache")
    found = Locator(elsewhere, graphql_sources=(source,)).locate(pinned)
    assert found.read_text() == xosc("inline")
    with pytest.raises(SourceError, match=f"no REST source at {base}/api was given"):
        Locator(elsewhere).locate(pinned)
    graphql_only = (GraphqlSource(endpoint=f"{base}/api", query="{a}"),)
    with pytest.raises(SourceError, match="no REST source"):
        Locator(elsewhere, graphql_sources=graphql_only).locate(pinned)
    json_route(routes, "/api", {"scenarios": []})
    with pytest.raises(SourceError, match="returns item 'a' any more"):
        Locator(elsewhere, graphql_sources=(source,)).locate(pinned)
    json_route(routes, "/api", {"scenarios": [{"id": "a", "content": xosc("changed")}]})
    with pytest.raises(SourceError, match="content changed since the list was frozen"):
        Locator(elsewhere, graphql_sources=(source,)).locate(pinned)


def test_needs_of_uris() -> None:
    graphql = GraphqlSource(endpoint="https://db/graphql", query="{a}")
    other_query = GraphqlSource(endpoint="https://db/graphql", query="{b}")
    rest = RestSource(url="https://db/api?x=1", secret=SecretRef(name="t", key="k"))
    unused = RestSource(url="https://db/other")
    sources = (HttpSource(url="https://h/a.tgz"), graphql, rest, unused, other_query)
    found = needs(
        [
            "configmap:suite-b/x.xosc",
            "configmap:suite-a/y.xosc",
            "configmap:suite-b/z.xosc",
            "graphql+https://db/graphql#1",
            "rest+https://db/api?x=1#2",
            "https://h/a.tgz#m.xosc",
            "file:///s/a.xosc",
            "not a uri",
        ],
        sources,
    )
    assert found.config_maps == ("suite-a", "suite-b")
    assert found.databases == (graphql, rest, other_query)
    assert needs(["https://h/a.tgz#m.xosc"], sources).databases == ()


def kubelet_volume(root: Path, name: str, data: dict[str, bytes]) -> Path:
    """A folder laid out like the kubelet's configMap volume: keys link into ``..data``."""
    folder = root / name
    stamp = folder / "..2026_11_24_10_00_00.000000001"
    stamp.mkdir(parents=True)
    for key, value in data.items():
        (stamp / key).write_bytes(value)
    (folder / "..data").symlink_to(stamp.name)
    for key in data:
        (folder / key).symlink_to(f"..data/{key}")
    return folder


def test_mounted_configmaps_read_a_kubelet_volume(tmp_path: Path) -> None:
    root = tmp_path / "configmaps"
    folder = kubelet_volume(root, "suite", {"a.xosc": b"A", "notes.txt": b"N"})
    (tmp_path / "secret").write_text("outside")
    (folder / "escape").symlink_to(tmp_path / "secret")
    reader = MountedConfigMaps(root)
    assert reader("suite") == {"a.xosc": b"A", "notes.txt": b"N"}
    ctx = FetchContext(base_dir=tmp_path, cache_dir=tmp_path / "cache", config_maps=reader)
    resolved = resolve(ConfigMapSource(name="suite"), ctx)
    assert resolved.files == ("a.xosc",)
    assert resolved.uris["a.xosc"] == "configmap:suite/a.xosc"
    located = Locator(ctx).locate(pin("configmap:suite/a.xosc", "A"))
    assert (located.parent / "notes.txt").read_text() == "N", "sibling keys (roads) come along"
    located = Locator(ctx).locate(pin("configmap:suite/notes.txt", "N", "notes.txt"))
    assert located.read_text() == "N"
    with pytest.raises(SourceError, match=r"ConfigMap 'suite' has no key 'b\.xosc' any more"):
        Locator(ctx).locate(pin("configmap:suite/b.xosc", "B", "b.xosc"))
    with pytest.raises(SourceError, match="ConfigMap 'gone' is not mounted in this pod"):
        reader("gone")
    with pytest.raises(SourceError, match="not a valid object name"):
        reader("../etc")


def test_mounted_configmaps_are_bounded(tmp_path: Path) -> None:
    root = tmp_path / "configmaps"
    kubelet_volume(root, "big", {"a.xosc": b"x" * 11})
    kubelet_volume(root, "many", {f"k{i}": b"x" for i in range(4)})
    with pytest.raises(SourceError, match=r"ConfigMap key big/a\.xosc is larger than 10 bytes"):
        MountedConfigMaps(root, SourceLimits(max_scenario_bytes=10))("big")
    with pytest.raises(SourceError, match="ConfigMap 'many': more than 3 keys"):
        MountedConfigMaps(root, SourceLimits(max_files=3))("many")
