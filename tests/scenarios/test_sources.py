"""Resolving each source kind against real local infrastructure (folders, git repos, HTTP server).

Covers: path sources (folder, single file, relative to the manifest, missing, hidden folders and
escaping symlinks skipped); git sources (local path and file:// URL, branch/tag/commit revisions,
sub-folder, commit pinned into the URI, a repository symlink escaping its tree refused, ``ext::``
and option-like URLs refused, unknown revision); http sources (single file, tar.gz and zip
archives, sha256 check, 404, download size limit, redirect to a non-HTTP scheme); GraphQL (url and
inline-content items, bearer token from the provider, variables, query errors, malformed
responses, missing provider); ConfigMap (injected reader, missing reader with a clear message).
"""

from __future__ import annotations

import hashlib
import io
import json
import subprocess
import tarfile
import zipfile
from pathlib import Path
from typing import Any

import pytest

from simtest_operator.errors import SourceError
from simtest_operator.scenarios import (
    ConfigMapSource,
    FetchContext,
    GitSource,
    GraphqlSource,
    HttpSource,
    PathSource,
    SecretRef,
    SourceLimits,
    gitfetching,
    resolve,
    uris,
)
from tests.scenarios.support import Routes, xosc


def git(repo: Path, *args: str) -> str:
    done = subprocess.run(
        ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t", *args],
        check=True, capture_output=True, text=True,
    )  # fmt: skip
    return done.stdout.strip()


@pytest.fixture
def repo(tmp_path: Path) -> Path:
    """A repository with two commits on main, a tag v1 on the first and a branch 'next'."""
    path = tmp_path / "repo"
    path.mkdir()
    git(path, "init", "-q", "-b", "main")
    (path / "suite").mkdir()
    (path / "suite/a.xosc").write_text(xosc("a v1"))
    (path / "README").write_text("readme")
    git(path, "add", "-A")
    git(path, "commit", "-q", "-m", "one")
    git(path, "tag", "v1")
    (path / "suite/a.xosc").write_text(xosc("a v2"))
    (path / "suite/b.xosc").write_text(xosc("b"))
    git(path, "add", "-A")
    git(path, "commit", "-q", "-m", "two")
    git(path, "branch", "next", "v1")
    return path


# --- path ----------------------------------------------------------------------------------------


def test_path_folder_relative_to_manifest(ctx: FetchContext) -> None:
    suite = ctx.base_dir / "suite"
    (suite / "sub").mkdir(parents=True)
    (suite / "a.xosc").write_text(xosc())
    (suite / "sub/b.xosc").write_text(xosc())
    (suite / ".git").mkdir()
    (suite / ".git/c.xosc").write_text(xosc())
    (suite / "out.xosc").symlink_to(ctx.base_dir.parent)  # a folder outside: skipped
    resolved = resolve(PathSource(path="suite"), ctx)
    assert resolved.files == ("a.xosc", "sub/b.xosc")
    assert resolved.uris["sub/b.xosc"] == (suite / "sub/b.xosc").as_uri()
    assert resolved.info.kind == "path" and resolved.info.files == 2


def test_path_single_file_and_missing(ctx: FetchContext) -> None:
    (ctx.base_dir / "one.xosc").write_text(xosc())
    resolved = resolve(PathSource(path="one.xosc"), ctx)
    assert resolved.files == ("one.xosc",)
    with pytest.raises(SourceError, match="does not exist"):
        resolve(PathSource(path="nope"), ctx)


# --- git -----------------------------------------------------------------------------------------


def test_git_local_path_head_pins_commit(ctx: FetchContext, repo: Path) -> None:
    head = git(repo, "rev-parse", "HEAD")
    resolved = resolve(GitSource(url=str(repo), path="suite"), ctx)
    assert resolved.info.revision == head
    assert resolved.files == ("a.xosc", "b.xosc")
    assert "a v2" in (resolved.root / "a.xosc").read_text()
    uri = uris.parse(resolved.uris["a.xosc"])
    assert isinstance(uri, uris.GitUri)
    assert (uri.url, uri.commit, uri.path) == (repo.as_uri(), head, "suite/a.xosc")


