"""Local workers and pods hand the engine the same request for the same scenario and timeout.

The local executor (``engines.execute``) and the pod's runner (``entrypoint.requests_for``) build
their ``RunRequest`` separately; the limits in it decide when a slow run ends as ``Timeout``, so
they must be one rule, or a scenario near its limit could pass locally and time out in a pod.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from simtest_operator.runner import engines, entrypoint, scenario_execution
from simtest_operator.runner.tasks import ScenarioTask
from simtest_operator.verdicts import ScenarioOutcome, Verdict
from tests.runner import podsupport


def _local_request(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, timeout: float
) -> scenario_execution.RunRequest:
    seen: list[scenario_execution.RunRequest] = []

    def capture(
        request: scenario_execution.RunRequest, *, processes: object = None
    ) -> scenario_execution.RunReport:
        seen.append(request)
        outcome = ScenarioOutcome(scenario_id="s", verdict=Verdict.PASSED)
        return scenario_execution.RunReport(outcome=outcome, storyboard_complete=True)

    monkeypatch.setattr(scenario_execution, "run_scenario", capture)
    job = podsupport.job(tmp_path, {"s": "pass"})
    engines.execute(
        ScenarioTask(
            scenario_id="s",
            scenario_path=tmp_path / "s.xosc",
            out_dir=tmp_path / "out",
            settings=job.settings,
            timeout_seconds=timeout,
        )
    )
    (request,) = seen
    return request


@pytest.mark.parametrize("timeout", [5.0, 30.0, 600.0])
def test_local_and_pod_runs_get_the_same_wall_clock_limit(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, timeout: float
) -> None:
    job = podsupport.job(tmp_path, {"s": "pass"})
    job = dataclasses.replace(job, spec=dataclasses.replace(job.spec, timeout_seconds=timeout))
    (scenario,) = job.spec.scenarios
    pod = entrypoint.requests_for(job, scenario, tmp_path / "s.xosc")
    local = _local_request(tmp_path, monkeypatch, timeout)
    assert pod.wall_clock_limit == local.wall_clock_limit
    assert pod.wall_clock_limit == scenario_execution.soft_limit(timeout)
    assert pod.wall_clock_limit is not None and pod.wall_clock_limit < timeout
