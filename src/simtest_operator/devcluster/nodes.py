"""Fake nodes: Node objects that the kwok controller keeps Ready and runs pods on.

A fake node is just a Node created with its capacity in ``status`` (as a kubelet would register
it) and the ``kwok.x-k8s.io/node: fake`` annotation that our kwok config manages. The scheduler
fits pods against that capacity for real, including the extended resources ``nvidia.com/gpu``
and ``simtest.dev/simulator`` (one unit = one concurrently running simulator pod).
"""

from __future__ import annotations

import dataclasses
from typing import Any

SIMULATOR_RESOURCE = "simtest.dev/simulator"
GPU_RESOURCE = "nvidia.com/gpu"
KWOK_ANNOTATION = "kwok.x-k8s.io/node"
FAKE_NODE_LABEL = "simtest.dev/fake-node"
NAME_PREFIX = "simtest-node-"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class NodeShape:
    """Capacity every fake node advertises."""

    simulator_slots: int = 3
    """``simtest.dev/simulator`` units: how many simulator pods fit on the node at once."""
    gpus: int = 1
    cpu: str = "16"
    memory: str = "64Gi"
    pods: int = 110

    def capacity(self) -> dict[str, str]:
        return {
            "cpu": self.cpu,
            "memory": self.memory,
            "pods": str(self.pods),
            GPU_RESOURCE: str(self.gpus),
            SIMULATOR_RESOURCE: str(self.simulator_slots),
        }


def node_names(count: int) -> tuple[str, ...]:
    return tuple(f"{NAME_PREFIX}{i}" for i in range(count))


def node_manifest(name: str, shape: NodeShape) -> dict[str, Any]:
    """One fake Node, status included (kwok's node-initialize stage keeps the capacity)."""
    return {
        "apiVersion": "v1",
        "kind": "Node",
        "metadata": {
            "name": name,
            "annotations": {KWOK_ANNOTATION: "fake", "node.alpha.kubernetes.io/ttl": "0"},
            "labels": {
                "kubernetes.io/hostname": name,
                "kubernetes.io/os": "linux",
                "kubernetes.io/arch": "amd64",
                "type": "kwok",
                FAKE_NODE_LABEL: "true",
            },
        },
        "status": {"capacity": shape.capacity(), "allocatable": shape.capacity()},
    }


def is_ready(node: dict[str, Any]) -> bool:
    """Whether a Node (as a dict) has condition Ready=True."""
    conditions = (node.get("status") or {}).get("conditions") or []
    return any(c.get("type") == "Ready" and c.get("status") == "True" for c in conditions)