@pytest.mark.parametrize("revision", ["v1", "next", "COMMIT"])
def test_git_revisions(ctx: FetchContext, repo: Path, revision: str) -> None:
    first = git(repo, "rev-parse", "v1^{commit}")
    if revision == "COMMIT":
        revision = first
    resolved = resolve(GitSource(url=repo.as_uri(), revision=revision, path="suite"), ctx)
    assert resolved.info.revision == first
    assert resolved.files == ("a.xosc",)
    assert "a v1" in (resolved.root / "a.xosc").read_text()


def test_git_over_dumb_http_resolves_a_branch(
    ctx: FetchContext, repo: Path, server: tuple[str, Routes], tmp_path: Path
) -> None:
    # A repository served as plain files (git's "dumb" HTTP) cannot answer a shallow fetch.
    bare = tmp_path / "suite.git"
    subprocess.run(["git", "clone", "-q", "--bare", str(repo), str(bare)], check=True)
    git(bare, "update-server-info")
    base, routes = server
    for file in bare.rglob("*"):
        if file.is_file():
            routes.get[f"/suite.git/{file.relative_to(bare).as_posix()}"] = (
                200, file.read_bytes(), {}
            )  # fmt: skip
    refs = routes.get["/suite.git/info/refs"]
    routes.get["/suite.git/info/refs?service=git-upload-pack"] = refs  # not smart: dumb fallback
    resolved = resolve(GitSource(url=f"{base}/suite.git", revision="main", path="suite"), ctx)
    assert resolved.info.revision == git(repo, "rev-parse", "main")
    assert resolved.files == ("a.xosc", "b.xosc")


def test_git_unknown_revision_and_folder(ctx: FetchContext, repo: Path) -> None:
    with pytest.raises(SourceError, match="git failed"):
        resolve(GitSource(url=str(repo), revision="no-such-branch"), ctx)
    with pytest.raises(SourceError, match="does not exist"):
        resolve(GitSource(url=str(repo), path="missing"), ctx)


def test_git_errors_show_the_cause_in_one_line(ctx: FetchContext, tmp_path: Path) -> None:
    # Issue 12: only git's last stderr line was shown, e.g. "and the repository exists.".
    not_a_repo = tmp_path / "plain-folder"
    not_a_repo.mkdir()
    with pytest.raises(SourceError) as caught:
        resolve(GitSource(url=str(not_a_repo)), ctx)
    message = str(caught.value)
    assert "does not appear to be a git repository" in message, message
    assert "Could not read from remote repository" in message
    assert "\n" not in message and "Please make sure" not in message
    with pytest.raises(SourceError) as caught:
        resolve(GitSource(url="https://bot:hunter2@127.0.0.1:1/suite.git"), ctx)
    message = str(caught.value)
    assert "unable to access" in message and "hunter2" not in message, message


def test_git_stderr_summary() -> None:
    summary = gitfetching.stderr_summary(
        "Cloning into 'x'...\nfatal: 'r' does not appear to be a git repository\n"
        "fatal: Could not read from remote repository.\n\nPlease make sure you have the "
        "correct access rights\nand the repository exists.\n"
    )
    assert summary == (
        "fatal: 'r' does not appear to be a git repository; "
        "fatal: Could not read from remote repository."
    )
    assert gitfetching.stderr_summary("something odd\nhappened\n") == "something odd; happened"
    assert gitfetching.stderr_summary("") == ""
    assert len(gitfetching.stderr_summary("fatal: " + "x" * 2000)) == 500


def test_git_repository_symlink_escaping_is_refused(ctx: FetchContext, repo: Path) -> None:
    (repo / "suite/evil.xosc").symlink_to("../../../../etc/passwd")
    git(repo, "add", "-A")
    git(repo, "commit", "-q", "-m", "evil")
    with pytest.raises(SourceError, match="escapes the archive folder"):
        resolve(GitSource(url=str(repo)), ctx)


