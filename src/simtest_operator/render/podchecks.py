"""Invariants every rendered simulator pod must meet, whatever its template says.

The operator's guarantees rest on them: one ``simtest.dev/simulator`` unit per pod (so the real
scheduler enforces simulators per node), the Pod Security ``restricted`` profile, an owner
reference to the SimEnvironment (so deletion cascades), a deadline (so a hung run ends as
Timeout) and ``restartPolicy: Never`` (so a crash is observed, not hidden by a restart).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from simtest_operator.errors import RenderError
from simtest_operator.render.inputs import SIMULATOR_RESOURCE, EnvironmentRequest


def check_pod(pod: Mapping[str, Any], request: EnvironmentRequest) -> None:
    """Raise :class:`RenderError` listing every violated invariant."""
    problems = list(_problems(pod, request))
    if problems:
        raise RenderError(
            f"template {request.template!r} renders a pod the operator cannot run: "
            + "; ".join(problems)
        )


def _problems(pod: Mapping[str, Any], request: EnvironmentRequest) -> list[str]:
    problems: list[str] = []
    if pod.get("apiVersion") != "v1" or pod.get("kind") != "Pod":
        problems.append("must be apiVersion v1, kind Pod")
    meta = pod.get("metadata") or {}
    if meta.get("name") != request.name or meta.get("namespace") != request.namespace:
        problems.append("metadata.name/namespace must be the environment's")
    labels = meta.get("labels") or {}
    missing = sorted(k for k, v in request.labels.items() if labels.get(k) != v)
    if missing:
        problems.append(f"metadata.labels must keep the operator's labels ({', '.join(missing)})")
    owners = meta.get("ownerReferences") or []
    if not any(o.get("uid") == request.owner.uid and o.get("controller") for o in owners):
        problems.append("metadata.ownerReferences must name the SimEnvironment as controller")
    spec = pod.get("spec") or {}
    if spec.get("restartPolicy") != "Never":
        problems.append("spec.restartPolicy must be Never")
    if not isinstance(spec.get("activeDeadlineSeconds"), int):
        problems.append("spec.activeDeadlineSeconds must be set")
    if spec.get("serviceAccountName") != request.service_account:
        problems.append("spec.serviceAccountName must be the simulator ServiceAccount")
    if spec.get("hostNetwork") or spec.get("hostPID") or spec.get("hostIPC"):
        problems.append("host namespaces are not allowed")
    problems.extend(_security_problems(spec))
    problems.extend(_slot_problems(spec))
    return problems


def _security_problems(spec: Mapping[str, Any]) -> list[str]:
    problems: list[str] = []
    pod_sc = spec.get("securityContext") or {}
    pod_seccomp = (pod_sc.get("seccompProfile") or {}).get("type")
    containers = [*(spec.get("initContainers") or []), *(spec.get("containers") or [])]
    if not containers:
        problems.append("spec.containers must not be empty")
    for container in containers:
        name = container.get("name", "?")
        sc = container.get("securityContext") or {}
        if not (sc.get("runAsNonRoot") or pod_sc.get("runAsNonRoot")):
            problems.append(f"container {name}: runAsNonRoot must be true")
        if sc.get("allowPrivilegeEscalation") is not False:
            problems.append(f"container {name}: allowPrivilegeEscalation must be false")
        if sc.get("privileged"):
            problems.append(f"container {name}: privileged is not allowed")
        if sc.get("readOnlyRootFilesystem") is not True:
            problems.append(f"container {name}: readOnlyRootFilesystem must be true")
        if "ALL" not in ((sc.get("capabilities") or {}).get("drop") or []):
            problems.append(f"container {name}: capabilities must drop ALL")
        if (sc.get("capabilities") or {}).get("add"):
            problems.append(f"container {name}: capabilities may not be added")
        seccomp = (sc.get("seccompProfile") or {}).get("type") or pod_seccomp
        if seccomp not in ("RuntimeDefault", "Localhost"):
            problems.append(f"container {name}: seccompProfile must be RuntimeDefault")
    for volume in spec.get("volumes") or []:
        if "hostPath" in volume:
            problems.append(f"volume {volume.get('name', '?')}: hostPath is not allowed")
    return problems


def _slot_problems(spec: Mapping[str, Any]) -> list[str]:
    units = 0
    for container in spec.get("containers") or []:
        resources = container.get("resources") or {}
        requests = resources.get("requests") or {}
        limits = resources.get("limits") or {}
        if SIMULATOR_RESOURCE in requests or SIMULATOR_RESOURCE in limits:
            if str(requests.get(SIMULATOR_RESOURCE)) != str(limits.get(SIMULATOR_RESOURCE)):
                return [f"{SIMULATOR_RESOURCE} requests and limits must be equal"]
            units += int(str(limits.get(SIMULATOR_RESOURCE)))
    if units != 1:
        return [f"the pod must request exactly one {SIMULATOR_RESOURCE} unit (found {units})"]
    return []
