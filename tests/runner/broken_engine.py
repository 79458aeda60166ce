"""An engine module that cannot start in a worker process (for the executor's start-up guard):
importing it in a spawned child exits the process, as a broken installation would."""

from __future__ import annotations

import multiprocessing
import os

from simtest_operator.runner.tasks import ScenarioTask
from simtest_operator.verdicts import ScenarioOutcome

# ``_inheriting`` is set while a spawned child unpickles its target, i.e. imports this module.
if getattr(multiprocessing.current_process(), "_inheriting", False):
    os._exit(3)


def execute(task: ScenarioTask) -> ScenarioOutcome:
    """Never reached in a worker."""
    raise AssertionError(task)
