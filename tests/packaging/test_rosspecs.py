"""The ROS package spec: what it accepts and how it refuses.

Covers: a full spec parses into typed fields (entrypoint as list or shell line, image as string
or mapping, sections, base); defaults (kind Deployment, appVersion = version, description); a table
of bad specs, each refused with a message naming the offending key.
"""

from __future__ import annotations

from pathlib import PurePosixPath

import pytest

from simtest_operator.errors import RenderError
from simtest_operator.packaging import rosspecs

MINIMAL = "name: bridge\nversion: 0.1.0\nimage: ghcr.io/acme/bridge:0.1.0\n"
DIGEST = "sha256:" + "ab" * 32


def test_full_spec_parses() -> None:
    spec = rosspecs.parse(
        "name: planner\nversion: 1.4.0\nappVersion: '2024.11'\nimage: {repository: r/p, "
        f"digest: '{DIGEST}'}}\nentrypoint: ros2 run planner 'node a'\nargs: [--x, 1]\n"
        "kind: Job\nparams: [config/a.yaml, b.yaml]\nros: {domainId: 4}\n"
        "dds: {peers: [a]}\nresources: {limits: {memory: 1Gi}}\ntemplates: k8s/t\n"
        "values: {env: {A: b}}\nbase: {version: 0.1.0, repository: oci://x/charts}\n"
    )
    assert spec.entrypoint == ("ros2", "run", "planner", "node a")
    assert spec.args == ("--x", "1")
    assert spec.image == {"digest": DIGEST, "repository": "r/p"}
    assert spec.kind == "Job" and spec.app_version == "2024.11"
    assert spec.params == (PurePosixPath("config/a.yaml"), PurePosixPath("b.yaml"))
    assert spec.templates == PurePosixPath("k8s/t")
    assert spec.sections == {
        "ros": {"domainId": 4},
        "dds": {"peers": ["a"]},
        "resources": {"limits": {"memory": "1Gi"}},
    }
    assert spec.values == {"env": {"A": "b"}}
    assert spec.base == rosspecs.BaseChart(version="0.1.0", repository="oci://x/charts")


def test_minimal_spec_gets_defaults() -> None:
    spec = rosspecs.parse(MINIMAL)
    assert spec.kind == "Deployment"
    assert spec.app_version == "0.1.0"
    assert spec.entrypoint == () and spec.params == () and spec.templates is None
    assert "bridge" in spec.description
    assert spec.base == rosspecs.BaseChart()


BAD = {
    "not a mapping": ("- a\n", "must be a mapping"),
    "invalid yaml": ("name: [\n", "not valid YAML"),
    "unknown key": (MINIMAL + "imagee: x\n", "unknown keys ['imagee']"),
    "missing name": ("version: 0.1.0\nimage: a:b\n", "name is required"),
    "upper-case name": (MINIMAL.replace("bridge", "Bridge"), "RFC 1123"),
    "long name": (MINIMAL.replace("bridge", "b" * 54), "at most 53"),
    "name not string": (MINIMAL.replace("name: bridge", "name: [a]"), "name must be a string"),
    "missing version": ("name: a\nimage: a:b\n", "version is required"),
    "bad version": (MINIMAL.replace("0.1.0", "1.0"), "not a SemVer"),
    "missing image": ("name: a\nversion: 0.1.0\n", "image is required"),
    "image with space": (MINIMAL.replace("ghcr.io/acme/bridge:0.1.0", "'a b'"), "whitespace"),
    "image no repository": ("name: a\nversion: 0.1.0\nimage: {tag: x}\n", "image.repository"),
    "image unknown key": (
        "name: a\nversion: 0.1.0\nimage: {repository: a, tg: x}\n",
        "unknown keys",
    ),
    "bad digest": ("name: a\nversion: 0.1.0\nimage: {repository: a, digest: md5:1}\n", "sha256"),
    "bad kind": (MINIMAL + "kind: StatefulSet\n", "kind must be one of"),
    "entrypoint mapping": (MINIMAL + "entrypoint: {a: b}\n", "entrypoint must be a list"),
    "entrypoint quote": (MINIMAL + 'entrypoint: "ros2 \'run"\n', "entrypoint:"),
    "params not list": (MINIMAL + "params: a.yaml\n", "params must be a list"),
    "params absolute": (MINIMAL + "params: [/etc/passwd]\n", "inside the spec's folder"),
    "params escape": (MINIMAL + "params: [../secret.yaml]\n", "inside the spec's folder"),
    "params bad name": (MINIMAL + "params: ['a b.yaml']\n", "not a valid ConfigMap key"),
    "params duplicate": (MINIMAL + "params: [a/p.yaml, b/p.yaml]\n", "share a file name"),
    "templates escape": (MINIMAL + "templates: ../t\n", "inside the spec's folder"),
    "ros not mapping": (MINIMAL + "ros: 3\n", "ros must be a mapping"),
    "values not mapping": (MINIMAL + "values: []\n", "values must be a mapping"),
    "base unknown": (MINIMAL + "base: {url: x}\n", "base must be a mapping"),
    "base bad version": (MINIMAL + "base: {version: latest}\n", "base.version"),
    "base bad repository": (MINIMAL + "base: {repository: ghcr.io/x}\n", "base.repository"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_specs_are_refused_with_the_key_named(case: str) -> None:
    text, message = BAD[case]
    with pytest.raises(RenderError) as caught:
        rosspecs.parse(text, source="package.yaml")
    assert message in str(caught.value)
    assert str(caught.value).startswith("package.yaml: ")
