"""Local node agent — development and test infrastructure only, never part of the product.

Simulator pods run on the dev cluster's real node (kubelet + containerd + runc, tests/realnode/);
this agent remains only as the base of :mod:`tests.e2e.helmfile_job_agent`, because a helmfile
Job's pod must talk to the API server, and the dev cluster has no service proxy (kube-proxy) that
would route a pod's in-cluster ``kubernetes`` Service address there. It plays kubelet for one
dedicated Node object: it registers
the node (with ``simtest.dev/simulator`` slots), keeps its Lease and Ready condition fresh, and
runs every pod the scheduler binds to it as a local ``simtest-runner`` *process* with the pod's
environment — literal values, and ``valueFrom`` references to Secrets and ConfigMaps read from the
API server at start, as a kubelet resolves them (a missing object or key keeps the pod ``Pending``
with its container waiting in ``CreateContainerConfigError``, retried on every resync, as a
kubelet does). When the process exits it reports the pod's terminated state — exit code, reason and
the termination message read from a per-pod file standing in for ``/dev/termination-log`` (the
log tail when that file is empty, as ``FallbackToLogsOnError`` would) — and, like a kubelet,
finishes pods that are being deleted. What the operator sees is the same pod lifecycle a real
node produces, with real SUMO runs and real verdicts.

Not emulated: images (the runner comes from this virtualenv), volumes (the artifacts volume is a
local folder per pod), resource limits, activeDeadlineSeconds enforcement.
"""

from __future__ import annotations

import base64
import contextlib
import dataclasses
import datetime
import os
import subprocess
import sys
import threading
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from kubernetes import client, watch
from kubernetes.client.exceptions import ApiException

NODE_LEASE_NAMESPACE = "kube-node-lease"


def _now() -> str:
    return datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def _micro_now() -> str:
    return datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ")


class ContainerConfigError(Exception):
    """The container environment cannot be built (kubelet: ``CreateContainerConfigError``)."""


_FIELD_PATHS = {
    "metadata.name": lambda pod: pod.metadata.name,
    "metadata.namespace": lambda pod: pod.metadata.namespace,
    "metadata.uid": lambda pod: pod.metadata.uid,
    "spec.nodeName": lambda pod: pod.spec.node_name,
    "spec.serviceAccountName": lambda pod: pod.spec.service_account_name,
}


def resolve_env(core: client.CoreV1Api, pod: client.V1Pod, env: Any) -> dict[str, str]:
    """The container's environment as a kubelet builds it: literal values, and ``valueFrom``
    references to Secret and ConfigMap keys (read from the API server now) and to a few pod
    fields. A missing object or key of a non-optional reference raises
    :class:`ContainerConfigError` with the kubelet's message."""
    namespace = pod.metadata.namespace
    cache: dict[tuple[str, str], Mapping[str, str] | None] = {}

    def data(kind: str, name: str) -> Mapping[str, str] | None:
        if (kind, name) not in cache:
            cache[(kind, name)] = _read(core, kind, namespace, name)
        return cache[(kind, name)]

    resolved: dict[str, str] = {}
    for item in env or []:
        if item.value_from is None:
            resolved[item.name] = item.value or ""
            continue
        source = item.value_from
        if source.secret_key_ref is not None or source.config_map_key_ref is not None:
            ref = source.secret_key_ref or source.config_map_key_ref
            kind = "Secret" if source.secret_key_ref is not None else "ConfigMap"
            values = data(kind, ref.name)
            if values is None:
                if ref.optional:
                    continue
                raise ContainerConfigError(f'{kind.lower()} "{ref.name}" not found')
            if ref.key not in values:
                if ref.optional:
                    continue
                raise ContainerConfigError(
                    f"couldn't find key {ref.key} in {kind} {namespace}/{ref.name}"
                )
            resolved[item.name] = values[ref.key]
        elif source.field_ref is not None and source.field_ref.field_path in _FIELD_PATHS:
            resolved[item.name] = str(_FIELD_PATHS[source.field_ref.field_path](pod) or "")
        else:
            raise ContainerConfigError(
                f"env {item.name}: this valueFrom is not emulated by the local node agent"
            )
    return resolved


def _read(core: client.CoreV1Api, kind: str, namespace: str, name: str) -> Mapping[str, str] | None:
    """The decoded data of a Secret or ConfigMap, or None when it does not exist."""
    try:
        if kind == "Secret":
            secret = core.read_namespaced_secret(name, namespace)
            return {k: base64.b64decode(v).decode("utf-8") for k, v in (secret.data or {}).items()}
        config_map = core.read_namespaced_config_map(name, namespace)
        binary = {
            k: base64.b64decode(v).decode("utf-8")
            for k, v in (config_map.binary_data or {}).items()
        }
        return {**binary, **(config_map.data or {})}
    except ApiException as exc:
        if exc.status == 404:
            return None
        raise


