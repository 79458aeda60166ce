"""What a real node needs from the cluster beyond its kubelet: the simulator-slot device plugin.

The dev cluster installs exactly what a user installs: the device-plugin DaemonSet of the
operator chart (``charts/simtest-operator``, ``devicePlugin.enabled``), rendered by ``helm
template`` and created in ``kube-system`` (its pods mount the kubelet's device-plugin directory,
which Pod Security allows only in a privileged namespace). So the chart's manifest is what runs
against the real kubelet in every test session, not a copy of it.
"""

from __future__ import annotations

import subprocess
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import yaml
from kubernetes import client, utils
from kubernetes.client.exceptions import ApiException

from simtest_operator.devcluster.nodes import SIMULATOR_RESOURCE
from simtest_operator.errors import ClusterError

CHART = Path("charts/simtest-operator")
"""The operator chart, relative to the repository root."""
DEVICE_PLUGIN_TEMPLATE = "templates/device-plugin.yaml"
NAMESPACE = "kube-system"


def find_chart(start: Path) -> Path:
    """The operator chart of the checkout containing ``start`` (searching upwards)."""
    for folder in (start.resolve(), *start.resolve().parents):
        if (folder / CHART / "Chart.yaml").is_file():
            return folder / CHART
    raise ClusterError(f"cannot find {CHART} above {start}; run this from a simtest checkout")


def device_plugin_documents(
    helm: Path, chart: Path, *, image: str, slots: int
) -> list[dict[str, Any]]:
    """The chart's device-plugin objects for ``image`` with ``slots`` per node."""
    repository, _, tag = image.rpartition(":")
    command = [
        str(helm), "template", "simtest", str(chart), "--namespace", NAMESPACE,
        "--show-only", DEVICE_PLUGIN_TEMPLATE,
        "--set", "devicePlugin.enabled=true",
        "--set", f"devicePlugin.image.repository={repository}",
        "--set", f"devicePlugin.image.tag={tag}",
        "--set", f"devicePlugin.slots={slots}",
    ]  # fmt: skip
    result = subprocess.run(command, capture_output=True, text=True, check=False, timeout=60)
    if result.returncode != 0:
        raise ClusterError(f"helm template of {chart} failed: {result.stderr.strip()}")
    return [d for d in yaml.safe_load_all(result.stdout) if isinstance(d, dict)]


def apply(api: client.ApiClient, documents: Iterable[Mapping[str, Any]]) -> None:
    """Create the objects (a fresh cluster has none of them)."""
    for document in documents:
        try:
            utils.create_from_dict(api, dict(document), namespace=NAMESPACE)  # type: ignore[no-untyped-call]
        except utils.FailToCreateError as exc:
            if not all(isinstance(e, ApiException) and e.status == 409 for e in exc.api_exceptions):
                raise ClusterError(f"cannot create {document.get('kind')}: {exc}") from exc


def simulator_slots(api: client.ApiClient, node: str) -> int:
    """``simtest.dev/simulator`` the node advertises as allocatable now (0 before the plugin)."""
    status = client.CoreV1Api(api).read_node(node).status
    allocatable = (status.allocatable if status else None) or {}
    return int(allocatable.get(SIMULATOR_RESOURCE, "0"))
