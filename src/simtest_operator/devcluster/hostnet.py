"""The host side of a real node's pod network: its bridge, made before and removed after the node.

The CNI bridge plugin would create the bridge on the first pod, but the kubelet needs the node's
address before that: it is the bridge's gateway address (a node address may not be loopback, and
the apiserver reaches the kubelet there for ``kubectl logs``). The plugin's ``DEL`` never removes
the bridge, so ``down`` does. Uses iproute2's ``ip`` (Debian ``iproute2``).
"""

from __future__ import annotations

import hashlib
import ipaddress
import shutil
import subprocess
from pathlib import Path

from simtest_operator.devcluster.nodeconfig import NodeNetwork
from simtest_operator.errors import ClusterError

POD_NETWORKS = ipaddress.IPv4Network("10.244.0.0/16")
"""Where node subnets are taken from, one free /24 per real node (as flannel's default)."""


def _ip(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    exe = shutil.which("ip")
    if exe is None:
        raise ClusterError("the `ip` command (Debian package iproute2) is needed for a real node")
    result = subprocess.run([exe, *args], capture_output=True, text=True, check=False)
    if check and result.returncode != 0:
        raise ClusterError(f"ip {' '.join(args)} failed: {result.stderr.strip()}")
    return result


def used_networks() -> set[ipaddress.IPv4Network]:
    """IPv4 networks routed on this machine now (other clusters' bridges among them)."""
    used = set()
    for line in _ip("-4", "route", "show").stdout.splitlines():
        target = line.split(" ", 1)[0]
        if target != "default":
            used.add(ipaddress.IPv4Network(target, strict=False))
    return used


def pick_network(cluster_root: Path, index: int) -> NodeNetwork:
    """A bridge name derived from the cluster (so two clusters never share one) and a free /24."""
    digest = hashlib.sha256(f"{cluster_root.resolve()}#{index}".encode()).hexdigest()
    used = used_networks()
    subnets = list(POD_NETWORKS.subnets(new_prefix=24))
    start = int(digest[:4], 16) % len(subnets)
    for offset in range(len(subnets)):
        subnet = subnets[(start + offset) % len(subnets)]
        if not any(subnet.overlaps(other) for other in used):
            return NodeNetwork(bridge=f"simtest{digest[:8]}", subnet=str(subnet))
    raise ClusterError(f"no free /24 left in {POD_NETWORKS} for a real node's pod network")


def create_bridge(network: NodeNetwork) -> None:
    """The bridge with the gateway address, up (idempotent)."""
    if _ip("link", "show", network.bridge, check=False).returncode != 0:
        _ip("link", "add", "name", network.bridge, "type", "bridge")
    prefix = network.subnet.split("/", 1)[1]
    addresses = _ip("-4", "addr", "show", "dev", network.bridge).stdout
    if f"inet {network.gateway}/" not in addresses:
        _ip("addr", "add", f"{network.gateway}/{prefix}", "dev", network.bridge)
    _ip("link", "set", network.bridge, "up")


def delete_bridge(network: NodeNetwork) -> bool:
    """Remove the bridge; True if it existed."""
    if _ip("link", "show", network.bridge, check=False).returncode != 0:
        return False
    _ip("link", "delete", network.bridge)
    return True
