"""Real nodes: containerd + runc + the kubelet as local processes, registered with the dev cluster.

A real node runs pods in real containers (the kubelet drives containerd over CRI; runc makes the
containers; CNI's bridge plugin gives each pod its own network namespace) and enforces what fake
nodes only pretend: images, commands, volumes, security contexts, resource limits, deadlines.

Lifecycle, driven by :class:`~simtest_operator.devcluster.cluster.DevCluster`:

* :func:`prepare` writes the node's files (containerd and kubelet configuration, CNI conflist, a
  client certificate ``system:node:<name>`` and its kubeconfig) and creates its bridge;
* the cluster spawns containerd, :func:`import_images` loads the built images (OCI archives from
  ``deploy/docker/build.sh``), then the cluster spawns the kubelet and waits for the Node to be
  Ready;
* on ``down``, :func:`remove_pods` asks containerd (through ``crictl``) to stop and remove every
  pod sandbox while it still runs, so CNI ``DEL`` releases the addresses and network namespaces;
  after the processes stopped, :func:`clean_up` kills what outlived them (container shims),
  unmounts what is left under the node folder and removes the bridge.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import shutil
import signal
import socket
import subprocess
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from simtest_operator.devcluster import hostnet, kubeconfig, nodeconfig
from simtest_operator.devcluster.nodeconfig import (
    DEVICE_PLUGIN_DIR,
    KubeletPorts,
    NodeLayout,
    NodeNetwork,
)
from simtest_operator.devcluster.pki import Pki, ensure_client_cert
from simtest_operator.errors import ClusterError

NODE_NAME = "simtest-real-0"
"""The real node's name: one per machine (every kubelet serves device plugins at one fixed path)."""
SYSTEM_BINARIES = ("containerd", "containerd-shim-runc-v2", "runc", "ctr")
"""From Debian's ``containerd`` and ``runc`` packages (``deploy/setup.sh test`` installs them)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RealNode:
    """One real node of a cluster (persisted in the cluster's state file)."""

    name: str
    root: Path
    network: NodeNetwork
    ports: KubeletPorts

    @property
    def layout(self) -> NodeLayout:
        return NodeLayout(root=self.root, name=self.name)

    def to_json(self) -> dict[str, object]:
        return {
            "name": self.name,
            "root": str(self.root),
            "bridge": self.network.bridge,
            "subnet": self.network.subnet,
            "ports": dataclasses.asdict(self.ports),
        }

    @classmethod
    def from_json(cls, data: dict[str, object]) -> RealNode:
        ports = data["ports"]
        assert isinstance(ports, dict)
        return cls(
            name=str(data["name"]),
            root=Path(str(data["root"])),
            network=NodeNetwork(bridge=str(data["bridge"]), subnet=str(data["subnet"])),
            ports=KubeletPorts(**{k: int(v) for k, v in ports.items()}),
        )


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RealNodeSetup:
    """What ``up`` gives the real node: built images instead of registry pulls, and the objects
    it needs from the cluster (the chart's device plugin, so that it advertises slots)."""

    sandbox_image: str
    """Name of the pod-sandbox ("pause") image among the archives."""
    archives: tuple[Path, ...]
    addons: tuple[Mapping[str, Any], ...] = ()
    """Created once the node is Ready (:mod:`~simtest_operator.devcluster.addons`); with any,
    ``up`` waits until the node advertises simulator slots."""


def system_binary(name: str) -> Path:
    """A binary from the Debian packages, or a :class:`ClusterError` saying how to get it."""
    found = shutil.which(name, path=f"{os.environ.get('PATH', '')}:/usr/sbin:/sbin")
    if found is None:
        raise ClusterError(
            f"{name} is not installed; a real node needs Debian's containerd, runc and "
            "containernetworking-plugins (`bash deploy/setup.sh test` installs them)"
        )
    return Path(found)


def check_host() -> None:
    """Fail early, with the reason, where a real node cannot run."""
    if os.geteuid() != 0:
        raise ClusterError("a real node needs root (containerd, runc, network namespaces)")
    for name in SYSTEM_BINARIES:
        system_binary(name)
    if not (nodeconfig.CNI_BIN_DIR / "bridge").exists():
        raise ClusterError(
            f"CNI plugins missing in {nodeconfig.CNI_BIN_DIR}; install Debian's "
            "containernetworking-plugins (`bash deploy/setup.sh test`)"
        )
    registration = DEVICE_PLUGIN_DIR / "kubelet.sock"
    if _socket_answers(registration):
        raise ClusterError(
            f"another kubelet on this machine serves {registration} (every kubelet uses that "
            "fixed path for device plugins); stop it, or the dev cluster that started it, first"
        )


def prepare(node: RealNode, *, pki: Pki, server: str, sandbox_image: str) -> None:
    """Write the node's configuration and credentials and create its bridge."""
    layout = node.layout
    for folder in (layout.root, layout.cni_conf_dir, layout.cni_ipam_dir, layout.kubelet_dir):
        folder.mkdir(parents=True, exist_ok=True)
    layout.containerd_config.write_text(
        nodeconfig.containerd_config(layout, sandbox_image=sandbox_image)
    )
    (layout.cni_conf_dir / "10-simtest.conflist").write_text(
        nodeconfig.cni_conflist(layout, node.network)
    )
    layout.kubelet_config.write_text(
        nodeconfig.kubelet_config(
            layout, network=node.network, ports=node.ports, client_ca=pki.ca_cert
        )
    )
    user = f"system:node:{node.name}"
    cert = ensure_client_cert(pki, name=f"node-{node.name}", user=user, groups=("system:nodes",))
    kubeconfig.write(
        layout.kubelet_kubeconfig,
        server=server,
        ca_pem=pki.ca_cert.read_bytes(),
        user=user,
        client_cert=cert.cert,
        client_key=cert.key,
    )
    DEVICE_PLUGIN_DIR.mkdir(parents=True, exist_ok=True)
    hostnet.create_bridge(node.network)


def containerd_ready(node: RealNode) -> bool:
    """Whether containerd answers on the node's socket."""
    result = subprocess.run(
        [str(system_binary("ctr")), "--address", str(node.layout.socket), "version"],
        capture_output=True,
        check=False,
        timeout=10,
    )
    return result.returncode == 0


def import_images(node: RealNode, archives: Iterable[Path]) -> None:
    """Load OCI archives into the node's containerd (namespace ``k8s.io``, what CRI uses).

    This stands in for a registry pull: the kubelet then finds the images by name and, with
    ``imagePullPolicy: IfNotPresent``, never tries to pull them.
    """
    ctr = str(system_binary("ctr"))
    for archive in archives:
        result = subprocess.run(
            [ctr, "--address", str(node.layout.socket), "-n", "k8s.io", "images", "import",
             str(archive)],
            capture_output=True,
            text=True,
            check=False,
            timeout=600,
        )  # fmt: skip
        if result.returncode != 0:
            raise ClusterError(f"cannot import {archive} into {node.name}: {result.stderr.strip()}")


def remove_pods(node: RealNode, crictl: Path | None, *, timeout: float = 60.0) -> None:
    """Stop and remove every pod sandbox of the node through CRI (containerd must be running)."""
    if crictl is None or not node.layout.socket.exists():
        return
    with contextlib.suppress(subprocess.TimeoutExpired):
        subprocess.run(
            [
                str(crictl),
                "--runtime-endpoint",
                f"unix://{node.layout.socket}",
                "--timeout",
                "30s",
                "rmp",
                "--all",
                "--force",
            ],
            capture_output=True,
            check=False,
            timeout=timeout,
        )


def clean_up(node: RealNode) -> None:
    """After containerd and the kubelet stopped: nothing of the node may be left running/mounted."""
    layout = node.layout
    _kill_shims(layout.socket)
    _kill_containers(layout.runc_root)
    for mount in sorted(_mounts_under(layout.root), key=len, reverse=True):
        subprocess.run(["umount", "-l", mount], capture_output=True, check=False)
    for netns in _netns_of(layout):
        subprocess.run(["umount", "-l", str(netns)], capture_output=True, check=False)
        netns.unlink(missing_ok=True)
    hostnet.delete_bridge(node.network)


def _socket_answers(path: Path) -> bool:
    if not path.exists():
        return False
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as probe:
        probe.settimeout(1.0)
        try:
            probe.connect(str(path))
        except OSError:
            return False
    return True


def _proc_cmdlines() -> Iterable[tuple[int, Sequence[str]]]:
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            raw = (entry / "cmdline").read_bytes()
        except OSError:
            continue
        yield int(entry.name), raw.decode(errors="replace").split("\0")


def _kill_shims(socket_path: Path) -> None:
    """SIGKILL the runc shims started by this node's containerd (they name its socket)."""
    for pid, argv in _proc_cmdlines():
        if argv and argv[0].endswith("containerd-shim-runc-v2") and str(socket_path) in argv:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)