@pytest.mark.parametrize("url", ["ext::sh -c touch% /tmp/pwned", "-uhack", "ftp://x/y"])
def test_git_dangerous_urls_are_refused(ctx: FetchContext, url: str) -> None:
    with pytest.raises(SourceError):
        resolve(GitSource(url=url), ctx)
    assert not Path("/tmp/pwned").exists()


# --- http ----------------------------------------------------------------------------------------


def tgz(files: dict[str, bytes]) -> bytes:
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as tar:
        for name, data in files.items():
            info = tarfile.TarInfo(name)
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
    return buffer.getvalue()


def zipped(files: dict[str, bytes]) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for name, data in files.items():
            archive.writestr(name, data)
    return buffer.getvalue()


def test_http_single_file(ctx: FetchContext, server: tuple[str, Routes]) -> None:
    base, routes = server
    body = xosc("single").encode()
    routes.get["/s/cut%20in.xosc"] = (200, body, {})
    resolved = resolve(HttpSource(url=f"{base}/s/cut%20in.xosc"), ctx)
    assert resolved.files == ("cut_in.xosc",)
    assert resolved.uris["cut_in.xosc"] == f"{base}/s/cut%20in.xosc"
    assert resolved.info.revision == hashlib.sha256(body).hexdigest()


@pytest.mark.parametrize("pack", [tgz, zipped])
def test_http_archive_with_sha256(ctx: FetchContext, server: tuple[str, Routes], pack: Any) -> None:
    base, routes = server
    data = pack({"suite/a.xosc": xosc("a").encode(), "suite/roads/r.xodr": b"<OpenDRIVE/>"})
    routes.get["/suite.bin"] = (200, data, {})
    digest = hashlib.sha256(data).hexdigest()
    resolved = resolve(HttpSource(url=f"{base}/suite.bin", sha256=digest), ctx)
    assert resolved.files == ("suite/a.xosc", "suite/roads/r.xodr")
    assert resolved.uris["suite/a.xosc"] == f"{base}/suite.bin#suite/a.xosc"
    with pytest.raises(SourceError, match="differs from the expected"):
        resolve(HttpSource(url=f"{base}/suite.bin", sha256="0" * 64), ctx)


def test_http_errors_and_limits(tmp_path: Path, server: tuple[str, Routes]) -> None:
    base, routes = server
    small = FetchContext(
        base_dir=tmp_path, cache_dir=tmp_path / "c", limits=SourceLimits(max_download_bytes=1000)
    )
    with pytest.raises(SourceError, match="HTTP 404"):
        resolve(HttpSource(url=f"{base}/missing.xosc"), small)
    routes.get["/big.xosc"] = (200, b"x" * 5000, {})
    with pytest.raises(SourceError, match="exceeds the 1000 byte limit"):
        resolve(HttpSource(url=f"{base}/big.xosc"), small)
    # A server that does not say how big the body is gets cut off while streaming.
    routes.get["/unsized.xosc"] = (200, b"x" * 5000, {"Content-Length": "omit"})
    with pytest.raises(SourceError, match="exceeds the 1000 byte limit"):
        resolve(HttpSource(url=f"{base}/unsized.xosc"), small)
    for target in ("file:///etc/passwd", "ftp://example.invalid/x.xosc"):
        routes.get["/redirect.xosc"] = (302, b"", {"Location": target})
        with pytest.raises(SourceError, match=r"non-HTTP|not allowed"):
            resolve(HttpSource(url=f"{base}/redirect.xosc"), small)
    assert not list((tmp_path / "c/http").glob("*/*")), "nothing left behind"


# --- graphql -------------------------------------------------------------------------------------


