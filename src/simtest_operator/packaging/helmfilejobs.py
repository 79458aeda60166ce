"""The Job that applies or destroys an environment's rendered helmfile (``provisioner: Helmfile``).

The operator's direct path creates the simulator pod itself; stacks packaged as charts (K8s-ROS
applications, auxiliary services) go through the real ``helmfile`` binary instead, run inside the
cluster by a Job so the operator never shells out. Everything here is pure: request in, manifests
out (STYLE rule 7), so the same environment always yields the same objects.

Objects per environment (all owned by the SimEnvironment, so deleting it removes them):

- a ConfigMap ``<job>`` holding ``helmfile.yaml`` (the rendered, run-specific helmfile);
- the Job ``<job>`` running ``helmfile sync`` or ``helmfile destroy`` on it.

Objects per campaign (owned by the TestCampaign): the Jobs' ServiceAccount and a RoleBinding to the
provisioner ClusterRole the operator chart installs (``<release>-helmfile-provisioner``). The
binding is namespaced, so a campaign's Jobs can only touch their own namespace.

Helm keeps release records in ConfigMaps (``HELM_DRIVER=configmap``), so the Jobs need no access to
Secrets; charts are read from the image (``IMAGE_CHARTS_DIR``) with ``--skip-deps`` because they
ship with their dependencies vendored and the root filesystem is read-only.
"""

from __future__ import annotations

import dataclasses
import enum
import hashlib
from collections.abc import Mapping
from typing import Any

from simtest_operator import podsecurity
from simtest_operator.errors import RenderError

IMAGE_CHARTS_DIR = "/opt/simtest/charts"
"""Where the helmfile image keeps ``charts/``; rendered helmfiles refer to charts below it."""
HELMFILE_MOUNT = "/etc/simtest/helmfile"
"""Where the Job sees the rendered helmfile (read-only)."""
HELMFILE_KEY = "helmfile.yaml"
"""Key of the rendered helmfile in its ConfigMap."""
LABEL_ENVIRONMENT = "simtest.dev/environment"
LABEL_ACTION = "simtest.dev/helmfile-action"
MAX_NAME = 63
"""Job names become pod label values, which are at most 63 characters."""


class Action(enum.StrEnum):
    """What the Job does with the helmfile."""

    SYNC = "sync"
    """Install or upgrade every release (provisioning)."""
    DESTROY = "destroy"
    """Uninstall every release (teardown)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Owner:
    """The object that owns what is rendered (its ownerReference)."""

    api_version: str
    kind: str
    name: str
    uid: str

    def reference(self) -> dict[str, Any]:
        """The ``ownerReferences`` entry (controller, blocking deletion of the owner)."""
        return {
            "apiVersion": self.api_version,
            "kind": self.kind,
            "name": self.name,
            "uid": self.uid,
            "controller": True,
            "blockOwnerDeletion": True,
        }


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class HelmfileJobRequest:
    """One helmfile run for one environment."""

    environment: str
    """SimEnvironment name; the Job and ConfigMap names derive from it."""
    namespace: str
    action: Action
    helmfile: str
    """The rendered, run-specific ``helmfile.yaml`` text (``render`` produces it)."""
    image: str
    """Image with helm, helmfile and the charts (``SIMTEST_OPERATOR_HELMFILE_IMAGE``)."""
    service_account: str
    """The campaign's provisioner ServiceAccount (see :func:`service_account_name`)."""
    owner: Owner
    """The SimEnvironment."""
    labels: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """Labels the operator selects its Jobs by (campaign, batch, attempt)."""
    deadline_seconds: int = 600
    """``activeDeadlineSeconds`` of the Job: helm gets this long to install or remove everything."""
    ttl_seconds: int = 3600
    """``ttlSecondsAfterFinished``: finished Jobs (and their logs) are kept this long."""
    cpu: str = "100m"
    memory: str = "256Mi"
    node_selector: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """Where the Job may run (e.g. away from the simulator nodes); empty: anywhere."""


def job_name(environment: str, action: Action) -> str:
    """``<environment>-hf-<action>``, shortened with a digest when it would exceed 63 characters."""
    return _bounded(environment, f"hf-{action.value}")


def service_account_name(campaign: str) -> str:
    """ServiceAccount of a campaign's helmfile Jobs."""
    return _bounded(campaign, "helmfile")


def config_map(request: HelmfileJobRequest) -> dict[str, Any]:
    """The ConfigMap carrying the rendered helmfile (immutable: one run, one file)."""
    _check(request)
    name = job_name(request.environment, request.action)
    return {
        "apiVersion": "v1",
        "kind": "ConfigMap",
        "metadata": _metadata(request, name),
        "immutable": True,
        "data": {HELMFILE_KEY: request.helmfile},
    }