def _kill_containers(runc_root: Path) -> None:
    """Force-delete whatever runc still lists under this node's runc root."""
    if not runc_root.is_dir():
        return
    runc = str(system_binary("runc"))
    for namespace_root in runc_root.iterdir():
        for container in namespace_root.iterdir() if namespace_root.is_dir() else ():
            subprocess.run(
                [runc, "--root", str(namespace_root), "delete", "--force", container.name],
                capture_output=True,
                check=False,
            )


def _mounts_under(root: Path) -> list[str]:
    prefix = f"{root.resolve()}/"
    found = []
    for line in Path("/proc/self/mounts").read_text().splitlines():
        target = line.split(" ")[1].replace("\\040", " ")
        if target.startswith(prefix) or target == prefix.rstrip("/"):
            found.append(target)
    return found


def _netns_of(layout: NodeLayout) -> list[Path]:
    """Network namespaces containerd made for this node's pods and did not remove.

    Each pod sandbox's OCI spec (``config.json`` under this node's containerd state) names its
    namespace; only those are ours (containerd 1.6 puts them at ``/var/run/netns/cni-<uuid>``).
    """
    state = layout.containerd_state
    found: set[Path] = set()
    for spec in state.rglob("config.json") if state.is_dir() else ():
        with contextlib.suppress(OSError, ValueError):
            namespaces = json.loads(spec.read_text()).get("linux", {}).get("namespaces", [])
            found.update(
                Path(ns["path"])
                for ns in namespaces
                if ns.get("type") == "network" and ns.get("path")
            )
    return sorted(found)
