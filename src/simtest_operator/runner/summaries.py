"""What a finished (or stopped) local run amounts to: counts, phase, exit code and its reason.

The exit codes are the CI contract of ``simtest run`` and ``simtest submit --wait``:
``0`` every scenario passed, ``1`` some failed (Failed or Timeout: verdicts on the system under
test), ``2`` errors or invalid input (Error, Invalid, a scenario not run, a bad manifest, an
interrupted run). Errors win over failures: a run whose infrastructure broke says nothing reliable.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence

from simtest_operator.verdicts import ScenarioOutcome, Verdict

EXIT_PASSED = 0
EXIT_FAILED = 1
EXIT_ERROR = 2


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Summary:
    """Final verdict counts over the whole frozen list, and what they mean."""

    total: int
    counts: Mapping[Verdict, int]
    """Final verdicts; scenarios without one are counted as ``Skipped``."""
    phase: str
    """The TestCampaign phase it corresponds to (Succeeded, Failed, Error, Cancelled)."""
    exit_code: int
    reason: str
    """One line for the terminal and CI logs."""

    def count(self, *verdicts: Verdict) -> int:
        """Scenarios whose final verdict is one of ``verdicts``."""
        return sum(self.counts.get(v, 0) for v in verdicts)


def summarise(
    scenario_ids: Sequence[str],
    outcomes: Mapping[str, ScenarioOutcome],
    *,
    interrupted: bool = False,
) -> Summary:
    """Summarise final ``outcomes`` (by scenario id) over the frozen list ``scenario_ids``."""
    counts = dict.fromkeys(Verdict, 0)
    for ident in scenario_ids:
        outcome = outcomes.get(ident)
        counts[outcome.verdict if outcome is not None else Verdict.SKIPPED] += 1
    total = len(scenario_ids)
    done = total - counts[Verdict.SKIPPED]
    if interrupted:
        return Summary(
            total=total,
            counts=counts,
            phase="Cancelled",
            exit_code=EXIT_ERROR,
            reason=f"interrupted after {done} of {total} scenarios; run the same command again "
            "to resume",
        )
    broken = [i for i in scenario_ids if _verdict(outcomes, i) in (Verdict.ERROR, Verdict.INVALID)]
    not_run = counts[Verdict.SKIPPED]
    if broken or not_run:
        parts = []
        if broken:
            first = outcomes[broken[0]]
            parts.append(
                f"{len(broken)} of {total} scenarios could not be judged "
                f"(first: {broken[0]}: {first.verdict.value}: {first.reason or 'no reason given'})"
            )
        if not_run:
            parts.append(f"{not_run} not run")
        return Summary(
            total=total, counts=counts, phase="Error", exit_code=EXIT_ERROR, reason="; ".join(parts)
        )
    failing = [
        i for i in scenario_ids if _verdict(outcomes, i) in (Verdict.FAILED, Verdict.TIMEOUT)
    ]
    if failing:
        first = outcomes[failing[0]]
        return Summary(
            total=total,
            counts=counts,
            phase="Failed",
            exit_code=EXIT_FAILED,
            reason=f"{len(failing)} of {total} scenarios failed "
            f"(first: {failing[0]}: {first.verdict.value}: {first.reason or 'no reason given'})",
        )
    return Summary(
        total=total,
        counts=counts,
        phase="Succeeded",
        exit_code=EXIT_PASSED,
        reason=f"all {total} scenarios passed",
    )


def _verdict(outcomes: Mapping[str, ScenarioOutcome], ident: str) -> Verdict | None:
    outcome = outcomes.get(ident)
    return outcome.verdict if outcome is not None else None
