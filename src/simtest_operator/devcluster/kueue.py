"""Kueue in the dev cluster (``simtest dev-cluster up --kueue``): its CRDs, config and command line.

The manager is the binary ``build.sh`` builds from ``sigs.k8s.io/kueue``; its CRDs are the
module's own (``config/components/crd/bases``, copied beside the binary). Pure except for
:func:`crd_documents` (reads those files).

Webhooks. The apiserver of this cluster cannot reach an in-cluster Service (no kube-proxy, no
cluster DNS), and Kueue's certificates name ``kueue-webhook-service.kueue-system.svc`` only, so
Kueue's admission webhooks are not registered here. Nothing the operator does needs them: it
creates its Workloads itself (``operator/admission.py``) instead of relying on the pod webhook
that gates pods. Kueue still manages its certificates internally, because without that it reads
its metrics certificate from a fixed ``/etc/kueue`` path. Its rotator must inject the CA into
two webhook configurations and the conversion settings of five CRDs before the manager starts,
so :func:`bootstrap_objects` creates the two configurations empty (no webhooks) and
:func:`crd_documents` adds the conversion stanza Kueue's kustomize patches add (pointing at the
Service). Conversion is only ever called for ``v1beta1`` requests; everything here (operator,
Kueue, ``kubectl``) uses the storage version ``v1beta2``. In a pod the kubelet mounts the
rotator's Secret as files; here :func:`mount_certs` copies it once it is filled.
"""

from __future__ import annotations

import base64
import copy
from pathlib import Path
from typing import Any

import yaml
from kubernetes import client
from kubernetes.client.exceptions import ApiException

from simtest_operator.devcluster.components import Layout
from simtest_operator.errors import ToolchainError

NAMESPACE = "kueue-system"
WEBHOOK_SERVICE = "kueue-webhook-service"
WEBHOOK_SECRET = "kueue-webhook-server-cert"
CONVERTED_CRDS = frozenset(
    {
        "localqueues.kueue.x-k8s.io",
        "clusterqueues.kueue.x-k8s.io",
        "cohorts.kueue.x-k8s.io",
        "workloads.kueue.x-k8s.io",
        "multikueueclusters.kueue.x-k8s.io",
    }
)
"""The CRDs Kueue's rotator injects its CA into (``pkg/util/cert``): they need a conversion
webhook stanza, or the rotator never reports ready and the manager never starts."""
FRAMEWORKS = ("batch/job",)
"""Job integrations: the operator needs none (it creates Workloads); ``batch/job`` lets an admin
try Kueue with a plain Job (``kueue.x-k8s.io/queue-name`` label, ``suspend: true``)."""


def crd_dir(kueue_binary: Path) -> Path:
    """The CRDs built with this binary: ``<toolchain>/kueue-<version>/crd``."""
    return kueue_binary.resolve().parent.parent / "crd"


def crd_documents(kueue_binary: Path) -> list[dict[str, Any]]:
    """Kueue's CRDs as installed here (conversion stanza added where the rotator needs one)."""
    folder = crd_dir(kueue_binary)
    files = sorted(folder.glob("*.yaml"))
    if not files:
        raise ToolchainError(
            f"no Kueue CRDs in {folder}; run `bash deploy/devcluster/build.sh kueue`"
        )
    documents = []
    for path in files:
        for document in yaml.safe_load_all(path.read_text()):
            if isinstance(document, dict):
                documents.append(with_conversion(document))
    return documents


def with_conversion(crd: dict[str, Any]) -> dict[str, Any]:
    """``crd`` with the conversion webhook stanza of Kueue's kustomize patches, if it needs one."""
    if crd.get("metadata", {}).get("name") not in CONVERTED_CRDS:
        return crd
    patched = copy.deepcopy(crd)
    patched["spec"]["conversion"] = {
        "strategy": "Webhook",
        "webhook": {
            "clientConfig": {
                "service": {"namespace": NAMESPACE, "name": WEBHOOK_SERVICE, "path": "/convert"}
            },
            "conversionReviewVersions": ["v1"],
        },
    }
    return patched


