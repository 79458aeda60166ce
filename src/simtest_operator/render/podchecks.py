"""Invariants every rendered simulator pod must meet, whatever its template says.

The operator's guarantees rest on them: one ``simtest.dev/simulator`` unit per pod (so the real
scheduler enforces simulators per node), the Pod Security ``restricted`` profile, an owner
reference to the SimEnvironment (so deletion cascades), a deadline (so a hung run ends as
Timeout) and ``restartPolicy: Never`` (so a crash is observed, not hidden by a restart). A pod
whose scenarios come from ConfigMaps or scenario databases must also mount those ConfigMaps and
pass the databases' tokens where the runner looks (:mod:`runspecs`), or every scenario of it would
end ``Error`` — better the campaign fails its pre-flight render with the reason.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from simtest_operator.errors import RenderError
from simtest_operator.render import runspecs
from simtest_operator.render.inputs import SIMULATOR_RESOURCE, EnvironmentRequest

RESTRICTED_VOLUMES = frozenset(
    {
        "configMap",
        "csi",
        "downwardAPI",
        "emptyDir",
        "ephemeral",
        "persistentVolumeClaim",
        "projected",
        "secret",
    }
)
"""Volume types the Pod Security ``restricted`` profile allows."""


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
    problems.extend(security_problems(spec))
    problems.extend(_slot_problems(spec))
    problems.extend(_source_problems(spec, request))
    return problems


def security_problems(spec: Mapping[str, Any]) -> list[str]:
    """What in a pod spec the Pod Security ``restricted`` profile refuses (also held against the
    evaluation Job's pod, :mod:`.evaluationjobs`)."""
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
        kinds = sorted(set(volume) - {"name"} - RESTRICTED_VOLUMES)
        if kinds:
            problems.append(
                f"volume {volume.get('name', '?')}: {', '.join(kinds)} is not allowed "
                "(restricted Pod Security)"
            )
    return problems


def _source_problems(spec: Mapping[str, Any], request: EnvironmentRequest) -> list[str]:
    """The runner's container must see every ConfigMap and token its scenarios need."""
    needs = request.source_needs
    if not needs.config_maps and not needs.databases:
        return []
    runner = next(
        (
            c
            for c in spec.get("containers") or []
            if any(e.get("name") == runspecs.ENV_VAR for e in c.get("env") or [])
        ),
        None,
    )
    if runner is None:
        return [f"no container has {runspecs.ENV_VAR}, so none can fetch the scenarios"]
    problems: list[str] = []
    volumes = {v.get("name"): v for v in spec.get("volumes") or []}
    mounted = {
        m.get("mountPath"): volumes.get(m.get("name"), {}) for m in runner.get("volumeMounts") or []
    }
    for entry in runspecs.config_map_volumes(needs.config_maps):
        volume = mounted.get(entry["mountPath"]) or {}
        if (volume.get("configMap") or {}).get("name") != entry["configMap"]:
            problems.append(
                f"ConfigMap {entry['configMap']} must be mounted at {entry['mountPath']} "
                f"(the scenarios read it)"
            )
    env = {e.get("name"): e for e in runner.get("env") or []}
    for ref, variable in runspecs.secret_variables(needs.databases).items():
        key_ref = ((env.get(variable) or {}).get("valueFrom") or {}).get("secretKeyRef") or {}
        if (key_ref.get("name"), key_ref.get("key")) != (ref.name, ref.key):
            problems.append(
                f"{variable} must come from Secret {ref.name} key {ref.key} "
                "(a scenario database's token)"
            )
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
