"""Command lines of the five control-plane processes (pure: paths and ports in, argv out).

Flags follow what kubeadm, envtest and kwokctl's binary runtime use, trimmed for a throw-away
single-machine cluster: loopback only, etcd without fsync, no leader election, API priority and
fairness off (it only adds latency for a single client), and health endpoints of the
controller-manager and scheduler open without authentication so readiness can be polled.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from simtest_operator.devcluster.pki import Pki
from simtest_operator.devcluster.toolchain import Toolchain

HEALTH_PATHS = "/healthz,/readyz,/livez,/metrics"
SERVICE_CIDR = "10.96.0.0/16"
SA_ISSUER = "https://kubernetes.default.svc.cluster.local"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Ports:
    """Loopback ports of one cluster."""

    etcd_client: int
    etcd_peer: int
    apiserver: int
    controller_manager: int
    scheduler: int
    kwok: int

    @classmethod
    def from_sequence(cls, ports: tuple[int, ...]) -> Ports:
        names = [f.name for f in dataclasses.fields(cls)]
        return cls(**dict(zip(names, ports, strict=True)))

    def as_dict(self) -> dict[str, int]:
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Layout:
    """Files of one cluster under its root directory."""

    root: Path

    @property
    def pki(self) -> Path:
        return self.root / "pki"

    @property
    def logs(self) -> Path:
        return self.root / "logs"

    @property
    def etcd_data(self) -> Path:
        return self.root / "etcd-data"

    @property
    def kubeconfig(self) -> Path:
        """The admin kubeconfig (system:masters)."""
        return self.root / "kubeconfig"

    @property
    def state(self) -> Path:
        return self.root / "state.json"

    @property
    def kwok_config(self) -> Path:
        return self.root / "kwok.yaml"

    def component_kubeconfig(self, client: str) -> Path:
        return self.root / "kubeconfigs" / f"{client}.kubeconfig"

    def log(self, component: str) -> Path:
        return self.logs / f"{component}.log"


def etcd(tc: Toolchain, layout: Layout, ports: Ports) -> list[str]:
    client = f"http://127.0.0.1:{ports.etcd_client}"
    peer = f"http://127.0.0.1:{ports.etcd_peer}"
    return [
        str(tc.binary("etcd")),
        "--name=simtest",
        f"--data-dir={layout.etcd_data}",
        f"--listen-client-urls={client}",
        f"--advertise-client-urls={client}",
        f"--listen-peer-urls={peer}",
        f"--initial-advertise-peer-urls={peer}",
        f"--initial-cluster=simtest={peer}",
        "--unsafe-no-fsync=true",  # a test cluster: durability is not worth the fsync latency
        "--log-level=warn",
    ]


def kube_apiserver(tc: Toolchain, layout: Layout, ports: Ports, pki: Pki) -> list[str]:
    return [
        str(tc.binary("kube-apiserver")),
        f"--etcd-servers=http://127.0.0.1:{ports.etcd_client}",
        "--bind-address=127.0.0.1",
        "--advertise-address=127.0.0.1",
        f"--secure-port={ports.apiserver}",
        f"--cert-dir={layout.pki}",
        f"--tls-cert-file={pki.serving_cert}",
        f"--tls-private-key-file={pki.serving_key}",
        f"--client-ca-file={pki.ca_cert}",
        f"--token-auth-file={pki.token_file}",
        f"--service-account-issuer={SA_ISSUER}",
        f"--service-account-key-file={pki.sa_pub}",
        f"--service-account-signing-key-file={pki.sa_key}",
        f"--service-cluster-ip-range={SERVICE_CIDR}",
        "--authorization-mode=Node,RBAC",
        "--allow-privileged=true",
        # Nothing listens on the advertised address for pods, so do not maintain its endpoints.
        "--endpoint-reconciler-type=none",
        # Reach a real node's kubelet (logs, exec) at its address, as kubeadm configures it.
        "--kubelet-preferred-address-types=InternalIP,ExternalIP,Hostname",
        "--enable-priority-and-fairness=false",
        "--profiling=false",
        "--v=1",
    ]


def _controller_common(layout: Layout, client: str, port: int) -> list[str]:
    kubeconfig = layout.component_kubeconfig(client)
    return [
        f"--kubeconfig={kubeconfig}",
        f"--authentication-kubeconfig={kubeconfig}",
        f"--authorization-kubeconfig={kubeconfig}",
        f"--authorization-always-allow-paths={HEALTH_PATHS}",
        "--bind-address=127.0.0.1",
        f"--secure-port={port}",
        f"--cert-dir={layout.root / 'serving' / client}",
        "--leader-elect=false",
        "--profiling=false",
        "--v=1",
    ]


def kube_controller_manager(tc: Toolchain, layout: Layout, ports: Ports, pki: Pki) -> list[str]:
    return [
        str(tc.binary("kube-controller-manager")),
        *_controller_common(layout, "kube-controller-manager", ports.controller_manager),
        # Each controller acts as its own service account, as on kubeadm clusters.
        "--use-service-account-credentials=true",
        f"--service-account-private-key-file={pki.sa_key}",
        f"--root-ca-file={pki.ca_cert}",
        f"--cluster-signing-cert-file={pki.ca_cert}",
        f"--cluster-signing-key-file={pki.ca_key}",
        f"--service-cluster-ip-range={SERVICE_CIDR}",
        "--controllers=*",
    ]


def kube_scheduler(tc: Toolchain, layout: Layout, ports: Ports) -> list[str]:
    return [
        str(tc.binary("kube-scheduler")),
        *_controller_common(layout, "kube-scheduler", ports.scheduler),
    ]


def kwok(tc: Toolchain, layout: Layout, ports: Ports) -> list[str]:
    return [
        str(tc.binary("kwok")),
        f"--kubeconfig={layout.component_kubeconfig('kwok')}",
        f"--config={layout.kwok_config}",
        f"--server-address=127.0.0.1:{ports.kwok}",
    ]