def bootstrap_objects() -> list[dict[str, Any]]:
    """What Kueue's manager expects before it starts: its namespace, the (empty) Secret its
    rotator fills, and the two webhook configurations it injects its CA into (no webhooks)."""
    base = WEBHOOK_SERVICE.removesuffix("-webhook-service")
    return [
        {"apiVersion": "v1", "kind": "Namespace", "metadata": {"name": NAMESPACE}},
        {
            "apiVersion": "v1",
            "kind": "Secret",
            "metadata": {"name": WEBHOOK_SECRET, "namespace": NAMESPACE},
        },
        *(
            {
                "apiVersion": "admissionregistration.k8s.io/v1",
                "kind": f"{kind}WebhookConfiguration",
                "metadata": {"name": f"{base}-{kind.lower()}-webhook-configuration"},
                "webhooks": [],
            }
            for kind in ("Validating", "Mutating")
        ),
    ]


def cert_dir(layout: Layout) -> Path:
    """Where the webhook server reads ``tls.crt`` and ``tls.key`` (a Secret volume in a pod)."""
    return layout.root / "kueue" / "certs"


def mount_certs(api: client.ApiClient, layout: Layout) -> bool:
    """Copy the rotator's certificate from its Secret into :func:`cert_dir`, as the kubelet's
    Secret volume would; False while the Secret is still empty."""
    try:
        secret = client.CoreV1Api(api).read_namespaced_secret(WEBHOOK_SECRET, NAMESPACE)
    except ApiException:
        return False
    data = secret.data or {}
    if not all(data.get(key) for key in ("tls.crt", "tls.key")):
        return False
    folder = cert_dir(layout)
    folder.mkdir(parents=True, exist_ok=True)
    for key in ("tls.crt", "tls.key", "ca.crt"):
        if data.get(key):
            target = folder / key
            target.write_bytes(base64.b64decode(data[key]))
            target.chmod(0o600)
    return True


def config_path(layout: Layout) -> Path:
    """The manager's Configuration file."""
    return layout.root / "kueue" / "config.yaml"


def configuration(layout: Layout, *, health_port: int, webhook_port: int) -> dict[str, Any]:
    """Kueue's ``Configuration`` for this cluster: loopback ports, no leader election, no metrics
    listener, fair sharing on (it only acts on ClusterQueues in a cohort, and admission fair
    sharing only on ClusterQueues that opt in with ``admissionScope``)."""
    return {
        "apiVersion": "config.kueue.x-k8s.io/v1beta2",
        "kind": "Configuration",
        "namespace": NAMESPACE,
        "health": {"healthProbeBindAddress": f"127.0.0.1:{health_port}"},
        "metrics": {"bindAddress": "0"},
        "webhook": {
            "host": "127.0.0.1",
            "port": webhook_port,
            "certDir": str(cert_dir(layout)),
        },
        "leaderElection": {"leaderElect": False},
        "internalCertManagement": {
            "enable": True,
            "webhookServiceName": WEBHOOK_SERVICE,
            "webhookSecretName": WEBHOOK_SECRET,
        },
        "integrations": {"frameworks": list(FRAMEWORKS)},
        "fairSharing": {
            "preemptionStrategies": ["LessThanOrEqualToFinalShare", "LessThanInitialShare"]
        },
        "admissionFairSharing": {"usageHalfLifeTime": "10m", "usageSamplingInterval": "10s"},
    }


def argv(kueue_binary: Path, layout: Layout, kubeconfig: Path) -> list[str]:
    """The manager's command line (the on-demand visibility API is off: it is an aggregated
    API server this cluster does not route to)."""
    return [
        str(kueue_binary),
        f"--config={config_path(layout)}",
        f"--kubeconfig={kubeconfig}",
        "--feature-gates=VisibilityOnDemand=false",
        "--zap-log-level=info",
    ]


def write_config(layout: Layout, *, health_port: int, webhook_port: int) -> Path:
    """Write the Configuration; return its path."""
    path = config_path(layout)
    path.parent.mkdir(parents=True, exist_ok=True)
    document = configuration(layout, health_port=health_port, webhook_port=webhook_port)
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path
