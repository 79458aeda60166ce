"""The frozen list and locating pinned files again.

Covers: source URI round trips for every kind (percent-encoded paths with ``#``/``@``/spaces),
malformed and escaping URIs refused; FrozenList JSON round trip, duplicate ids, malformed
documents; the Locator finding path, git, http-archive, http-file, graphql-content and ConfigMap
files, verifying sha256 (a changed file is an error naming both digests), and fetching an
archive only once per run.
"""

from __future__ import annotations

import hashlib
import io
import json
import subprocess
import tarfile
from pathlib import Path
from typing import Any

import pytest

from simtest_operator.errors import SourceError
from simtest_operator.scenarios import (
    ConfigMapSource,
    FetchContext,
    FrozenList,
    GitSource,
    GraphqlSource,
    HttpSource,
    Locator,
    PathSource,
    PinnedScenario,
    ResolvedSourceInfo,
    resolve,
    sha256_hex,
    uris,
)
from tests.scenarios.support import Routes, xosc

COMMIT = "a" * 40
FORMAT = "simtest.dev/frozen-list/v1"


@pytest.mark.parametrize(
    ("uri", "expected"),
    [
        ("file:///tmp/x%20y/a.xosc", uris.FileUri(path=Path("/tmp/x y/a.xosc"))),
        (
            uris.git_uri("https://h/r.git", COMMIT, "s/a #1@x.xosc"),
            uris.GitUri(url="https://h/r.git", commit=COMMIT, path="s/a #1@x.xosc"),
        ),
        (
            uris.git_uri("git@h:r@x.git", COMMIT, "a.xosc"),
            uris.GitUri(url="git@h:r@x.git", commit=COMMIT, path="a.xosc"),
        ),
        ("https://h/s.tgz#d/a%23b.xosc", uris.HttpUri(url="https://h/s.tgz", member="d/a#b.xosc")),
        ("https://h/a.xosc?x=1", uris.HttpUri(url="https://h/a.xosc?x=1")),
        (
            uris.graphql_uri("https://h/g", "c/1"),
            uris.GraphqlUri(endpoint="https://h/g", item="c/1"),
        ),
        (uris.configmap_uri("cm", "a.xosc"), uris.ConfigMapUri(name="cm", key="a.xosc")),
    ],
)
def test_uri_round_trips(uri: str, expected: uris.SourceUri) -> None:
    assert uris.parse(uri) == expected


@pytest.mark.parametrize(
    "uri",
    [
        "git+https://h/r.git@abc#a.xosc",  # short commit
        f"git+https://h/r.git@{COMMIT}#../a.xosc",
        "https://h/s.tgz#/etc/passwd",
        "https://h/s.tgz#a/../../b",
        "ftp://h/a.xosc",
        "file://otherhost/a.xosc",
        "graphql+ftp://x#1",
        "configmap:nokey",
    ],
)
def test_bad_uris(uri: str) -> None:
    with pytest.raises(SourceError):
        uris.parse(uri)


def test_frozen_list_json_round_trip() -> None:
    frozen = FrozenList(
        campaign="smoke",
        scenarios=(
            PinnedScenario(id="a.xosc", source="file:///a.xosc", sha256="1" * 64),
            PinnedScenario(id="d.xosc#2", source="file:///b.xosc", sha256="2" * 64,
                           overrides={"speed": "30", "gap": "2"}),
        ),
        sources=(ResolvedSourceInfo(kind="path", location="/x", files=2),),
        notes=("skipped 1 catalog",),
    )  # fmt: skip
    text = json.dumps(frozen.to_json())
    assert FrozenList.from_json(json.loads(text)) == frozen
    assert list(frozen.to_json()["scenarios"][1]["overrides"]) == ["gap", "speed"]
    assert frozen.subset({"d.xosc#2"}).scenarios == (frozen.scenarios[1],)


@pytest.mark.parametrize(
    ("document", "message"),
    [
        ({"format": "nope"}, "not a frozen scenario list"),
        ({"format": FORMAT, "scenarios": {}}, "must be a list"),
        ({"format": FORMAT, "scenarios": [{"id": "a"}]}, "no string 'source'"),
        (
            {"format": FORMAT,
             "scenarios": [{"id": "a", "source": "file:///a", "sha256": "xyz"}]},
            "64-hex",
        ),
        (
            {"format": FORMAT,
             "scenarios": [{"id": "a", "source": "file:///a", "sha256": "1" * 64}] * 2},
            "appears twice",
        ),
    ],
)  # fmt: skip
def test_malformed_frozen_lists(document: Any, message: str) -> None:
    with pytest.raises(SourceError, match=message):
        FrozenList.from_json(document)


