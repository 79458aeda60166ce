"""Per-scenario result records, as kept in SimEnvironment and ScenarioBatch status.

The wire shape is ``api``'s ``ScenarioResult``; inside the operator a record is this frozen
dataclass so that views, plans and comparisons are plain values.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from simtest_operator.verdicts import ScenarioOutcome, Verdict

REASON_MAX = 1024
"""``ScenarioResult.reason`` is limited to this many characters by the CRD schema."""


def clip(text: str, limit: int = REASON_MAX) -> str:
    """One line of at most ``limit`` characters."""
    flat = " ".join(text.split())
    return flat if len(flat) <= limit else flat[: limit - 1] + "…"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ResultRecord:
    """The result of one scenario (final, or of one attempt while retries remain)."""

    id: str
    verdict: Verdict
    reason: str = ""
    metrics: tuple[tuple[str, float], ...] = ()
    duration_seconds: float = 0.0
    attempts: int = 1
    artifacts: tuple[tuple[str, str], ...] = ()
    results_stored: bool = True
    """False when the pod could not store the attempt in the results database."""
    sut_image_id: str = ""
    """The SUT image the kubelet ran for this attempt (``repo@sha256:…`` or ``sha256:…``)."""

    def to_wire(self) -> dict[str, Any]:
        """``ScenarioResult`` wire form."""
        wire: dict[str, Any] = {
            "id": self.id,
            "verdict": self.verdict.value,
            "reason": clip(self.reason),
            "durationSeconds": round(max(self.duration_seconds, 0.0), 3),
            "attempts": max(self.attempts, 1),
        }
        if self.metrics:
            wire["metrics"] = dict(self.metrics)
        if self.artifacts:
            wire["artifacts"] = dict(self.artifacts)
        if not self.results_stored:
            wire["resultsStored"] = False
        if self.sut_image_id:
            wire["sutImageId"] = self.sut_image_id
        return wire

    @classmethod
    def from_wire(cls, data: Mapping[str, Any]) -> ResultRecord:
        """Inverse of :meth:`to_wire` (lenient about missing optional fields)."""
        return cls(
            id=str(data["id"]),
            verdict=Verdict(data["verdict"]),
            reason=str(data.get("reason", "")),
            metrics=tuple(
                sorted((str(k), float(v)) for k, v in (data.get("metrics") or {}).items())
            ),
            duration_seconds=float(data.get("durationSeconds", 0.0)),
            attempts=int(data.get("attempts", 1)),
            artifacts=tuple(
                sorted((str(k), str(v)) for k, v in (data.get("artifacts") or {}).items())
            ),
            results_stored=data.get("resultsStored") is not False,
            sut_image_id=str(data.get("sutImageId") or ""),
        )

    @classmethod
    def from_outcome(
        cls, outcome: ScenarioOutcome, *, attempts: int, duration: float | None = None
    ) -> ResultRecord:
        """A record from the runner's compact outcome."""
        return cls(
            id=outcome.scenario_id,
            verdict=outcome.verdict,
            reason=clip(outcome.reason),
            metrics=tuple(sorted((k, float(v)) for k, v in outcome.metrics.items())),
            duration_seconds=outcome.wall_seconds if duration is None else duration,
            attempts=attempts,
            artifacts=tuple(sorted(outcome.artifacts.items())),
        )
