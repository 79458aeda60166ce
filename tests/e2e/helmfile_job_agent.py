"""Local helmfile Job agent — development and test infrastructure only, never part of the product.

kwok fakes the pods of Jobs (they "succeed" at once without running anything), and no kubelet can
run the helmfile image here. This agent plays kubelet for one dedicated Node object (the operator
places its helmfile Jobs there with ``SIMTEST_OPERATOR_HELMFILE_NODE_SELECTOR``) and runs each pod
bound to it as a local process: the pod's own command and arguments, i.e. the REAL ``helmfile``
binary of the dev toolchain (and the real ``helm`` it calls), with

* the pod's ``configMap`` volumes materialised from the API server (the rendered helmfile) and its
  ``emptyDir`` volumes as local folders, at paths standing in for the mount paths;
* the helmfile image's ``charts/`` (``/opt/simtest/charts``) standing in as this checkout's
  ``charts/``;
* the pod's ServiceAccount as its identity: a kubeconfig holding a token of that account (what a
  pod gets mounted), so helm works with exactly the RBAC the operator bound to the Job.

Path stand-ins are applied to the arguments, the environment and the materialised files. The
pod's terminated state (exit code, helmfile's output tail as ``FallbackToLogsOnError`` would give)
is reported by :class:`LocalNodeAgent`, so the Job controller completes or fails the Job as usual.
"""

from __future__ import annotations

import dataclasses
import os
import re
import time
from pathlib import Path
from typing import Any

import yaml
from kubernetes import client
from kubernetes.client.exceptions import ApiException

from tests.e2e.local_node_agent import LocalNodeAgent

IMAGE_CHARTS_DIR = "/opt/simtest/charts"


@dataclasses.dataclass(frozen=True)
class Ran:
    """One pod the agent ran."""

    pod: str
    args: tuple[str, ...]


class HelmfileJobAgent(LocalNodeAgent):
    """Runs helmfile Job pods bound to ``node`` as local helmfile processes (a thread)."""

    def __init__(
        self,
        api: client.ApiClient,
        *,
        node: str,
        workdir: Path,
        toolchain_bin: Path,
        charts_dir: Path,
        kubeconfig: Path,
    ) -> None:
        super().__init__(api, node=node, workdir=workdir, slots=0)
        self.toolchain_bin = toolchain_bin
        self.charts_dir = charts_dir
        self.admin_kubeconfig = kubeconfig
        self.ran: list[Ran] = []

    def _launch(self, pod: client.V1Pod) -> None:
        container = pod.spec.containers[0]
        folder = self.workdir / pod.metadata.namespace / pod.metadata.name
        folder.mkdir(parents=True, exist_ok=True)
        paths = {IMAGE_CHARTS_DIR: str(self.charts_dir)}
        for mount in container.volume_mounts or []:
            local = folder / "mounts" / mount.name
            local.mkdir(parents=True, exist_ok=True)
            paths[mount.mount_path] = str(local)
        for volume in pod.spec.volumes or []:
            if volume.config_map is not None:
                data = self._config_map(pod.metadata.namespace, volume.config_map.name)
                for name, text in data.items():
                    (folder / "mounts" / volume.name / name).write_text(_mapped(text, paths))
        env = {"PATH": f"{self.toolchain_bin}:{os.environ.get('PATH', '')}"}
        for item in container.env or []:
            if item.value is not None:
                env[item.name] = _mapped(item.value, paths)
        env["KUBECONFIG"] = str(self._identity(pod, folder))
        binary = str(self.toolchain_bin / container.command[0])
        args = [_mapped(a, paths) for a in (container.args or [])]
        self.ran.append(Ran(pod=pod.metadata.name, args=tuple(container.args or ())))
        self._start_process(pod, [binary, *args], env=env, folder=folder, log_name="helmfile.log")

    def _config_map(self, namespace: str, name: str) -> dict[str, str]:
        """The ConfigMap's data; a kubelet waits for a missing one too (the destroy Job's
        ConfigMap is created right after its Job)."""
        deadline = time.monotonic() + 60
        while True:
            try:
                return dict(self.core.read_namespaced_config_map(name, namespace).data or {})
            except ApiException as exc:
                if exc.status != 404 or time.monotonic() > deadline:
                    raise
                time.sleep(0.5)

    def _identity(self, pod: client.V1Pod, folder: Path) -> Path:
        """A kubeconfig authenticating as the pod's ServiceAccount (its mounted token)."""
        account = pod.spec.service_account_name or "default"
        token = self.core.create_namespaced_service_account_token(
            account, pod.metadata.namespace, {"spec": {"expirationSeconds": 3600}}
        ).status.token
        config: dict[str, Any] = yaml.safe_load(self.admin_kubeconfig.read_text())
        for user in config["users"]:
            user["user"] = {"token": token}
        for context in config["contexts"]:
            context["context"]["namespace"] = pod.metadata.namespace
        path = folder / "serviceaccount.kubeconfig"
        path.write_text(yaml.safe_dump(config))
        return path


def _mapped(text: str, paths: dict[str, str]) -> str:
    """``text`` with each stand-in path replaced in one pass (longest first, so a replacement
    is never rewritten again)."""
    pattern = "|".join(re.escape(p) for p in sorted(paths, key=len, reverse=True))
    return re.sub(pattern, lambda m: paths[m.group(0)], text)
