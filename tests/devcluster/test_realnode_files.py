"""Files and choices of the real node, checked without starting it.

Covers: containerd's configuration is valid TOML whose paths all stay inside the node folder and
carries the settings this machine needs (OOM-score restriction, cgroupfs, imported sandbox image,
our CNI folder); the CNI conflist (bridge + host-local, no masquerading, gateway = node address);
the kubelet configuration (cgroup v1 accepted, cgroupfs, no image GC, its own ports on the node
address) and command line; the node's client certificate (``system:node:<name>`` in
``system:nodes``, signed by the cluster CA, client auth only); a node network never reuses a
routed subnet; the state file keeps the real node for ``down``.
"""

from __future__ import annotations

import ipaddress
import json
import subprocess
import tomllib
from pathlib import Path

import pytest
import yaml

from simtest_operator.devcluster import hostnet, nodeconfig
from simtest_operator.devcluster.components import Ports
from simtest_operator.devcluster.nodeconfig import KubeletPorts, NodeLayout, NodeNetwork
from simtest_operator.devcluster.pki import ensure_client_cert, ensure_pki
from simtest_operator.devcluster.realnodes import RealNode
from simtest_operator.devcluster.state import ClusterState

NETWORK = NodeNetwork(bridge="simtestabcdef01", subnet="10.244.9.0/24")


def _layout(tmp_path: Path) -> NodeLayout:
    return NodeLayout(root=tmp_path / "nodes" / "simtest-real-0", name="simtest-real-0")


def test_containerd_config_is_toml_inside_the_node_folder(tmp_path: Path) -> None:
    layout = _layout(tmp_path)
    config = tomllib.loads(nodeconfig.containerd_config(layout, sandbox_image="localhost/p:1"))
    assert config["version"] == 2
    for path in (config["root"], config["state"], config["grpc"]["address"]):
        assert Path(path).is_relative_to(layout.root)
    cri = config["plugins"]["io.containerd.grpc.v1.cri"]
    assert cri["sandbox_image"] == "localhost/p:1"
    assert cri["restrict_oom_score_adj"] is True
    runc = cri["containerd"]["runtimes"]["runc"]
    assert runc["options"]["SystemdCgroup"] is False
    assert Path(runc["options"]["Root"]) == layout.runc_root
    assert Path(cri["cni"]["conf_dir"]) == layout.cni_conf_dir


def test_cni_conflist_is_a_bridge_without_masquerading(tmp_path: Path) -> None:
    conflist = json.loads(nodeconfig.cni_conflist(_layout(tmp_path), NETWORK))
    (bridge,) = conflist["plugins"]
    assert bridge["type"] == "bridge" and bridge["bridge"] == NETWORK.bridge
    assert bridge["ipMasq"] is False
    (subnet,) = bridge["ipam"]["ranges"][0]
    assert subnet == {"subnet": "10.244.9.0/24", "gateway": "10.244.9.1"}
    assert Path(bridge["ipam"]["dataDir"]).is_relative_to(tmp_path)


def test_kubelet_config_and_command_line(tmp_path: Path) -> None:
    layout = _layout(tmp_path)
    ports = KubeletPorts(server=40001, healthz=40002)
    config = yaml.safe_load(
        nodeconfig.kubelet_config(layout, network=NETWORK, ports=ports, client_ca=tmp_path / "ca")
    )
    assert config["kind"] == "KubeletConfiguration"
    assert config["address"] == NETWORK.gateway and config["port"] == 40001
    assert config["failCgroupV1"] is False and config["cgroupDriver"] == "cgroupfs"
    assert config["imageGCHighThresholdPercent"] == 100
    assert config["containerRuntimeEndpoint"] == f"unix://{layout.socket}"
    argv = nodeconfig.kubelet_argv(
        Path("/bin/kubelet"), layout, network=NETWORK, labels={"a": "1", "b": "2"}
    )
    assert f"--node-ip={NETWORK.gateway}" in argv
    assert "--node-labels=a=1,b=2" in argv
    assert f"--root-dir={layout.kubelet_dir}" in argv


def test_node_client_certificate(tmp_path: Path) -> None:
    pki = ensure_pki(tmp_path / "pki")
    cert = ensure_client_cert(pki, name="node-x", user="system:node:x", groups=("system:nodes",))
    text = subprocess.run(
        ["openssl", "x509", "-in", str(cert.cert), "-noout", "-subject", "-ext",
         "extendedKeyUsage"],
        capture_output=True, text=True, check=True,
    ).stdout  # fmt: skip
    assert "O = system:nodes" in text and "CN = system:node:x" in text
    assert "TLS Web Client Authentication" in text
    verify = subprocess.run(
        ["openssl", "verify", "-CAfile", str(pki.ca_cert), str(cert.cert)],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert verify.returncode == 0, verify.stderr
    again = ensure_client_cert(pki, name="node-x", user="system:node:x", groups=("system:nodes",))
    assert again.cert.read_bytes() == cert.cert.read_bytes()


def test_node_network_avoids_routed_subnets(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    first = hostnet.pick_network(tmp_path, 0)
    taken = ipaddress.IPv4Network(first.subnet)
    monkeypatch.setattr(hostnet, "used_networks", lambda: {taken})
    second = hostnet.pick_network(tmp_path, 0)
    assert second.bridge == first.bridge  # derived from the cluster, stable
    assert second.subnet != first.subnet
    assert len(first.bridge) <= 15
    assert hostnet.pick_network(tmp_path / "other", 0).bridge != first.bridge


def test_state_file_keeps_the_real_node(tmp_path: Path) -> None:
    node = RealNode(
        name="simtest-real-0",
        root=tmp_path,
        network=NETWORK,
        ports=KubeletPorts(server=1, healthz=2),
    )
    state = ClusterState(
        server="https://127.0.0.1:1",
        ports=Ports.from_sequence((1, 2, 3, 4, 5, 6)),
        real_nodes=(node,),
    )
    assert ClusterState.from_json(state.to_json()).real_nodes == (node,)
