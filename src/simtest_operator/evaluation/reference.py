"""Comparison with a reference player's output (``esmini-reference.json``).

For a scenario that ran, compare the storyboard end time and, per entity, the reference point
positions at the common 1 Hz sample times. A run *matches* when the end time is within
:data:`END_TOLERANCE` and every entity's median position error is at most
:data:`MEDIAN_TOLERANCE`. Differences the stand-in makes on purpose (the ego driven by the SUT
model, esmini-specific controllers it does not imitate) are passed in as labels and reported
next to the figures, never used to hide them.
"""

from __future__ import annotations

import dataclasses
import json
import math
import statistics
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from simtest_operator.errors import EvaluationError

END_TOLERANCE = 0.5
"""Seconds the storyboard end time may differ."""
MEDIAN_TOLERANCE = 1.0
"""Metres the median position error of every entity may reach."""

Sample = Sequence[float]
"""(t, x, y, heading, speed)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class EntityError:
    """Position error of one entity over the common sample times."""

    name: str
    samples: int
    median: float
    maximum: float


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Comparison:
    """How one run compares with the reference."""

    key: str
    end_difference: float | None
    """Our end time minus the reference's (None when either did not end)."""
    entities: tuple[EntityError, ...]
    missing: tuple[str, ...]
    """Reference entities we have no samples for."""
    intended: tuple[str, ...]
    """Labels of intended differences (SUT-driven ego, esmini controllers)."""

    @property
    def worst_median(self) -> float:
        return max((e.median for e in self.entities), default=0.0)

    @property
    def match(self) -> bool:
        ends = self.end_difference is not None and abs(self.end_difference) <= END_TOLERANCE
        return (
            ends and not self.missing and all(e.median <= MEDIAN_TOLERANCE for e in self.entities)
        )


def load(path: Path) -> Mapping[str, Any]:
    """The ``scenarios`` mapping of a reference file."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise EvaluationError(f"cannot read reference file {path}: {exc}") from exc
    scenarios = data.get("scenarios") if isinstance(data, dict) else None
    if not isinstance(scenarios, dict):
        raise EvaluationError(f"reference file {path} has no 'scenarios' object")
    return scenarios


def find(reference: Mapping[str, Any], scenario: Path) -> str | None:
    """The reference key for a scenario file: the longest key that is a suffix of its path."""
    text = scenario.resolve().as_posix()
    best: str | None = None
    for key in reference:
        tail = key.split("/", 1)[1] if key.startswith("esmini/") else key
        if text.endswith("/" + tail) and (best is None or len(key) > len(best)):
            best = key
    return best


def compare(
    key: str,
    entry: Mapping[str, Any],
    *,
    samples: Mapping[str, Sequence[Sample]],
    end_time: float | None,
    intended: Sequence[str] = (),
    time_limit: float | None = None,
) -> Comparison:
    """Compare one run's 1 Hz samples and end time with a reference entry.

    ``end_time`` None means our storyboard did not end within ``time_limit``; if the reference
    did not end by then either, the end times count as equal (and that is labelled).
    """
    ref_end = entry.get("end_time")
    end_difference = (
        end_time - float(ref_end) if end_time is not None and ref_end is not None else None
    )
    labels = list(intended)
    if (
        end_time is None
        and ref_end is not None
        and time_limit is not None
        and (float(ref_end) >= time_limit)
    ):
        end_difference = 0.0
        labels.append(f"neither ended within {time_limit:g} s")
    rc = entry.get("rc")
    if rc not in (None, 0, "timeout"):
        # the reference player failed on the file (a path only valid from another folder):
        # there is nothing to match, and running it is the intended difference
        labels.append(f"reference player failed (rc {rc})")
    errors: list[EntityError] = []
    missing: list[str] = []
    for name, ref_samples in (entry.get("samples_1hz") or {}).items():
        ours = {round(s[0]): s for s in samples.get(name, ())}
        distances = [
            math.hypot(ours[round(r[0])][1] - r[1], ours[round(r[0])][2] - r[2])
            for r in ref_samples
            if round(r[0]) in ours
        ]
        if not distances:
            missing.append(name)
            continue
        errors.append(
            EntityError(
                name=name,
                samples=len(distances),
                median=statistics.median(distances),
                maximum=max(distances),
            )
        )
    return Comparison(
        key=key,
        end_difference=end_difference,
        entities=tuple(errors),
        missing=tuple(missing),
        intended=tuple(labels),
    )