def test_graphql_items_token_and_variables(ctx: FetchContext, server: tuple[str, Routes]) -> None:
    base, routes = server
    routes.get["/files/remote.xosc"] = (200, xosc("remote").encode(), {})
    seen: list[Any] = []

    def answer(path: str, headers: dict[str, str], payload: Any) -> tuple[int, bytes]:
        seen.append((path, headers.get("Authorization"), payload))
        items = [
            {"id": "cut-in/001", "content": xosc("inline")},
            {"id": 7, "url": f"{base}/files/remote.xosc"},
        ]
        return 200, json.dumps({"data": {"scenarios": {"nodes": items}}}).encode()

    routes.post = answer
    source = GraphqlSource(
        endpoint=f"{base}/graphql", query="query($c: String) { scenarios(category: $c) { id } }",
        variables={"c": "cut-in"}, secret=SecretRef(name="db", key="token"),
    )  # fmt: skip
    secrets = {SecretRef(name="db", key="token"): "s3cret"}
    with_secrets = FetchContext(
        base_dir=ctx.base_dir, cache_dir=ctx.cache_dir, secrets=lambda ref: secrets[ref]
    )
    resolved = resolve(source, with_secrets)
    assert resolved.files == ("7.xosc", "cut-in/001.xosc")
    assert resolved.uris["cut-in/001.xosc"] == f"graphql+{base}/graphql#cut-in/001"
    assert resolved.uris["7.xosc"] == f"{base}/files/remote.xosc"
    assert "inline" in (resolved.root / "cut-in/001.xosc").read_text()
    assert seen[0][1] == "Bearer s3cret"
    assert seen[0][2]["variables"] == {"c": "cut-in"}
    with pytest.raises(SourceError, match="no secret provider"):
        resolve(source, ctx)


@pytest.mark.parametrize(
    ("document", "message"),
    [
        ({"errors": [{"message": "bad field"}]}, "query failed: bad field"),
        ({"data": {"a": [], "b": []}}, "exactly one field"),
        ({"data": {"a": 5}}, "not a list"),
        ({"data": {"a": [{"id": "x"}]}}, "exactly one of 'url' or 'content'"),
        ({"data": {"a": [{"id": "x", "url": "file:///etc/passwd"}]}}, "not an http"),
        ({"data": {"a": [{"id": "../x", "content": "<a/>"}]}}, "outside"),
        ({"data": {"a": [{"id": "x", "content": "a"}, {"id": "x", "content": "b"}]}}, "twice"),
    ],
)
def test_graphql_bad_responses(
    ctx: FetchContext, server: tuple[str, Routes], document: Any, message: str
) -> None:
    base, routes = server
    routes.post = lambda *_: (200, json.dumps(document).encode())
    with pytest.raises(SourceError, match=message):
        resolve(GraphqlSource(endpoint=f"{base}/graphql", query="{a}"), ctx)


def test_graphql_token_never_in_errors(ctx: FetchContext, server: tuple[str, Routes]) -> None:
    base, routes = server
    routes.post = lambda *_: (500, b"boom")
    with_secrets = FetchContext(
        base_dir=ctx.base_dir, cache_dir=ctx.cache_dir, secrets=lambda ref: "t0ken-value"
    )
    source = GraphqlSource(endpoint=f"{base}/g", query="{a}", secret=SecretRef(name="s", key="k"))
    with pytest.raises(SourceError) as caught:
        resolve(source, with_secrets)
    assert "t0ken-value" not in str(caught.value)


# --- configMap -----------------------------------------------------------------------------------


def test_configmap_needs_a_reader(ctx: FetchContext) -> None:
    with pytest.raises(SourceError, match="needs a Kubernetes cluster"):
        resolve(ConfigMapSource(name="suite"), ctx)
    data = {"a.xosc": xosc("a").encode(), "notes.txt": b"n", "b.xosc": xosc("b").encode()}
    reading = FetchContext(
        base_dir=ctx.base_dir, cache_dir=ctx.cache_dir, config_maps=lambda name: data
    )
    resolved = resolve(ConfigMapSource(name="suite"), reading)
    assert resolved.files == ("a.xosc", "b.xosc")
    assert resolved.uris["a.xosc"] == "configmap:suite/a.xosc"
    with pytest.raises(SourceError, match="no key"):
        resolve(ConfigMapSource(name="suite", keys=("zzz.xosc",)), reading)
