"""The real engine behind the executor's task interface.

:func:`execute` adapts a :class:`~simtest_operator.runner.tasks.ScenarioTask` to the engine's
:func:`~simtest_operator.runner.scenario_execution.run_scenario` (simulation, online evaluation and
recording in this process). The engine gets the wall-clock limit pods use too
(:func:`~simtest_operator.runner.scenario_execution.soft_limit`, a little below the executor's); the
executor's kill is the backstop for a simulator that stops responding altogether.
"""

from __future__ import annotations

from simtest_operator.openscenario import LoadOptions
from simtest_operator.runner import scenario_execution
from simtest_operator.runner.tasks import ScenarioTask
from simtest_operator.sut.processes import SutProcesses
from simtest_operator.verdicts import ScenarioOutcome


def execute(task: ScenarioTask, processes: SutProcesses | None = None) -> ScenarioOutcome:
    """Run one attempt of a scenario on the SUMO stand-in (module-level: workers import it)."""
    request = scenario_execution.RunRequest(
        scenario=task.scenario_path,
        nets_dir=task.settings.cache.nets,
        scenario_id=task.scenario_id,
        overrides=dict(task.overrides),
        sut=task.sut,
        criteria=task.criteria,
        simulation=task.settings.simulation,
        output_dir=task.out_dir,
        record=task.record,
        wall_clock_limit=scenario_execution.soft_limit(task.timeout_seconds),
        loading=LoadOptions(source_root=task.source_root, maps=task.settings.maps),
    )
    return scenario_execution.run_scenario(request, processes=processes).outcome
