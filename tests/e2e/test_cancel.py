"""Cancellation end to end on the dev control plane with kwok nodes.

Covers: ``spec.cancel`` set mid-run deletes the running simulator pods, ends their scenarios and
every unstarted one ``Skipped`` ("cancelled"), phase ``Cancelled`` with ``Complete=True`` reason
``Cancelled`` and a ``Cancelled`` event, no pod is created afterwards, and setting ``cancel`` back
to false does nothing; ``activeDeadlineSeconds`` through ``simtest submit --wait``: the campaign
ends ``Cancelled`` (``DeadlineExceeded``) and submit exits 2 with a one-line reason.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import yaml

from tests.e2e import support

LONG_RUN = {"simulator": {"podAnnotations": {"simtest.dev/fake-duration": "300s"}}}
"""kwok "runs" every pod of these campaigns for 5 minutes: cancellation ends them, nothing else."""


def _patch_spec(cluster: support.Cluster, name: str, spec: dict[str, Any]) -> None:
    cluster.custom.patch_namespaced_custom_object(
        support.GROUP, support.VERSION, cluster.namespace, "testcampaigns", name, {"spec": spec}
    )


def _wait(predicate: Any, *, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.25)
    raise AssertionError(f"not reached within {timeout}s: {what}")


def _condition(status: dict[str, Any], kind: str) -> dict[str, Any]:
    return next(c for c in status.get("conditions", []) if c["type"] == kind)


def test_cancel_deletes_running_pods_and_skips_the_rest(
    operator: support.OperatorProcess, cluster: support.Cluster, sources: Path
) -> None:
    support.scenario_files(sources / "scenarios", [f"long-{i:02d}.xosc" for i in range(10)])
    body = support.campaign(
        "cancelme",
        execution={"maxParallel": 3, "batchSize": 4, "timeoutSeconds": 600},
        values=LONG_RUN,
    )
    with support.running(operator):
        cluster.create(body)
        _wait(
            lambda: len([p for p in cluster.pods() if p.status.phase == "Running"]) == 3,
            timeout=90,
            what="three simulator pods running",
        )
        running = {p.metadata.name for p in cluster.pods()}
        _patch_spec(cluster, "cancelme", {"cancel": True})
        status = cluster.wait_complete("cancelme", timeout=90, alive=operator.alive)
        _wait(lambda: not cluster.pods(), timeout=60, what="every simulator pod deleted")
        _patch_spec(cluster, "cancelme", {"cancel": False})  # un-cancelling does nothing
        time.sleep(3)  # give a (wrong) restart every chance to show up
        after = cluster.status("cancelme")
        pods_after = cluster.pods()
        events = cluster.core.list_namespaced_event(
            cluster.namespace, field_selector="involvedObject.name=cancelme"
        ).items
    assert status["phase"] == "Cancelled"
    complete = _condition(status, "Complete")
    assert (complete["status"], complete["reason"]) == ("True", "Cancelled")
    assert (status["total"], status["skipped"], status["passed"], status["errored"]) == (
        10,
        10,
        0,
        0,
    )
    results = cluster.results("cancelme")  # one result per scenario of the existing batch(es)
    assert results and all(
        r["verdict"] == "Skipped" and r["reason"] == "cancelled" for r in results.values()
    )
    assert len(running) == 3 and status["batches"] == 1
    assert after["phase"] == "Cancelled" and not pods_after
    assert any(e.reason == "Cancelled" for e in events), [e.reason for e in events]
    assert "Traceback" not in operator.log_text()


def test_deadline_through_submit_exits_2_with_the_reason(
    operator: support.OperatorProcess,
    cluster: support.Cluster,
    sources: Path,
    kubeconfig_path: Path,
    tmp_path: Path,
) -> None:
    support.scenario_files(sources / "scenarios", ["pass-0.xosc", "pass-1.xosc", "long-0.xosc"])
    body = support.campaign("deadline", execution={"maxParallel": 3, "timeoutSeconds": 600})
    body["spec"]["activeDeadlineSeconds"] = 20
    manifest = tmp_path / "deadline.yaml"
    manifest.write_text(yaml.safe_dump(body), encoding="utf-8")
    # only long-0 runs for 5 minutes; the two others pass after 2 s
    long_template = sources.parent / "templates" / "kwok" / "values.yaml.j2"
    text = long_template.read_text(encoding="utf-8")
    long_template.write_text(
        text.replace(
            '{%- set seconds = 6 if scenario.id.startswith("slow-") else 2 %}',
            '{%- set seconds = 300 if scenario.id.startswith("long-") else 2 %}',
        ),
        encoding="utf-8",
    )
    with support.running(operator):
        submitted = support.submit(
            manifest,
            namespace=cluster.namespace,
            kubeconfig=kubeconfig_path,
            timeout=120,
        )
        status = cluster.status("deadline")
    output = submitted.stdout + submitted.stderr
    assert submitted.returncode == 2, output
    assert "deadline: cancelled: DeadlineExceeded: activeDeadlineSeconds (20 s) exceeded" in output
    assert status["phase"] == "Cancelled"
    assert _condition(status, "Complete")["reason"] == "DeadlineExceeded"
    results = cluster.results("deadline")
    assert {k: r["verdict"] for k, r in results.items()} == {
        "pass-0.xosc": "Passed",
        "pass-1.xosc": "Passed",
        "long-0.xosc": "Skipped",
    }
    assert results["long-0.xosc"]["reason"].startswith("cancelled: activeDeadlineSeconds")
