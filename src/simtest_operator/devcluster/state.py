"""The dev cluster's state file and the values ``up``/``status`` return.

``state.json`` in the cluster root is rewritten after every process start, so even an ``up``
that crashed half-way leaves a record that ``down`` can use to stop exactly what was started.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

from simtest_operator.devcluster.components import Ports
from simtest_operator.devcluster.processes import ProcessRecord
from simtest_operator.devcluster.realnodes import RealNode


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ClusterState:
    """What one ``up`` started (persisted as JSON)."""

    server: str
    ports: Ports
    processes: tuple[ProcessRecord, ...] = ()
    nodes: tuple[str, ...] = ()
    real_nodes: tuple[RealNode, ...] = ()
    """Nodes with a kubelet and containerd; ``down`` removes their pods, mounts and bridges."""
    crds: tuple[str, ...] = ()
    started_at: float = 0.0
    startup_seconds: float | None = None
    """Wall time of ``up`` until everything was ready; None while starting."""

    def to_json(self) -> str:
        data: dict[str, Any] = {
            "server": self.server,
            "ports": self.ports.as_dict(),
            "processes": [
                {**dataclasses.asdict(p), "argv": list(p.argv), "log": str(p.log)}
                for p in self.processes
            ],
            "nodes": list(self.nodes),
            "real_nodes": [node.to_json() for node in self.real_nodes],
            "crds": list(self.crds),
            "started_at": self.started_at,
            "startup_seconds": self.startup_seconds,
        }
        return json.dumps(data, indent=2) + "\n"

    @classmethod
    def from_json(cls, text: str) -> ClusterState:
        data = json.loads(text)
        return cls(
            server=data["server"],
            ports=Ports(**data["ports"]),
            processes=tuple(
                ProcessRecord(
                    name=p["name"],
                    pid=p["pid"],
                    start_ticks=p["start_ticks"],
                    argv=tuple(p["argv"]),
                    log=Path(p["log"]),
                )
                for p in data["processes"]
            ),
            nodes=tuple(data["nodes"]),
            real_nodes=tuple(RealNode.from_json(n) for n in data.get("real_nodes", ())),
            crds=tuple(data["crds"]),
            started_at=data["started_at"],
            startup_seconds=data["startup_seconds"],
        )

    def save(self, path: Path) -> None:
        tmp = path.with_suffix(".tmp")
        tmp.write_text(self.to_json())
        tmp.replace(path)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ClusterInfo:
    """How to reach a running dev cluster."""

    root: Path
    kubeconfig: Path
    """Admin kubeconfig (user ``admin`` in ``system:masters``), CA embedded."""
    server: str
    """``https://127.0.0.1:<port>``."""
    token: str
    """The admin bearer token (the same one the kubeconfig holds)."""
    ca_file: Path
    """CA of the apiserver's serving certificate."""
    logs_dir: Path
    nodes: tuple[str, ...]
    crds: tuple[str, ...]
    real_nodes: tuple[str, ...] = ()
    """Names of the nodes with a real kubelet (after the fake ones in ``nodes``)."""
    ports: Ports
    startup_seconds: float | None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ComponentStatus:
    name: str
    pid: int
    alive: bool
    log: Path


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ClusterStatus:
    """What ``status`` found."""

    root: Path
    started: bool
    """A state file exists (``up`` ran and ``down`` did not)."""
    server: str | None
    apiserver_ready: bool
    components: tuple[ComponentStatus, ...] = ()

    @property
    def running(self) -> bool:
        """Every component alive and the apiserver answering ``/readyz``."""
        return self.started and self.apiserver_ready and all(c.alive for c in self.components)
