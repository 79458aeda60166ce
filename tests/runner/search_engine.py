"""A stand-in system under test for local search runs: its verdict follows the proposal's
parameter values (it fails where the cut-in gap is short and the ego fast), so a search has
something to find. Module level, so spawned workers can import it."""

from __future__ import annotations

import os
import time

from simtest_operator.runner.tasks import ScenarioTask
from simtest_operator.sut.processes import SutProcesses
from simtest_operator.verdicts import ScenarioOutcome, Verdict


def execute(task: ScenarioTask, processes: SutProcesses | None = None) -> ScenarioOutcome:
    """Failed below a margin of zero; ``minTTC`` is the margin. Sleeps a little so several
    workers are busy at once (it starts no SUT: ``processes`` stays unused)."""
    gap = float(task.overrides["CutInGap"])
    ego = float(task.overrides["EgoSpeed"])
    margin = max(gap - 20.0, 0.0) / 5 + max(25.0 - ego, 0.0) / 5
    time.sleep(0.05 + (hash(task.scenario_id) % 5) / 100)
    return ScenarioOutcome(
        scenario_id=task.scenario_id,
        verdict=Verdict.FAILED if margin == 0.0 else Verdict.PASSED,
        reason="minTTC below 1.0 s" if margin == 0.0 else "",
        metrics={"minTTC": margin, "pid": float(os.getpid())},
        simulated_seconds=5.0,
        wall_seconds=0.05,
        attempts=task.attempt,
    )
