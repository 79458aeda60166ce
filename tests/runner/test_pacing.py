"""``spec.environment.simulator.realTimeFactor``: the run is paced against the wall clock.

Covers: with a factor of 20 a 10-second scenario takes at least half a second of wall time (the
engine alone runs it about 100x real time), with the same verdict and simulated time as unpaced.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.runner import scenario_execution
from simtest_operator.settings import SimulationSettings

SCENARIO = (
    Path(__file__).resolve().parents[2]
    / "scenarios"
    / "smoke"
    / "following_highway_v25_thw2_drop5_d2.xosc"
)


@pytest.mark.slow
def test_real_time_factor_paces_the_run(tmp_path: Path) -> None:
    def run(factor: float) -> scenario_execution.RunReport:
        return scenario_execution.run_scenario(
            scenario_execution.RunRequest(
                scenario=SCENARIO,
                nets_dir=tmp_path / "nets",
                simulation=SimulationSettings(real_time_factor=factor),
                record=False,
            )
        )

    free = run(0.0).outcome
    paced = run(20.0).outcome
    assert paced.verdict == free.verdict
    assert paced.simulated_seconds == pytest.approx(free.simulated_seconds)
    assert paced.wall_seconds >= paced.simulated_seconds / 20.0 - 0.05
