"""Configuration of a real node: containerd, CNI bridge, kubelet (pure: paths in, text out).

The settings are those a kubeadm node uses, minus what this kind of machine cannot grant (see
docs/dev-cluster.md, "The real node"): no systemd (cgroupfs driver), cgroup v1 (accepted
explicitly), no CAP_SYS_RESOURCE (containerd must not lower OOM scores), no registry (the sandbox
image is imported, never pulled). Everything a node writes lives under its own folder, except the
two paths the kubelet hard-codes (``/var/lib/kubelet/device-plugins`` and
``/var/lib/kubelet/pod-resources`` are derived from ``--root-dir``; only the device-plugin
registration socket is fixed), so a node can be removed without a trace.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import yaml

CNI_BIN_DIR = Path("/usr/lib/cni")
"""Where Debian's ``containernetworking-plugins`` installs the plugins."""
DEVICE_PLUGIN_DIR = Path("/var/lib/kubelet/device-plugins")
"""The kubelet serves its device-plugin registration socket here whatever its ``--root-dir``."""
REAL_NODE_LABEL = "simtest.dev/real-node"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class NodeLayout:
    """Files of one real node under ``<cluster root>/nodes/<name>``."""

    root: Path
    name: str

    @property
    def containerd_config(self) -> Path:
        return self.root / "containerd.toml"

    @property
    def containerd_root(self) -> Path:
        """Content store and snapshots (the imported images)."""
        return self.root / "containerd"

    @property
    def containerd_state(self) -> Path:
        return self.root / "containerd-state"

    @property
    def socket(self) -> Path:
        """containerd's CRI/gRPC socket (what kubelet and crictl talk to)."""
        return self.root / "containerd.sock"

    @property
    def runc_root(self) -> Path:
        """runc's state: lists exactly this node's containers (``runc --root ... list``)."""
        return self.root / "runc"

    @property
    def cni_conf_dir(self) -> Path:
        return self.root / "cni" / "net.d"

    @property
    def cni_ipam_dir(self) -> Path:
        return self.root / "cni" / "ipam"

    @property
    def kubelet_dir(self) -> Path:
        """The kubelet's ``--root-dir`` (pods' volumes, plugins, checkpoints)."""
        return self.root / "kubelet"

    @property
    def kubelet_config(self) -> Path:
        return self.root / "kubelet-config.yaml"

    @property
    def kubelet_kubeconfig(self) -> Path:
        return self.root / "kubelet.kubeconfig"

    @property
    def pod_logs(self) -> Path:
        """Container logs (``kubectl logs`` reads them through the kubelet)."""
        return self.root / "pod-logs"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class NodeNetwork:
    """The node's pod network: a Linux bridge with one /24, the host as gateway."""

    bridge: str
    """Interface name (at most 15 characters), unique per cluster."""
    subnet: str
    """e.g. ``10.244.7.0/24``; pods get addresses from it, the bridge the first one."""

    @property
    def gateway(self) -> str:
        """The bridge's own address: how pods reach services listening on the host."""
        prefix = self.subnet.split("/", 1)[0].rsplit(".", 1)[0]
        return f"{prefix}.1"


def containerd_config(layout: NodeLayout, *, sandbox_image: str) -> str:
    """containerd 1.6 configuration (version 2 schema) for one node, as TOML text."""
    cri = 'plugins."io.containerd.grpc.v1.cri"'
    lines = [
        "# Written by simtest dev-cluster for one real node; see docs/dev-cluster.md.",
        "version = 2",
        f"root = {_toml(layout.containerd_root)}",
        f"state = {_toml(layout.containerd_state)}",
        # Only what a CRI node uses; the rest would log errors about missing kernel features.
        "disabled_plugins = ["
        + ", ".join(
            _toml(p)
            for p in (
                "io.containerd.snapshotter.v1.aufs",
                "io.containerd.snapshotter.v1.btrfs",
                "io.containerd.snapshotter.v1.devmapper",
                "io.containerd.snapshotter.v1.zfs",
                "io.containerd.tracing.processor.v1.otlp",
                "io.containerd.internal.v1.tracing",
            )
        )
        + "]",
        "",
        "[grpc]",
        f"  address = {_toml(layout.socket)}",
        "[ttrpc]",
        f"  address = {_toml(layout.socket.with_suffix('.sock.ttrpc'))}",
        "[metrics]",
        '  address = ""',
        "",
        f"[{cri}]",
        f"  sandbox_image = {_toml(sandbox_image)}",
        # The VM withholds CAP_SYS_RESOURCE: without this runc fails to set the -998 OOM score
        # the kubelet asks for ("can't get final child's PID from pipe").
        "  restrict_oom_score_adj = true",
        "  disable_apparmor = true",
        '  stream_server_address = "127.0.0.1"',
        '  stream_server_port = "0"',
        "  enable_unprivileged_ports = true",
        f"[{cri}.containerd]",
        '  snapshotter = "overlayfs"',
        '  default_runtime_name = "runc"',
        f"[{cri}.containerd.runtimes.runc]",
        '  runtime_type = "io.containerd.runc.v2"',
        f"[{cri}.containerd.runtimes.runc.options]",
        "  SystemdCgroup = false",
        f"  Root = {_toml(layout.runc_root)}",
        f"[{cri}.cni]",
        f"  bin_dir = {_toml(CNI_BIN_DIR)}",
        f"  conf_dir = {_toml(layout.cni_conf_dir)}",
        "  max_conf_num = 1",
        '[plugins."io.containerd.internal.v1.opt"]',
        f"  path = {_toml(layout.root / 'opt')}",
        "",
    ]
    return "\n".join(lines)


