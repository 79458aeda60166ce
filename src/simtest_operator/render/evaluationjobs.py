"""The campaign's evaluation step (``spec.evaluation.offline``): one Job running ``simtest
evaluate`` on the finished run, rendered from plain values.

The Job runs the runner image (it has the ``simtest`` command) under the campaign's simulator
ServiceAccount and the same restricted Pod Security settings as the simulator pods; the results
database's DSN and the S3 keys reach it only through ``secretKeyRef`` variables, never as values in
the manifest. ``simtest evaluate`` writes its summary to the termination-message file, so the
operator learns the outcome and the evaluation id from the pod's status without reading logs.

Exit 1 (a scenario did not pass) and exit 2 (bad input: unreadable criteria, unknown run) are
answers, not accidents: the pod failure policy ends the Job at once instead of retrying them;
``backoffLimit`` retries only crashes, and a node drain does not count.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from simtest_operator import podsecurity
from simtest_operator.render.inputs import ArtifactTarget, OwnerRef, SecretKey
from simtest_operator.settings import RESULTS_DSN

CONTAINER = "evaluate"
"""Name of the Job's one container."""
CRITERIA_MOUNT = "/etc/simtest/criteria"
"""Where the criteria ConfigMap key is mounted (read-only)."""
PVC_ROOT = "/pvc"
"""Where an artifacts claim is mounted read-only, as ``<root>/<claim>`` (``--pvc-root``)."""
TERMINATION_LOG = "/dev/termination-log"
"""Where ``--summary-file`` writes: the container's termination message."""
VERDICT_EXIT_CODES = (1, 2)
"""Exit codes that end the Job without a retry (a verdict, bad input)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ConfigMapKey:
    """A key of a ConfigMap (the criteria set)."""

    name: str
    key: str


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EvaluationJobRequest:
    """Everything the evaluation Job renders from."""

    name: str
    namespace: str
    labels: Mapping[str, str]
    """Labels of the Job and its pod (the operator watches the campaign's)."""
    owner: OwnerRef
    """The TestCampaign: deleting it removes the Job and its pod."""
    service_account: str
    image: str
    """The runner image (``spec.environment.simulator.image``)."""
    run_key: str
    """The campaign's run in the results database."""
    results_dsn: SecretKey
    artifacts: ArtifactTarget = dataclasses.field(default_factory=ArtifactTarget)
    """Where the recordings are: S3 keys as variables, a claim mounted read-only."""
    criteria: ConfigMapKey | None = None
    """The criteria set; None: the built-in ``default``."""
    backoff_limit: int = 1
    deadline_seconds: int = 3600
    node_selector: Mapping[str, str] = dataclasses.field(default_factory=dict)
    tolerations: tuple[Mapping[str, Any], ...] = ()
    cpu: str = "500m"
    memory: str = "1Gi"


def job(request: EvaluationJobRequest) -> dict[str, Any]:
    """The evaluation Job manifest."""
    labels = dict(sorted(request.labels.items()))
    return {
        "apiVersion": "batch/v1",
        "kind": "Job",
        "metadata": {
            "name": request.name,
            "namespace": request.namespace,
            "labels": labels,
            "ownerReferences": [
                {
                    "apiVersion": request.owner.api_version,
                    "kind": request.owner.kind,
                    "name": request.owner.name,
                    "uid": request.owner.uid,
                    "controller": True,
                    "blockOwnerDeletion": True,
                }
            ],
        },
        "spec": {
            "backoffLimit": request.backoff_limit,
            "activeDeadlineSeconds": request.deadline_seconds,
            "podFailurePolicy": {
                "rules": [
                    {
                        "action": "FailJob",
                        "onExitCodes": {
                            "containerName": CONTAINER,
                            "operator": "In",
                            "values": list(VERDICT_EXIT_CODES),
                        },
                    },
                    {"action": "Ignore", "onPodConditions": [{"type": "DisruptionTarget"}]},
                ]
            },
            "template": {"metadata": {"labels": labels}, "spec": _pod_spec(request)},
        },
    }


def _pod_spec(request: EvaluationJobRequest) -> dict[str, Any]:
    volumes: list[dict[str, Any]] = [{"name": "tmp", "emptyDir": {"sizeLimit": "2Gi"}}]
    mounts: list[dict[str, Any]] = [{"name": "tmp", "mountPath": "/tmp"}]
    args = ["evaluate", "--run", request.run_key, "--summary-file", TERMINATION_LOG]
    if request.criteria is not None:
        volumes.append(
            {
                "name": "criteria",
                "configMap": {
                    "name": request.criteria.name,
                    "items": [{"key": request.criteria.key, "path": request.criteria.key}],
                },
            }
        )
        mounts.append({"name": "criteria", "mountPath": CRITERIA_MOUNT, "readOnly": True})
        args += ["--criteria", f"{CRITERIA_MOUNT}/{request.criteria.key}"]
    pvc = request.artifacts.pvc
    if pvc is not None:
        volumes.append(
            {
                "name": "artifacts",
                "persistentVolumeClaim": {"claimName": pvc.claim_name, "readOnly": True},
            }
        )
        mounts.append(
            {"name": "artifacts", "mountPath": f"{PVC_ROOT}/{pvc.claim_name}", "readOnly": True}
        )
        args += ["--pvc-root", PVC_ROOT]
    spec: dict[str, Any] = {
        "restartPolicy": "Never",
        "serviceAccountName": request.service_account,
        "automountServiceAccountToken": False,
        "enableServiceLinks": False,
        "securityContext": podsecurity.pod_context(),
        "containers": [
            {
                "name": CONTAINER,
                "image": request.image,
                "imagePullPolicy": "IfNotPresent",
                "command": ["simtest"],
                "args": args,
                "env": _env(request),
                "resources": {
                    "requests": {"cpu": request.cpu, "memory": request.memory},
                    "limits": {"cpu": request.cpu, "memory": request.memory},
                },
                "securityContext": podsecurity.container_context(),
                "terminationMessagePath": TERMINATION_LOG,
                "terminationMessagePolicy": "FallbackToLogsOnError",
                "volumeMounts": mounts,
            }
        ],
        "volumes": volumes,
    }
    if request.node_selector:
        spec["nodeSelector"] = dict(sorted(request.node_selector.items()))
    if request.tolerations:
        spec["tolerations"] = [dict(t) for t in request.tolerations]
    return spec


def _env(request: EvaluationJobRequest) -> list[dict[str, Any]]:
    env: list[dict[str, Any]] = [
        _from_secret(RESULTS_DSN, request.results_dsn.name, request.results_dsn.key),
        {"name": "HOME", "value": "/tmp"},
        {"name": "SIMTEST_CACHE_DIR", "value": "/tmp/simtest-cache"},
    ]
    s3 = request.artifacts.s3
    if s3 is not None:
        env.append({"name": "AWS_ENDPOINT_URL_S3", "value": s3.endpoint})
        env += [
            _from_secret(key, s3.secret_name, key)
            for key in ("AWS_ACCESS_KEY_ID", "AWS_SECRET_ACCESS_KEY")
        ]
    return env


def _from_secret(variable: str, secret: str, key: str) -> dict[str, Any]:
    return {"name": variable, "valueFrom": {"secretKeyRef": {"name": secret, "key": key}}}
