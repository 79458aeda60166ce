"""Verdicts: the one vocabulary for how a scenario run ended.

Shared by the simulator, the evaluator, the results store, the runner and the CRD status, so it
lives at the bottom of the layer stack.
"""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Mapping
from typing import Any


class Verdict(enum.StrEnum):
    """Final outcome of one scenario run."""

    PASSED = "Passed"
    """Every criterion held and the storyboard completed."""
    FAILED = "Failed"
    """The system under test violated a criterion. Never retried."""
    ERROR = "Error"
    """The infrastructure broke (pod lost, simulator crash, bad map). Retried per spec."""
    TIMEOUT = "Timeout"
    """The run did not finish within its time limit."""
    INVALID = "Invalid"
    """The scenario file cannot be run as written; the reason names the element."""
    SKIPPED = "Skipped"
    """The scenario was not run (campaign cancelled or filtered at run time)."""

    @property
    def retriable(self) -> bool:
        """Only infrastructure errors are worth another attempt."""
        return self is Verdict.ERROR

    @property
    def counts_as_ran(self) -> bool:
        """Passed, Failed and Timeout are verdicts on the system under test."""
        return self in (Verdict.PASSED, Verdict.FAILED, Verdict.TIMEOUT)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ScenarioOutcome:
    """The compact result of one attempt at one scenario.

    This is what the runner writes as a pod's termination message and next to its artifacts, what
    the local executor collects, what the results store keeps and what ScenarioBatch status lists.
    """

    scenario_id: str
    verdict: Verdict
    reason: str = ""
    """One line: which criterion failed, which element is unsupported, what broke."""
    metrics: Mapping[str, float] = dataclasses.field(default_factory=dict)
    """Key metrics, e.g. ``minTTC``, ``minTHW``, ``minDistance``, ``maxDecel``."""
    simulated_seconds: float = 0.0
    wall_seconds: float = 0.0
    attempts: int = 1
    artifacts: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """Artifact name -> URI (recording, log, full result file)."""
    ignored_elements: tuple[str, ...] = ()
    """OpenSCENARIO elements accepted but not simulated (environment, light state, ...)."""
    versions: Mapping[str, str] = dataclasses.field(default_factory=dict)
    """Component versions (simulator, SUT model, simtest) for reproducibility."""

    def to_json(self) -> dict[str, Any]:
        """A JSON-compatible dict (camelCase keys, as in result files and termination messages)."""
        return {
            "scenarioId": self.scenario_id,
            "verdict": self.verdict.value,
            "reason": self.reason,
            "metrics": dict(self.metrics),
            "simulatedSeconds": self.simulated_seconds,
            "wallSeconds": self.wall_seconds,
            "attempts": self.attempts,
            "artifacts": dict(self.artifacts),
            "ignoredElements": list(self.ignored_elements),
            "versions": dict(self.versions),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> ScenarioOutcome:
        """Inverse of :meth:`to_json`; unknown keys are ignored, missing optional ones defaulted."""
        return cls(
            scenario_id=str(data["scenarioId"]),
            verdict=Verdict(data["verdict"]),
            reason=str(data.get("reason", "")),
            metrics={str(k): float(v) for k, v in dict(data.get("metrics", {})).items()},
            simulated_seconds=float(data.get("simulatedSeconds", 0.0)),
            wall_seconds=float(data.get("wallSeconds", 0.0)),
            attempts=int(data.get("attempts", 1)),
            artifacts={str(k): str(v) for k, v in dict(data.get("artifacts", {})).items()},
            ignored_elements=tuple(str(e) for e in data.get("ignoredElements", ())),
            versions={str(k): str(v) for k, v in dict(data.get("versions", {})).items()},
        )