@dataclasses.dataclass
class _Running:
    process: subprocess.Popen[bytes]
    started: str
    message_file: Path
    log_file: Path


class LocalNodeAgent:
    """Runs pods bound to ``node`` as local simtest-runner processes (a thread)."""

    def __init__(self, api: client.ApiClient, *, node: str, workdir: Path, slots: int = 2) -> None:
        self.core = client.CoreV1Api(api)
        self.coordination = client.CoordinationV1Api(api)
        self.node = node
        self.workdir = workdir
        self.slots = slots
        self.running: dict[tuple[str, str], _Running] = {}
        self.finished: set[tuple[str, str]] = set()
        self.started_pods: list[str] = []
        self.config_errors: dict[tuple[str, str], str] = {}
        """Pods waiting in ``CreateContainerConfigError``, with the kubelet's message."""
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []

    # --- node registration -------------------------------------------------------------------

    def _node_body(self) -> dict[str, Any]:
        capacity = {
            "cpu": "8",
            "memory": "16Gi",
            "pods": "50",
            "simtest.dev/simulator": str(self.slots),
        }
        return {
            "apiVersion": "v1",
            "kind": "Node",
            "metadata": {
                "name": self.node,
                "labels": {
                    "kubernetes.io/hostname": self.node,
                    "kubernetes.io/os": "linux",
                    "simtest.dev/local-agent": "true",
                },
            },
            "status": {
                "capacity": capacity,
                "allocatable": capacity,
                "conditions": self._conditions(),
                "addresses": [{"type": "InternalIP", "address": "127.0.0.1"}],
                "nodeInfo": {
                    "architecture": "amd64",
                    "bootID": "",
                    "containerRuntimeVersion": "local-agent",
                    "kernelVersion": "",
                    "kubeProxyVersion": "",
                    "kubeletVersion": "local-agent",
                    "machineID": "",
                    "operatingSystem": "linux",
                    "osImage": "",
                    "systemUUID": "",
                },
            },
        }

    def _conditions(self) -> list[dict[str, str]]:
        now = _now()
        return [
            {
                "type": "Ready",
                "status": "True",
                "reason": "LocalAgentReady",
                "message": "local node agent (test infrastructure)",
                "lastHeartbeatTime": now,
                "lastTransitionTime": now,
            }
        ]

    def start(self) -> None:
        try:
            self.core.create_node(body=self._node_body())
        except ApiException as exc:
            if exc.status != 409:
                raise
        self._heartbeat_once()
        for target in (self._heartbeat, self._watch, self._reap):
            thread = threading.Thread(target=target, daemon=True, name=f"agent-{target.__name__}")
            thread.start()
            self._threads.append(thread)

    def stop(self) -> None:
        self._stop.set()
        for run in self.running.values():
            run.process.kill()
        for thread in self._threads:
            thread.join(timeout=10)
        with contextlib.suppress(ApiException):
            self.core.delete_node(self.node)

    def _heartbeat_once(self) -> None:
        self.core.patch_node_status(self.node, {"status": {"conditions": self._conditions()}})
        lease = {
            "apiVersion": "coordination.k8s.io/v1",
            "kind": "Lease",
            "metadata": {"name": self.node, "namespace": NODE_LEASE_NAMESPACE},
            "spec": {
                "holderIdentity": self.node,
                "leaseDurationSeconds": 40,
                "renewTime": _micro_now(),
            },
        }
        try:
            self.coordination.create_namespaced_lease(NODE_LEASE_NAMESPACE, lease)
        except ApiException as exc:
            if exc.status != 409:
                raise
            self.coordination.patch_namespaced_lease(
                self.node, NODE_LEASE_NAMESPACE, {"spec": lease["spec"]}
            )

    def _heartbeat(self) -> None:
        while not self._stop.wait(10):
            try:
                self._heartbeat_once()
            except ApiException:
                continue

    # --- pods --------------------------------------------------------------------------------

    def _watch(self) -> None:
        while not self._stop.is_set():
            watcher = watch.Watch()
            try:
                for event in watcher.stream(
                    self.core.list_pod_for_all_namespaces,
                    field_selector=f"spec.nodeName={self.node}",
                    timeout_seconds=5,
                ):
                    if self._stop.is_set():
                        break
                    self._handle(event["object"])
            except ApiException:
                time.sleep(0.5)

    def _handle(self, pod: client.V1Pod) -> None:
        key = (pod.metadata.namespace, pod.metadata.name)
        if pod.metadata.deletion_timestamp is not None:
            run = self.running.pop(key, None)
            if run is not None:
                run.process.kill()
            with contextlib.suppress(ApiException):
                self.core.delete_namespaced_pod(
                    pod.metadata.name, pod.metadata.namespace, grace_period_seconds=0
                )
            return
        if key in self.running or key in self.finished or pod.status.phase not in (None, "Pending"):
            return
        self._launch(pod)

    def _launch(self, pod: client.V1Pod) -> None:
        key = (pod.metadata.namespace, pod.metadata.name)
        container = pod.spec.containers[0]
        try:
            pod_env = resolve_env(self.core, pod, container.env)
        except (ContainerConfigError, ApiException) as exc:
            message = str(exc) if isinstance(exc, ContainerConfigError) else f"API: {exc.reason}"
            self._config_error(pod, message)
            return
        self.config_errors.pop(key, None)
        folder = self.workdir / pod.metadata.namespace / pod.metadata.name
        folder.mkdir(parents=True, exist_ok=True)
        message_file = folder / "termination-log"
        env = {k: v for k, v in os.environ.items() if not k.startswith(("SIMTEST_", "AWS_"))}
        env.update(pod_env)
        env["HOME"] = str(folder)
        env["SIMTEST_CACHE_DIR"] = str(self.workdir / "cache")  # shared, like a node-local cache
        command = [
            sys.executable,
            "-c",
            "from simtest_operator.runner.entrypoint import main; main()",
            "--termination-log",
            str(message_file),
            "--artifacts",
            str(folder / "artifacts"),
        ]
        self._start_process(pod, command, env=env, folder=folder, log_name="runner.log")

    def _start_process(
        self,
        pod: client.V1Pod,
        command: list[str],
        *,
        env: Mapping[str, str],
        folder: Path,
        log_name: str,
    ) -> None:
        """Run the pod's container as a local process and report the pod Running."""
        key = (pod.metadata.namespace, pod.metadata.name)
        container = pod.spec.containers[0]
        message_file = folder / "termination-log"
        message_file.write_text("")
        log_file = folder / log_name
        started = _now()
        with log_file.open("wb") as handle:
            process = subprocess.Popen(
                command, env=dict(env), stdout=handle, stderr=subprocess.STDOUT, cwd=folder
            )
        self.running[key] = _Running(
            process=process, started=started, message_file=message_file, log_file=log_file
        )
        self.started_pods.append(pod.metadata.name)
        self._patch_status(
            key,
            {
                "phase": "Running",
                "startTime": started,
                "conditions": [{"type": "Ready", "status": "True", "lastTransitionTime": started}],
                "containerStatuses": [
                    {
                        "name": container.name,
                        "image": container.image,
                        "imageID": "",
                        "ready": True,
                        "restartCount": 0,
                        "started": True,
                        "state": {"running": {"startedAt": started}},
                    }
                ],
            },
        )

    def _config_error(self, pod: client.V1Pod, message: str) -> None:
        """What a kubelet reports while it cannot build the container's config: the pod stays
        Pending, its container waits with ``CreateContainerConfigError`` (written once per
        message; the watch's resync retries the start)."""
        key = (pod.metadata.namespace, pod.metadata.name)
        if self.config_errors.get(key) == message:
            return
        self.config_errors[key] = message
        container = pod.spec.containers[0]
        self._patch_status(
            key,
            {
                "phase": "Pending",
                "conditions": [
                    {
                        "type": "Ready",
                        "status": "False",
                        "reason": "ContainersNotReady",
                        "lastTransitionTime": _now(),
                    }
                ],
                "containerStatuses": [
                    {
                        "name": container.name,
                        "image": container.image,
                        "imageID": "",
                        "ready": False,
                        "restartCount": 0,
                        "started": False,
                        "state": {
                            "waiting": {"reason": "CreateContainerConfigError", "message": message}
                        },
                    }
                ],
            },
        )

    def _reap(self) -> None:
        while not self._stop.wait(0.1):
            for key, run in list(self.running.items()):
                code = run.process.poll()
                if code is None:
                    continue
                self.running.pop(key, None)
                self.finished.add(key)
                message = run.message_file.read_text(errors="replace")
                if not message.strip() and code != 0:
                    message = "\n".join(
                        run.log_file.read_text(errors="replace").splitlines()[-40:]
                    )[-2048:]
                finished = _now()
                self._patch_status(
                    key,
                    {
                        "phase": "Succeeded" if code == 0 else "Failed",
                        "conditions": [
                            {"type": "Ready", "status": "False", "lastTransitionTime": finished}
                        ],
                        "containerStatuses": [
                            {
                                "name": "simulator",
                                "image": "local",
                                "imageID": "",
                                "ready": False,
                                "restartCount": 0,
                                "started": False,
                                "state": {
                                    "terminated": {
                                        "exitCode": code,
                                        "reason": "Completed" if code == 0 else "Error",
                                        "message": message[:4096],
                                        "startedAt": run.started,
                                        "finishedAt": finished,
                                    }
                                },
                            }
                        ],
                    },
                )

    def _patch_status(self, key: tuple[str, str], status: dict[str, Any]) -> None:
        with contextlib.suppress(ApiException):
            self.core.patch_namespaced_pod_status(key[1], key[0], {"status": status})
