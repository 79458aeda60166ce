"""Kueue in the dev cluster, without starting it: the CRDs it installs, its bootstrap objects,
its Configuration and command line.

Covers: the five CRDs Kueue's certificate rotator injects its CA into get the conversion
webhook stanza (without it the rotator never reports ready and the manager never starts), the
others stay as the module ships them; the Secret and the two webhook configurations it expects
exist and register no webhook; the Configuration keeps every listener on loopback, turns leader
election and the metrics listener off, manages certificates internally into the cluster's own
folder, and enables fair sharing; the CRDs from a built toolchain parse (when Kueue is built).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.devcluster import kueue
from simtest_operator.devcluster.components import Layout
from simtest_operator.errors import ToolchainError
from simtest_operator.settings import Settings


def _crd(name: str) -> dict[str, object]:
    return {"kind": "CustomResourceDefinition", "metadata": {"name": name}, "spec": {"group": "g"}}


def test_conversion_stanza_only_where_the_rotator_injects() -> None:
    workloads = kueue.with_conversion(_crd("workloads.kueue.x-k8s.io"))
    conversion = workloads["spec"]["conversion"]  # type: ignore[index]
    assert conversion["strategy"] == "Webhook"
    assert conversion["webhook"]["clientConfig"]["service"] == {
        "namespace": "kueue-system",
        "name": "kueue-webhook-service",
        "path": "/convert",
    }
    flavors = _crd("resourceflavors.kueue.x-k8s.io")
    assert kueue.with_conversion(flavors) is flavors


def test_bootstrap_objects_register_no_webhook() -> None:
    objects = {(o["kind"], o["metadata"]["name"]): o for o in kueue.bootstrap_objects()}
    assert ("Namespace", "kueue-system") in objects
    assert ("Secret", "kueue-webhook-server-cert") in objects
    for kind in ("Validating", "Mutating"):
        config = objects[
            (f"{kind}WebhookConfiguration", f"kueue-{kind.lower()}-webhook-configuration")
        ]
        assert config["webhooks"] == []


def test_configuration_stays_on_loopback_in_the_cluster_folder(tmp_path: Path) -> None:
    layout = Layout(root=tmp_path)
    config = kueue.configuration(layout, health_port=4001, webhook_port=4002)
    assert config["health"] == {"healthProbeBindAddress": "127.0.0.1:4001"}
    assert config["webhook"] == {
        "host": "127.0.0.1",
        "port": 4002,
        "certDir": str(tmp_path / "kueue" / "certs"),
    }
    assert config["metrics"] == {"bindAddress": "0"}
    assert config["leaderElection"] == {"leaderElect": False}
    assert config["internalCertManagement"]["enable"] is True
    assert "preemptionStrategies" in config["fairSharing"]
    path = kueue.write_config(layout, health_port=4001, webhook_port=4002)
    argv = kueue.argv(Path("/bin/kueue"), layout, tmp_path / "k.kubeconfig")
    assert f"--config={path}" in argv and "--feature-gates=VisibilityOnDemand=false" in argv


def test_crds_of_the_built_toolchain() -> None:
    binary = Settings.from_env().cache.toolchain / "bin" / "kueue"
    if not binary.exists():
        pytest.skip("Kueue is not built (bash deploy/devcluster/build.sh kueue)")
    names = {d["metadata"]["name"] for d in kueue.crd_documents(binary)}
    assert {"workloads.kueue.x-k8s.io", "clusterqueues.kueue.x-k8s.io"} <= names
    with pytest.raises(ToolchainError, match="no Kueue CRDs"):
        kueue.crd_documents(Path("/nonexistent/bin/kueue"))