def job(request: HelmfileJobRequest) -> dict[str, Any]:
    """The Job running ``helmfile sync`` or ``helmfile destroy`` on the mounted helmfile."""
    _check(request)
    name = job_name(request.environment, request.action)
    labels = _labels(request)
    container = {
        "name": "helmfile",
        "image": request.image,
        "imagePullPolicy": "IfNotPresent",
        "command": ["helmfile"],
        "args": [
            "--file",
            f"{HELMFILE_MOUNT}/{HELMFILE_KEY}",
            "--no-color",
            request.action.value,
            "--skip-deps",
        ],
        "env": [
            {"name": "HELM_DRIVER", "value": "configmap"},
            {"name": "HOME", "value": "/tmp"},
            {"name": "TMPDIR", "value": "/tmp"},
            {"name": "HELM_CACHE_HOME", "value": "/tmp/helm/cache"},
            {"name": "HELM_CONFIG_HOME", "value": "/tmp/helm/config"},
            {"name": "HELM_DATA_HOME", "value": "/tmp/helm/data"},
        ],
        "resources": {
            "requests": {"cpu": request.cpu, "memory": request.memory},
            "limits": {"memory": request.memory},
        },
        "securityContext": podsecurity.container_context(),
        "terminationMessagePolicy": "FallbackToLogsOnError",
        "volumeMounts": [
            {"name": "helmfile", "mountPath": HELMFILE_MOUNT, "readOnly": True},
            {"name": "tmp", "mountPath": "/tmp"},
        ],
    }
    return {
        "apiVersion": "batch/v1",
        "kind": "Job",
        "metadata": _metadata(request, name),
        "spec": {
            # The operator retries at its own level (a new environment attempt), so one pod only.
            "backoffLimit": 0,
            "activeDeadlineSeconds": request.deadline_seconds,
            "ttlSecondsAfterFinished": request.ttl_seconds,
            "template": {
                "metadata": {"labels": labels},
                "spec": {
                    "restartPolicy": "Never",
                    **(
                        {"nodeSelector": dict(sorted(request.node_selector.items()))}
                        if request.node_selector
                        else {}
                    ),
                    "serviceAccountName": request.service_account,
                    # helm talks to the API server with this ServiceAccount's token.
                    "automountServiceAccountToken": True,
                    "enableServiceLinks": False,
                    "securityContext": podsecurity.pod_context(),
                    "containers": [container],
                    "volumes": [
                        {"name": "helmfile", "configMap": {"name": name}},
                        {"name": "tmp", "emptyDir": {"sizeLimit": "1Gi"}},
                    ],
                },
            },
        },
    }


def service_account(
    *, campaign: str, namespace: str, owner: Owner, labels: Mapping[str, str]
) -> dict[str, Any]:
    """The campaign's provisioner identity (owned by the TestCampaign)."""
    return {
        "apiVersion": "v1",
        "kind": "ServiceAccount",
        "metadata": {
            "name": service_account_name(campaign),
            "namespace": namespace,
            "labels": dict(sorted(labels.items())),
            "ownerReferences": [owner.reference()],
        },
        "automountServiceAccountToken": False,
    }


def role_binding(
    *,
    campaign: str,
    namespace: str,
    cluster_role: str,
    owner: Owner,
    labels: Mapping[str, str],
) -> dict[str, Any]:
    """Binds the provisioner ClusterRole (``SIMTEST_OPERATOR_HELMFILE_ROLE``) to the campaign's
    ServiceAccount in the campaign's namespace only."""
    name = service_account_name(campaign)
    return {
        "apiVersion": "rbac.authorization.k8s.io/v1",
        "kind": "RoleBinding",
        "metadata": {
            "name": name,
            "namespace": namespace,
            "labels": dict(sorted(labels.items())),
            "ownerReferences": [owner.reference()],
        },
        "roleRef": {
            "apiGroup": "rbac.authorization.k8s.io",
            "kind": "ClusterRole",
            "name": cluster_role,
        },
        "subjects": [{"kind": "ServiceAccount", "name": name, "namespace": namespace}],
    }


def _bounded(base: str, suffix: str) -> str:
    name = f"{base}-{suffix}"
    if len(name) <= MAX_NAME:
        return name
    digest = hashlib.sha256(base.encode("utf-8")).hexdigest()[:8]
    keep = MAX_NAME - len(suffix) - len(digest) - 2
    return f"{base[:keep].rstrip('-')}-{digest}-{suffix}"


def _labels(request: HelmfileJobRequest) -> dict[str, str]:
    labels = {
        **request.labels,
        LABEL_ENVIRONMENT: request.environment,
        LABEL_ACTION: request.action.value,
        "app.kubernetes.io/component": "helmfile-provisioner",
    }
    return dict(sorted(labels.items()))


def _metadata(request: HelmfileJobRequest, name: str) -> dict[str, Any]:
    return {
        "name": name,
        "namespace": request.namespace,
        "labels": _labels(request),
        "ownerReferences": [request.owner.reference()],
    }


def _check(request: HelmfileJobRequest) -> None:
    if not request.helmfile.strip():
        raise RenderError(f"environment {request.environment}: the rendered helmfile is empty")
    if request.deadline_seconds <= 0:
        raise RenderError(
            f"environment {request.environment}: deadline_seconds must be positive, "
            f"got {request.deadline_seconds}"
        )