def pin(resolved_uri: str, path: Path, ident: str = "s") -> PinnedScenario:
    return PinnedScenario(id=ident, source=resolved_uri, sha256=sha256_hex(path.read_bytes()))


def test_locate_path_and_detect_change(ctx: FetchContext) -> None:
    (ctx.base_dir / "a.xosc").write_text(xosc("one"))
    resolved = resolve(PathSource(path="."), ctx)
    pinned = pin(resolved.uris["a.xosc"], resolved.root / "a.xosc")
    locator = Locator(ctx)
    assert locator.locate(pinned) == ctx.base_dir / "a.xosc"
    (ctx.base_dir / "a.xosc").write_text(xosc("two"))
    with pytest.raises(SourceError, match="content changed since the list was frozen"):
        locator.locate(pinned)


def test_locate_git_from_a_fresh_cache(ctx: FetchContext, tmp_path: Path) -> None:
    repo = tmp_path / "repo"
    repo.mkdir()
    (repo / "a.xosc").write_text(xosc("git"))
    for args in (["init", "-q"], ["add", "-A"], ["commit", "-q", "-m", "x"]):
        subprocess.run(["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t",
                        *args], check=True)  # fmt: skip
    resolved = resolve(GitSource(url=str(repo)), ctx)
    pinned = pin(resolved.uris["a.xosc"], resolved.root / "a.xosc")
    elsewhere = FetchContext(base_dir=ctx.base_dir, cache_dir=tmp_path / "other-cache")
    found = Locator(elsewhere).locate(pinned)
    assert found.read_text() == xosc("git")
    assert found.is_relative_to(tmp_path / "other-cache")


def test_locate_http_archive_once_and_single_file(
    ctx: FetchContext, server: tuple[str, Routes]
) -> None:
    base, routes = server
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as tar:
        for name in ("a.xosc", "b.xosc"):
            data = xosc(name).encode()
            info = tarfile.TarInfo(name)
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
    routes.get["/s.tgz"] = (200, buffer.getvalue(), {})
    routes.get["/one.xosc"] = (200, xosc("one").encode(), {})
    archive = resolve(HttpSource(url=f"{base}/s.tgz"), ctx)
    single = resolve(HttpSource(url=f"{base}/one.xosc"), ctx)
    pins = [pin(archive.uris[n], archive.root / n, n) for n in archive.files]
    pins.append(pin(single.uris["one.xosc"], single.root / "one.xosc", "one"))
    routes.requests.clear()
    locator = Locator(ctx)
    assert [locator.locate(p).read_text() for p in pins] == [
        xosc("a.xosc"), xosc("b.xosc"), xosc("one"),
    ]  # fmt: skip
    assert [r[1] for r in routes.requests] == ["/s.tgz", "/one.xosc"], "each body fetched once"


def test_locate_graphql_content_and_configmap(
    ctx: FetchContext, server: tuple[str, Routes]
) -> None:
    base, routes = server
    body = {"data": {"s": [{"id": "x", "content": xosc("inline")}]}}
    routes.post = lambda *_: (200, json.dumps(body).encode())
    source = GraphqlSource(endpoint=f"{base}/g", query="{s}")
    resolved = resolve(source, ctx)
    pinned = pin(resolved.uris["x.xosc"], resolved.root / "x.xosc")
    assert Locator(ctx, graphql_sources=(source,)).locate(pinned).read_text() == xosc("inline")
    with pytest.raises(SourceError, match="no GraphQL source"):
        Locator(ctx).locate(pinned)
    data = {"a.xosc": b"<a/>", "raw": b"<b/>"}
    reading = FetchContext(
        base_dir=ctx.base_dir, cache_dir=ctx.cache_dir, config_maps=lambda name: data
    )
    cm = resolve(ConfigMapSource(name="cm", keys=("raw",)), reading)
    found = Locator(reading).locate(pin(cm.uris["raw"], cm.root / "raw"))
    assert found.read_bytes() == b"<b/>"
    assert hashlib.sha256(found.read_bytes()).hexdigest() == sha256_hex(b"<b/>")
