"""Files the dev cluster writes, checked without starting it.

Covers: the PKI (the serving cert verifies against the CA for 127.0.0.1, tokens are stable across
calls and carry the right users/groups), kubeconfig rendering, fake-node manifests, the state
file round trip, and the kwok config (parses, keeps the node/pod stages, uses our annotations).
"""

from __future__ import annotations

import base64
import subprocess
from importlib import resources
from pathlib import Path

import yaml

from simtest_operator.devcluster import kubeconfig
from simtest_operator.devcluster.components import Ports
from simtest_operator.devcluster.nodes import (
    GPU_RESOURCE,
    KWOK_ANNOTATION,
    SIMULATOR_RESOURCE,
    NodeShape,
    node_manifest,
    node_names,
)
from simtest_operator.devcluster.pki import ensure_pki
from simtest_operator.devcluster.processes import ProcessRecord
from simtest_operator.devcluster.state import ClusterState


def test_serving_cert_verifies_for_loopback_and_tokens_are_stable(tmp_path: Path) -> None:
    pki = ensure_pki(tmp_path / "pki")
    result = subprocess.run(
        [
            "openssl",
            "verify",
            "-CAfile",
            str(pki.ca_cert),
            "-verify_ip",
            "127.0.0.1",
            str(pki.serving_cert),
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    again = ensure_pki(tmp_path / "pki")
    assert again.tokens == pki.tokens
    lines = pki.token_file.read_text().splitlines()
    admin = next(line for line in lines if line.startswith(pki.tokens["admin"] + ","))
    assert admin.endswith(',admin,admin,"system:masters"')
    assert pki.sa_pub.read_text().startswith("-----BEGIN PUBLIC KEY-----")


def test_kubeconfig_embeds_ca_and_token(tmp_path: Path) -> None:
    path = kubeconfig.write(
        tmp_path / "kc", server="https://127.0.0.1:6443", ca_pem=b"PEM", user="admin", token="t0k"
    )
    doc = yaml.safe_load(path.read_text())
    cluster = doc["clusters"][0]["cluster"]
    assert cluster["server"] == "https://127.0.0.1:6443"
    assert base64.b64decode(cluster["certificate-authority-data"]) == b"PEM"
    assert doc["users"][0]["user"] == {"token": "t0k"}
    assert doc["current-context"] == doc["contexts"][0]["name"]
    assert path.stat().st_mode & 0o077 == 0


def test_fake_node_advertises_simulator_and_gpu_capacity() -> None:
    names = node_names(3)
    assert names == ("simtest-node-0", "simtest-node-1", "simtest-node-2")
    node = node_manifest(names[0], NodeShape(simulator_slots=4, gpus=2))
    assert node["metadata"]["annotations"][KWOK_ANNOTATION] == "fake"
    for field in ("capacity", "allocatable"):
        assert node["status"][field][SIMULATOR_RESOURCE] == "4"
        assert node["status"][field][GPU_RESOURCE] == "2"
        assert {"cpu", "memory", "pods"} <= set(node["status"][field])


def test_state_round_trips(tmp_path: Path) -> None:
    state = ClusterState(
        server="https://127.0.0.1:1",
        ports=Ports.from_sequence((1, 2, 3, 4, 5, 6)),
        processes=(
            ProcessRecord(
                name="etcd", pid=10, start_ticks=99, argv=("etcd", "-x"), log=tmp_path / "etcd.log"
            ),
        ),
        nodes=("n0",),
        crds=("a.simtest.dev",),
        started_at=1.5,
        startup_seconds=12.0,
    )
    state.save(tmp_path / "state.json")
    assert ClusterState.from_json((tmp_path / "state.json").read_text()) == state


def test_kwok_config_keeps_node_stages_and_reads_simtest_annotations() -> None:
    text = resources.files("simtest_operator.devcluster").joinpath("kwok.yaml").read_text()
    docs = list(yaml.safe_load_all(text))
    assert docs[0]["kind"] == "KwokConfiguration"
    assert docs[0]["options"]["manageNodesWithAnnotationSelector"] == f"{KWOK_ANNOTATION}=fake"
    stages = {d["metadata"]["name"]: d for d in docs[1:]}
    assert all(d["kind"] == "Stage" for d in docs[1:])
    assert {
        "node-initialize",
        "node-heartbeat-with-lease",
        "pod-ready",
        "simtest-fake-finish",
        "pod-complete",
        "pod-delete",
    } == set(stages)
    finish = stages["simtest-fake-finish"]["spec"]
    assert "simtest.dev/fake-duration" in finish["delay"]["durationFrom"]["jq"]["expression"]
    template = finish["next"]["statusTemplate"]
    assert "simtest.dev/fake-exit-code" in template
    assert "simtest.dev/fake-termination-message" in template
    # kwok uses the jitter as the delay when jitter <= duration: never set one here.
    assert "jitterDurationMilliseconds" not in finish["delay"]
