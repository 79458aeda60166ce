"""``DevCluster``: a real control plane (etcd, apiserver, controller-manager, scheduler, kwok) as
local processes on loopback, for tests and local development.

We start the processes ourselves instead of through ``kwokctl create cluster --runtime binary``:
that gives us every flag (etcd without fsync, API priority and fairness off, RBAC users per
component, our own kwok stages), the exact pids for ``down``, per-component logs, and readiness
checks that fail fast with the log tail when a component dies. See docs/dev-cluster.md.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import shutil
import subprocess
import time
from importlib import resources
from pathlib import Path

from simtest_operator.devcluster import (
    addons,
    components,
    hostnet,
    kubeconfig,
    kueue,
    provisioning,
    realnodes,
)
from simtest_operator.devcluster.components import Layout, Ports
from simtest_operator.devcluster.nodeconfig import (
    REAL_NODE_LABEL,
    KubeletPorts,
    containerd_argv,
    kubelet_argv,
)
from simtest_operator.devcluster.nodes import NodeShape, node_names
from simtest_operator.devcluster.pki import Pki, ensure_pki
from simtest_operator.devcluster.processes import (
    ProcessRecord,
    free_ports,
    is_alive,
    port_in_use,
    spawn,
    stop,
)
from simtest_operator.devcluster.readiness import http_ok, wait_until
from simtest_operator.devcluster.realnodes import RealNode, RealNodeSetup
from simtest_operator.devcluster.state import (
    ClusterInfo,
    ClusterState,
    ClusterStatus,
    ComponentStatus,
)
from simtest_operator.devcluster.toolchain import CONTROL_PLANE_BINARIES, Toolchain
from simtest_operator.errors import ClusterError, ToolchainError

COMPONENT_USERS = ("kube-controller-manager", "kube-scheduler", "kwok", "kueue")


class DevCluster:
    """One dev cluster, living in ``root`` (PKI, kubeconfig, logs, etcd data, state file).

    ``tied_to_this_process=True`` (test fixtures) makes the kernel stop the components when the
    Python process that started them dies; otherwise (the CLI) they are detached and outlive
    ``up``.
    """

    __slots__ = ("_procs", "layout", "tied", "toolchain")

    def __init__(
        self, root: Path, toolchain: Toolchain, *, tied_to_this_process: bool = False
    ) -> None:
        self.layout = Layout(root=root)
        self.toolchain = toolchain
        self.tied = tied_to_this_process
        self._procs: dict[int, subprocess.Popen[bytes]] = {}

    # -- public API -----------------------------------------------------------------------------

    def up(
        self,
        *,
        nodes: int = 3,
        slots: int = 3,
        shape: NodeShape | None = None,
        crds_dir: Path | None = None,
        apiserver_port: int | None = None,
        real_node: RealNodeSetup | None = None,
        with_kueue: bool = False,
        timeout: float = 90.0,
    ) -> ClusterInfo:
        """Start the cluster (or return the running one) and wait until it is usable.

        Usable means: apiserver ``/readyz`` ok, controller-manager, scheduler and kwok healthy,
        the CRDs from ``crds_dir`` established (skipped when the folder is missing or empty),
        ``nodes`` fake nodes Ready with ``slots`` ``simtest.dev/simulator`` each (``shape``
        overrides all capacities), the ``default`` service account present, and with
        ``real_node`` the real node (kubelet + containerd) Ready with its images imported and,
        given addons, advertising simulator slots; ``with_kueue`` adds Kueue's manager (its CRDs
        established, ``/readyz`` ok).
        """
        current = self._load_state()
        if current is not None:
            if self.status().running:
                if with_kueue and not any(r.name == "kueue" for r in current.processes):
                    current = self._start_kueue(current, timeout=timeout)  # `up`, then `up --kueue`
                    current.save(self.layout.state)
                return self._info(current)
            self.down()  # stale: something died; start over cleanly
        if real_node is not None:
            realnodes.check_host()
        needed = (
            *CONTROL_PLANE_BINARIES,
            *(("kubelet", "crictl") if real_node else ()),
            *(("kueue",) if with_kueue else ()),
        )
        missing = self.toolchain.missing(needed)
        if missing:
            raise ToolchainError(
                f"not built: {', '.join(missing)} (in {self.toolchain.bin_dir}); "
                "run `bash deploy/devcluster/build.sh` or `simtest dev-cluster build`"
            )
        if apiserver_port is not None and port_in_use(apiserver_port):
            raise ClusterError(f"port {apiserver_port} on 127.0.0.1 is in use; pick another")
        shape = shape or NodeShape(simulator_slots=slots)
        started = time.monotonic()
        ports = self._pick_ports(apiserver_port)
        pki = self._prepare_files(ports)
        state = ClusterState(
            server=f"https://127.0.0.1:{ports.apiserver}", ports=ports, started_at=time.time()
        )
        state.save(self.layout.state)
        try:
            state = self._start(state, pki, timeout=timeout)
            state = self._provision(
                state, pki, nodes=nodes, shape=shape, crds_dir=crds_dir, timeout=timeout
            )
            if with_kueue:
                state = self._start_kueue(state, timeout=timeout)
            if real_node is not None:
                state = self._start_real_node(state, pki, real_node, timeout=timeout)
        except BaseException:
            self.down()
            raise
        state = dataclasses.replace(state, startup_seconds=time.monotonic() - started)
        state.save(self.layout.state)
        return self._info(state)

    def down(self) -> tuple[str, ...]:
        """Stop exactly the processes ``up`` started (newest first); return their names.

        Logs, PKI and kubeconfig stay in the root for inspection; etcd data is wiped on the
        next ``up``.
        """
        state = self._load_state()
        stopped: list[str] = []
        if state is not None:
            by_name = {record.name: record for record in state.processes}
            crictl = self.toolchain.bin_dir / "crictl"
            for node in state.real_nodes:
                # The kubelet first (it would restart pods), then the pods through containerd.
                kubelet = by_name.get(f"kubelet-{node.name}")
                if kubelet is not None and stop(kubelet):
                    stopped.append(kubelet.name)
                realnodes.remove_pods(node, crictl if crictl.exists() else None)
            for record in reversed(state.processes):
                if stop(record):
                    stopped.append(record.name)
            for node in state.real_nodes:
                realnodes.clean_up(node)
            self.layout.state.unlink(missing_ok=True)
        for proc in self._procs.values():
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(timeout=5)
        self._procs.clear()
        return tuple(stopped)

    def stop_component(self, name: str) -> bool:
        """Stop one component (e.g. ``kubelet-simtest-real-0``) as a crash or an admin would."""
        return stop(self._component(self._require_state(), name))

    def start_component(self, name: str) -> None:
        """Start a stopped component again with the command line it had (a restart)."""
        state = self._require_state()
        record = self._component(state, name)
        if is_alive(record):
            raise ClusterError(f"{name} is still running (pid {record.pid})")
        rest = dataclasses.replace(
            state, processes=tuple(r for r in state.processes if r != record)
        )
        self._spawn(rest, name, list(record.argv))

    @staticmethod
    def _component(state: ClusterState, name: str) -> ProcessRecord:
        for record in state.processes:
            if record.name == name:
                return record
        raise ClusterError(f"no component {name!r} (have: {[r.name for r in state.processes]})")

    def _require_state(self) -> ClusterState:
        state = self._load_state()
        if state is None:
            raise ClusterError(f"no dev cluster is started in {self.layout.root}; run `up` first")
        return state

    def status(self) -> ClusterStatus:
        """Which recorded processes are alive and whether the apiserver answers ``/readyz``."""
        state = self._load_state()
        if state is None:
            return ClusterStatus(
                root=self.layout.root, started=False, server=None, apiserver_ready=False
            )
        pki = ensure_pki(self.layout.pki)
        return ClusterStatus(
            root=self.layout.root,
            started=True,
            server=state.server,
            apiserver_ready=self._apiserver_ready(state.server, pki),
            components=tuple(
                ComponentStatus(name=r.name, pid=r.pid, alive=is_alive(r), log=r.log)
                for r in state.processes
            ),
        )

    def info(self) -> ClusterInfo:
        """Connection details of the started cluster; :class:`ClusterError` if not started."""
        return self._info(self._require_state())

    # -- steps ----------------------------------------------------------------------------------

    def _pick_ports(self, apiserver_port: int | None) -> Ports:
        picked = list(free_ports(6))
        if apiserver_port is not None:
            picked = [p for p in picked if p != apiserver_port][:5]
            picked.insert(2, apiserver_port)
        return Ports.from_sequence(tuple(picked[:6]))

    def _prepare_files(self, ports: Ports) -> Pki:
        layout = self.layout
        layout.root.mkdir(parents=True, exist_ok=True)
        shutil.rmtree(layout.etcd_data, ignore_errors=True)
        pki = ensure_pki(layout.pki)
        server = f"https://127.0.0.1:{ports.apiserver}"
        ca_pem = pki.ca_cert.read_bytes()
        kubeconfig.write(
            layout.kubeconfig, server=server, ca_pem=ca_pem, user="admin", token=pki.tokens["admin"]
        )
        for client in COMPONENT_USERS:
            kubeconfig.write(
                layout.component_kubeconfig(client),
                server=server,
                ca_pem=ca_pem,
                user=client,
                token=pki.tokens[client],
            )
        stages = resources.files("simtest_operator.devcluster").joinpath("kwok.yaml")
        layout.kwok_config.write_text(stages.read_text())
        return pki

    def _spawn(self, state: ClusterState, name: str, argv: list[str]) -> ClusterState:
        record, proc = spawn(name, argv, log=self.layout.log(name), detach=not self.tied)
        if proc is not None:
            self._procs[record.pid] = proc
        state = dataclasses.replace(state, processes=(*state.processes, record))
        state.save(self.layout.state)
        return state

    def _start(self, state: ClusterState, pki: Pki, *, timeout: float) -> ClusterState:
        tc, layout, ports = self.toolchain, self.layout, state.ports
        state = self._spawn(state, "etcd", components.etcd(tc, layout, ports))
        etcd = state.processes[-1]
        wait_until(
            lambda: http_ok(f"http://127.0.0.1:{ports.etcd_client}/health"),
            what="etcd /health",
            timeout=timeout,
            watch=[etcd],
            blame=etcd,
        )
        state = self._spawn(
            state, "kube-apiserver", components.kube_apiserver(tc, layout, ports, pki)
        )
        apiserver = state.processes[-1]
        wait_until(
            lambda: self._apiserver_ready(state.server, pki),
            what="kube-apiserver /readyz",
            timeout=timeout,
            watch=[etcd, apiserver],
            blame=apiserver,
        )
        state = self._spawn(
            state,
            "kube-controller-manager",
            components.kube_controller_manager(tc, layout, ports, pki),
        )
        state = self._spawn(state, "kube-scheduler", components.kube_scheduler(tc, layout, ports))
        state = self._spawn(state, "kwok", components.kwok(tc, layout, ports))
        by_name = {r.name: r for r in state.processes}
        for name, url in (
            ("kube-controller-manager", f"https://127.0.0.1:{ports.controller_manager}/healthz"),
            ("kube-scheduler", f"https://127.0.0.1:{ports.scheduler}/healthz"),
            ("kwok", f"http://127.0.0.1:{ports.kwok}/healthz"),
        ):
            wait_until(
                functools.partial(http_ok, url, verify=False),
                what=f"{name} /healthz",
                timeout=timeout,
                watch=state.processes,
                blame=by_name[name],
            )
        return state

    def _provision(
        self,
        state: ClusterState,
        pki: Pki,
        *,
        nodes: int,
        shape: NodeShape,
        crds_dir: Path | None,
        timeout: float,
    ) -> ClusterState:
        api = provisioning.api_client(self.layout.kubeconfig)
        try:
            documents = provisioning.read_crds(crds_dir) if crds_dir and crds_dir.is_dir() else []
            crds = provisioning.apply_crds(api, documents)
            names = node_names(nodes)
            provisioning.create_nodes(api, names, shape)
            by_name = {r.name: r for r in state.processes}
            wait_until(
                lambda: provisioning.crds_established(api, crds),
                what="CRDs Established",
                timeout=timeout,
                watch=state.processes,
                blame=by_name["kube-apiserver"],
            )
            wait_until(
                lambda: provisioning.nodes_ready(api, names),
                what=f"{nodes} nodes Ready",
                timeout=timeout,
                watch=state.processes,
                blame=by_name["kwok"],
            )
            wait_until(
                lambda: provisioning.default_service_account_exists(api, "default"),
                what="service account default/default",
                timeout=timeout,
                watch=state.processes,
                blame=by_name["kube-controller-manager"],
            )
        finally:
            api.close()  # type: ignore[no-untyped-call]
        state = dataclasses.replace(state, nodes=names, crds=crds)
        state.save(self.layout.state)
        return state

    def _start_kueue(self, state: ClusterState, *, timeout: float) -> ClusterState:
        """Kueue's CRDs and bootstrap objects, then its manager, ready when ``/readyz`` answers
        (after its rotator injected the CA: see :mod:`~simtest_operator.devcluster.kueue`)."""
        binary = self.toolchain.binary("kueue")
        api = provisioning.api_client(self.layout.kubeconfig)
        by_name = {r.name: r for r in state.processes}
        try:
            crds = provisioning.apply_crds(api, kueue.crd_documents(binary))
            wait_until(
                lambda: provisioning.crds_established(api, crds),
                what="Kueue CRDs Established",
                timeout=timeout,
                watch=state.processes,
                blame=by_name["kube-apiserver"],
            )
            addons.apply(api, kueue.bootstrap_objects())
        finally:
            api.close()  # type: ignore[no-untyped-call]
        health, webhook = free_ports(2)
        kueue.write_config(self.layout, health_port=health, webhook_port=webhook)
        argv = kueue.argv(binary, self.layout, self.layout.component_kubeconfig("kueue"))
        state = self._spawn(dataclasses.replace(state, crds=(*state.crds, *crds)), "kueue", argv)
        api = provisioning.api_client(self.layout.kubeconfig)
        try:
            wait_until(
                functools.partial(kueue.mount_certs, api, self.layout),
                what="Kueue's webhook certificate in its Secret",
                timeout=timeout,
                watch=state.processes,
                blame=state.processes[-1],
            )
        finally:
            api.close()  # type: ignore[no-untyped-call]
        wait_until(
            functools.partial(http_ok, f"http://127.0.0.1:{health}/readyz"),
            what="kueue /readyz",
            timeout=timeout,
            watch=state.processes,
            blame=state.processes[-1],
        )
        return state

    def _start_real_node(
        self,
        state: ClusterState,
        pki: Pki,
        setup: RealNodeSetup,
        *,
        timeout: float,
    ) -> ClusterState:
        """containerd, the images, the kubelet; the Node Ready; the addons and the slots."""
        name = realnodes.NODE_NAME
        server_port, healthz_port = free_ports(2)
        node = RealNode(
            name=name,
            root=self.layout.root / "nodes" / name,
            network=hostnet.pick_network(self.layout.root, 0),
            ports=KubeletPorts(server=server_port, healthz=healthz_port),
        )
        state = dataclasses.replace(state, real_nodes=(node,))
        state.save(self.layout.state)
        realnodes.prepare(node, pki=pki, server=state.server, sandbox_image=setup.sandbox_image)
        containerd = realnodes.system_binary("containerd")
        state = self._spawn(state, f"containerd-{name}", containerd_argv(containerd, node.layout))
        wait_until(
            functools.partial(realnodes.containerd_ready, node),
            what=f"containerd of {name}",
            timeout=timeout,
            watch=state.processes[-1:],
            blame=state.processes[-1],
        )
        realnodes.import_images(node, setup.archives)
        labels = {REAL_NODE_LABEL: "true", "kubernetes.io/os": "linux"}
        kubelet = self.toolchain.binary("kubelet")
        argv = kubelet_argv(kubelet, node.layout, network=node.network, labels=labels)
        state = self._spawn(state, f"kubelet-{name}", argv)
        api = provisioning.api_client(self.layout.kubeconfig)
        try:
            wait_until(
                functools.partial(provisioning.nodes_ready, api, [name]),
                what=f"real node {name} Ready",
                timeout=timeout,
                watch=state.processes[-2:],
                blame=state.processes[-1],
            )
            if setup.addons:
                addons.apply(api, setup.addons)
                wait_until(
                    lambda: addons.simulator_slots(api, name) > 0,
                    what=f"{name} advertising simulator slots (device plugin in kube-system)",
                    timeout=timeout,
                    watch=state.processes[-2:],
                    blame=state.processes[-1],
                )
        finally:
            api.close()  # type: ignore[no-untyped-call]
        return state

    # -- helpers --------------------------------------------------------------------------------

    def _apiserver_ready(self, server: str, pki: Pki) -> bool:
        return http_ok(f"{server}/readyz", ca_file=pki.ca_cert, token=pki.tokens["admin"])

    def _load_state(self) -> ClusterState | None:
        try:
            return ClusterState.from_json(self.layout.state.read_text())
        except FileNotFoundError:
            return None
        except (ValueError, KeyError, TypeError) as exc:
            raise ClusterError(
                f"unreadable state file {self.layout.state}: {exc}; stop the processes named "
                "in it by hand, then delete it"
            ) from exc

    def _info(self, state: ClusterState) -> ClusterInfo:
        pki = ensure_pki(self.layout.pki)
        return ClusterInfo(
            root=self.layout.root,
            kubeconfig=self.layout.kubeconfig,
            server=state.server,
            token=pki.tokens["admin"],
            ca_file=pki.ca_cert,
            logs_dir=self.layout.logs,
            nodes=state.nodes,
            real_nodes=tuple(node.name for node in state.real_nodes),
            crds=state.crds,
            ports=state.ports,
            startup_seconds=state.startup_seconds,
        )
