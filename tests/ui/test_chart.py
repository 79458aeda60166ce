"""The operator chart's optional results UI, rendered by the real helm (no cluster).

Covers: off by default (no UI objects); enabled, a Deployment running ``simtest ui`` on all
addresses with the DSN from the named Secret key, probes on ``/healthz``, Pod Security
``restricted``, no service-account token, and a Service whose selector matches the UI pods and
not the operator's (nor the operator's selectors the UI pods); `helm lint --strict` is clean;
enabling it without a Secret name, or with a typo, is refused with a clear message.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from tests.charts.helmtools import (
    OPERATOR_CHART,
    Tool,
    documents,
    find,
    helm,
    restricted_problems,
    template,
    tools_home,
)

__all__ = ["helm", "tools_home"]
ENABLED = {"ui": {"enabled": True, "databaseSecretRef": {"name": "results-db", "key": "url"},
                  "service": {"port": 8088}}}  # fmt: skip


def _render(helm: Tool, values: dict[str, Any]) -> list[dict[str, Any]]:
    return documents(template(helm, OPERATOR_CHART, values=values).stdout)


def test_off_by_default(helm: Tool) -> None:
    names = {doc["metadata"]["name"] for doc in _render(helm, {})}
    assert not any(name.endswith("-ui") for name in names)


def test_enabled(helm: Tool, tmp_path: Path) -> None:
    docs = _render(helm, ENABLED)
    deployment = find(docs, "Deployment", "simtest-operator-ui")
    pod = deployment["spec"]["template"]
    (container,) = pod["spec"]["containers"]
    assert container["args"] == ["ui", "--host", "0.0.0.0", "--port", "8080"]
    assert container["env"] == [{"name": "SIMTEST_RESULTS_DATABASE", "valueFrom": {
        "secretKeyRef": {"name": "results-db", "key": "url"}}}]  # fmt: skip
    assert container["readinessProbe"]["httpGet"] == {"path": "/healthz", "port": "http"}
    assert restricted_problems(pod["spec"]) == []
    assert pod["spec"]["automountServiceAccountToken"] is False
    service = find(docs, "Service", "simtest-operator-ui")
    assert service["spec"]["ports"][0]["port"] == 8088
    ui_labels = pod["metadata"]["labels"]
    assert all(ui_labels.get(k) == v for k, v in service["spec"]["selector"].items())
    operator = find(docs, "Deployment", "simtest-operator")
    operator_selector = operator["spec"]["selector"]["matchLabels"]
    assert not all(ui_labels.get(k) == v for k, v in operator_selector.items())
    assert not all(
        operator["spec"]["template"]["metadata"]["labels"].get(k) == v
        for k, v in service["spec"]["selector"].items()
    )
    values = tmp_path / "values.yaml"
    values.write_text(yaml.safe_dump(ENABLED))
    linted = helm.run("lint", "--strict", OPERATOR_CHART, "--values", values)
    assert "0 chart(s) failed" in linted.stdout and "[WARNING]" not in linted.stdout


def test_refused(helm: Tool) -> None:
    missing = template(helm, OPERATOR_CHART, values={"ui": {"enabled": True}}, check=False)
    assert missing.returncode != 0
    assert "ui.enabled needs ui.databaseSecretRef.name" in missing.stderr
    typo = template(helm, OPERATOR_CHART, values={"ui": {"enable": True}}, check=False)
    assert typo.returncode != 0 and "'enable' not allowed" in typo.stderr
