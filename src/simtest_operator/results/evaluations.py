"""Evaluation records: re-evaluations of recorded runs, as the store takes and returns them.

An evaluation is one criteria set applied to the runs of one campaign run; the runs' original
verdicts stay untouched in ``runs``. The records are plain values so that ``results`` does not
depend on ``evaluation`` (the two sit on one layer): the CLI converts between them.
"""

from __future__ import annotations

import dataclasses
import datetime
import hashlib
import json
from collections.abc import Mapping
from typing import Any, NewType

from simtest_operator.results.records import RunKey
from simtest_operator.verdicts import Verdict

EvaluationId = NewType("EvaluationId", str)
"""Identifies one evaluation, e.g. ``strict-20250101T120000Z-3f2a9c1d``."""

EVIDENCE = ("complete", "incomplete", "missing")


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EvaluationInfo:
    """What an evaluation applies to which run."""

    run_key: RunKey
    criteria_name: str
    criteria: Mapping[str, Any]
    """The whole criteria set (JSON-compatible), kept so the evaluation can be traced and redone."""
    created_at: datetime.datetime
    versions: Mapping[str, str] = dataclasses.field(default_factory=dict)

    @property
    def criteria_sha256(self) -> str:
        return hashlib.sha256(
            json.dumps(self.criteria, sort_keys=True, separators=(",", ":")).encode()
        ).hexdigest()


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EvaluationRecord:
    """An evaluation as stored."""

    evaluation_id: EvaluationId
    info: EvaluationInfo
    finished_at: datetime.datetime | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class MetricCheck:
    """A base-scenario metric, with its threshold and result when it was checked."""

    value: float
    threshold: float | None = None
    passed: bool | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class StoredBaseScenario:
    """One base scenario of an evaluated run."""

    kind: str
    actor: int | None
    start: float
    end: float
    verdict: Verdict
    reason: str = ""
    detail: str = ""
    metrics: Mapping[str, MetricCheck] = dataclasses.field(default_factory=dict)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EvaluatedRun:
    """The new evaluation of one attempt."""

    scenario_id: str
    attempt: int
    verdict: Verdict
    reason: str
    evidence: str
    quality: Mapping[str, float] = dataclasses.field(default_factory=dict)
    issues: tuple[str, ...] = ()
    metrics: Mapping[str, float] = dataclasses.field(default_factory=dict)
    base_scenarios: tuple[StoredBaseScenario, ...] = ()
    recording: str = ""
    """Where the recording was read from (URI or path), for traceability."""


def derive_evaluation_id(info: EvaluationInfo) -> EvaluationId:
    """``<criteria name>-<UTC created>-<8 hex of run key, criteria digest and creation time>``."""
    created = info.created_at.astimezone(datetime.UTC)
    identity = f"{info.run_key}#{info.criteria_sha256}@{created.isoformat()}"
    digest = hashlib.sha256(identity.encode()).hexdigest()[:8]
    name = "".join(c if c.isalnum() or c in "-_." else "-" for c in info.criteria_name)[:40]
    return EvaluationId(f"{name}-{created:%Y%m%dT%H%M%SZ}-{digest}")


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EvaluationMessage:
    """What ``simtest evaluate --summary-file`` writes and the operator's evaluation step reads
    back from the Job pod's termination message: which evaluation of which run, and the summary
    line. JSON, because the kubelet keeps at most 4 KiB of it; anything else (a crash's log tail)
    reads back as the summary alone."""

    summary: str
    evaluation_id: str = ""
    run_key: str = ""

    MAX_BYTES = 4096

    def to_text(self) -> str:
        """The message, shortened to fit the kubelet's limit."""
        summary = self.summary
        while True:
            text = json.dumps(
                {"evaluation": self.evaluation_id, "run": self.run_key, "summary": summary},
                ensure_ascii=False,
            )
            if len(text.encode()) <= self.MAX_BYTES or not summary:
                return text
            summary = summary[: len(summary) * 3 // 4] + "…"

    @classmethod
    def from_text(cls, text: str) -> EvaluationMessage:
        """Read a termination message (ours, or any text)."""
        try:
            data = json.loads(text)
        except ValueError:
            data = None
        if isinstance(data, dict) and isinstance(data.get("summary"), str):
            return cls(
                summary=data["summary"],
                evaluation_id=str(data.get("evaluation") or ""),
                run_key=str(data.get("run") or ""),
            )
        lines = [line.strip() for line in text.strip().splitlines() if line.strip()]
        return cls(summary=" | ".join(lines[-3:]))
