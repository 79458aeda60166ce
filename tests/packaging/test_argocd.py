"""The Argo CD pieces in deploy/argocd: the TestCampaign health check and the Applications.

Covers: the Lua health script, run by a real Lua 5.1 interpreter (Argo CD's gopher-lua dialect),
maps campaign states to Argo health (no status / stale generation / Pending / Running ->
Progressing; Succeeded with Complete=True -> Healthy; Succeeded without it -> Progressing;
Failed / Error / Cancelled -> Degraded with the reason and counters; Suspended -> Suspended); the
argocd-cm snippet embeds exactly that script under the key Argo CD looks up; the Applications
point at paths that exist (the operator chart) and use server-side apply.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml
from lupa import lua51

REPO = Path(__file__).resolve().parents[2]
ARGOCD = REPO / "deploy" / "argocd"
SCRIPT = (ARGOCD / "testcampaign-health.lua").read_text(encoding="utf-8")


def health(obj: dict[str, Any]) -> dict[str, str]:
    """Run the script the way Argo CD does: `obj` is a global, the script returns a table."""
    runtime = lua51.LuaRuntime(unpack_returned_tuples=True)
    runtime.globals().obj = runtime.table_from(obj, recursive=True)
    result = runtime.execute(SCRIPT)
    return {"status": result["status"], "message": result["message"]}


def campaign(
    phase: str | None = None, complete: str | None = None, **status: Any
) -> dict[str, Any]:
    body: dict[str, Any] = {"metadata": {"name": "smoke", "generation": 1}}
    if phase is not None:
        body["status"] = {"phase": phase, "observedGeneration": 1, "progress": "3/4", **status}
        if complete is not None:
            body["status"]["conditions"] = [
                {"type": "Running", "status": "False", "reason": "Done"},
                {
                    "type": "Complete",
                    "status": complete,
                    "reason": "R",
                    "message": "1 scenario failed",
                },
            ]
    return body


@pytest.mark.parametrize(
    ("body", "expected"),
    [
        (campaign(), "Progressing"),
        (campaign("Pending"), "Progressing"),
        (campaign("Resolving"), "Progressing"),
        (campaign("Running", "False", passed=2), "Progressing"),
        (campaign("Succeeded", "True", passed=4), "Healthy"),
        (campaign("Succeeded"), "Progressing"),
        (campaign("Succeeded", "False"), "Progressing"),
        (campaign("Failed", "True", failed=1), "Degraded"),
        (campaign("Error", "True", errored=1), "Degraded"),
        (campaign("Cancelled"), "Degraded"),
        (campaign("Suspended"), "Suspended"),
    ],
)
def test_health_per_state(body: dict[str, Any], expected: str) -> None:
    assert health(body)["status"] == expected


def test_messages_carry_reason_and_counters() -> None:
    failed = health(campaign("Failed", "True", passed=3, failed=1))
    assert failed["message"].startswith("Failed: 1 scenario failed")
    assert "3/4 done: 3 passed, 1 failed, 0 errored" in failed["message"]
    assert health(campaign())["message"] == "Waiting for the simtest operator"


def test_stale_status_is_progressing() -> None:
    body = campaign("Succeeded", "True")
    body["metadata"]["generation"] = 2
    result = health(body)
    assert result["status"] == "Progressing"
    assert "generation 2" in result["message"]


def test_config_map_embeds_the_script() -> None:
    config_map = yaml.safe_load((ARGOCD / "argocd-cm-health.yaml").read_text())
    assert config_map["metadata"] == {
        "name": "argocd-cm",
        "namespace": "argocd",
        "labels": {"app.kubernetes.io/name": "argocd-cm", "app.kubernetes.io/part-of": "argocd"},
    }
    assert config_map["data"] == {"resource.customizations.health.simtest.dev_TestCampaign": SCRIPT}


@pytest.mark.parametrize("name", ["application-operator.yaml", "application-campaigns.yaml"])
def test_applications(name: str) -> None:
    app = yaml.safe_load((ARGOCD / name).read_text())
    assert app["apiVersion"] == "argoproj.io/v1alpha1" and app["kind"] == "Application"
    assert "ServerSideApply=true" in app["spec"]["syncPolicy"]["syncOptions"]
    source = app["spec"]["source"]
    if source["repoURL"].endswith("simtest-operator.git"):
        assert (REPO / source["path"] / "Chart.yaml").is_file()
        values = source["helm"]["valuesObject"]
        chart_values = yaml.safe_load((REPO / source["path"] / "values.yaml").read_text())
        assert set(values) <= set(chart_values)
    else:
        assert app["spec"]["syncPolicy"]["automated"]["prune"] is False