def cni_conflist(layout: NodeLayout, network: NodeNetwork) -> str:
    """The pod network: bridge + host-local IPAM, no masquerading (nothing leaves the machine)."""
    document = {
        "cniVersion": "0.4.0",
        "name": "simtest",
        "plugins": [
            {
                "type": "bridge",
                "bridge": network.bridge,
                "isGateway": True,
                "ipMasq": False,
                "hairpinMode": True,
                "ipam": {
                    "type": "host-local",
                    "ranges": [[{"subnet": network.subnet, "gateway": network.gateway}]],
                    "routes": [{"dst": "0.0.0.0/0"}],
                    "dataDir": str(layout.cni_ipam_dir),
                },
            }
        ],
    }
    return json.dumps(document, indent=2) + "\n"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class KubeletPorts:
    server: int
    healthz: int


def kubelet_config(
    layout: NodeLayout, *, network: NodeNetwork, ports: KubeletPorts, client_ca: Path
) -> str:
    """The KubeletConfiguration of one node, as YAML."""
    endpoint = f"unix://{layout.socket}"
    document: dict[str, Any] = {
        "apiVersion": "kubelet.config.k8s.io/v1beta1",
        "kind": "KubeletConfiguration",
        # The node's address (its bridge): reachable from this machine and its pods only.
        "address": network.gateway,
        "port": ports.server,
        "readOnlyPort": 0,
        "healthzBindAddress": "127.0.0.1",
        "healthzPort": ports.healthz,
        # Reached only from this machine; the apiserver has no kubelet client certificate here.
        "authentication": {
            "anonymous": {"enabled": True},
            "webhook": {"enabled": False},
            "x509": {"clientCAFile": str(client_ca)},
        },
        "authorization": {"mode": "AlwaysAllow"},
        "containerRuntimeEndpoint": endpoint,
        "imageServiceEndpoint": endpoint,
        # No systemd as PID 1, cgroup v1 hierarchies, no swap accounting: accept all three.
        "cgroupDriver": "cgroupfs",
        "failCgroupV1": False,
        "failSwapOn": False,
        # Pod and QoS cgroups (kubepods/...) as on any node: pod-level limits, and the kubelet's
        # in-place resize code path needs them (with cgroupsPerQOS off, kubelet 1.36.4 panics
        # in doPodResizeAction when a pod's sync is retried, e.g. after an image pull error).
        "cgroupsPerQOS": True,
        "enforceNodeAllocatable": ["pods"],
        "localStorageCapacityIsolation": False,
        "podLogsDir": str(layout.pod_logs),
        "volumePluginDir": str(layout.kubelet_dir / "volume-plugins"),
        "resolvConf": "",
        "clusterDomain": "cluster.local",
        "serializeImagePulls": False,
        # Images are imported, not pulled: never garbage-collect them.
        "imageGCHighThresholdPercent": 100,
        "imageGCLowThresholdPercent": 99,
        "evictionHard": {"memory.available": "100Mi", "nodefs.available": "1%"},
        "rotateCertificates": False,
        "serverTLSBootstrap": False,
        "maxPods": 110,
        "shutdownGracePeriod": "0s",
        "nodeStatusUpdateFrequency": "5s",
        "syncFrequency": "10s",
    }
    return yaml.safe_dump(document, sort_keys=True)


def kubelet_argv(
    binary: Path,
    layout: NodeLayout,
    *,
    network: NodeNetwork,
    labels: dict[str, str],
    verbosity: int = 1,
) -> list[str]:
    return [
        str(binary),
        f"--config={layout.kubelet_config}",
        f"--kubeconfig={layout.kubelet_kubeconfig}",
        f"--root-dir={layout.kubelet_dir}",
        f"--cert-dir={layout.kubelet_dir / 'pki'}",
        f"--hostname-override={layout.name}",
        f"--node-ip={network.gateway}",
        "--node-labels=" + ",".join(f"{k}={v}" for k, v in sorted(labels.items())),
        f"--v={verbosity}",
    ]


def containerd_argv(binary: Path, layout: NodeLayout) -> list[str]:
    return [str(binary), f"--config={layout.containerd_config}", "--log-level=warn"]


def _toml(value: object) -> str:
    """A TOML basic string (JSON's escaping is a subset TOML accepts)."""
    return json.dumps(str(value))
