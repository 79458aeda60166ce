"""One attempt at one scenario, as handed to a worker process, and the function that runs it.

A task is a plain, picklable value: everything a worker needs (the local scenario file, parameter
overrides, the system under test, the criteria, the simulator settings, where to write) and
nothing it would have to look up. The function that executes it is passed by reference, so the
same executor drives the real engine and the documented test double in :mod:`fakes`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

from simtest_operator.drivermodel import SutConfig
from simtest_operator.evaluation import Criteria
from simtest_operator.settings import Settings
from simtest_operator.verdicts import ScenarioOutcome

if TYPE_CHECKING:
    from simtest_operator.sut.processes import SutProcesses

RECORDING = "recording.mcap"
"""File name of the omega-prime recording inside a scenario's output folder."""
LOG = "log.txt"
"""File name of the log (every attempt appended, with a header line per attempt)."""
RESULT = "result.json"
"""File name of the full result."""
ENGINE_LOG = "run.log"
"""File name of the engine's own summary log (written by the real engine only)."""
SUT_LOG = "sut.log"
"""File name of what a SUT process the runner started printed (bounded, stdout and stderr)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ScenarioTask:
    """What a worker needs to run one attempt."""

    scenario_id: str
    scenario_path: Path
    """Local file, already located and sha256-verified."""
    source_root: Path | None = None
    """Folder the scenario's references must stay in (its fetched source); None: a local file."""
    overrides: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """OpenSCENARIO global parameter values."""
    out_dir: Path
    """The scenario's output folder (recording, log and result go here)."""
    attempt: int = 1
    sut: SutConfig = dataclasses.field(default_factory=SutConfig)
    criteria: Criteria = dataclasses.field(default_factory=Criteria)
    settings: Settings
    """Cache folders and simulation settings (step, seed, recording rate) of the campaign."""
    record: bool = True
    """Write an omega-prime recording."""
    timeout_seconds: float = 60.0
    """Wall-clock limit the executor enforces; informative for the engine."""

    @property
    def recording_path(self) -> Path:
        """Where the recording goes."""
        return self.out_dir / RECORDING

    @property
    def log_path(self) -> Path:
        """Where the attempt's log lines go."""
        return self.out_dir / LOG


class ExecuteFn(Protocol):
    """Runs one task in the current process and returns its outcome. Must be a module-level
    function (workers are spawned and receive it by reference). ``processes`` are the worker's
    warm SUT processes (``lifetime: worker``). Raising is allowed: ScenarioError becomes
    Invalid, anything else Error."""

    def __call__(
        self, task: ScenarioTask, /, processes: SutProcesses | None = None
    ) -> ScenarioOutcome: ...


ARTIFACT_FILES: Mapping[str, str] = {
    "recording": RECORDING,
    "log": LOG,
    "engineLog": ENGINE_LOG,
    "sutLog": SUT_LOG,
}
"""Artifacts a scenario folder may hold besides its result, by name in ``outcome.artifacts``."""
