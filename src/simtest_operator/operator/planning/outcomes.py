"""What one phase of a planning step decides: actions in order, plus when to look again."""

from __future__ import annotations

import dataclasses
import datetime

from simtest_operator.operator.actions import Action


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Outcome:
    """A phase's actions (applied in this order) and wake-ups, and the latencies it measured."""

    actions: tuple[Action, ...] = ()
    wakes: tuple[datetime.datetime, ...] = ()
    """Moments at which the step must run again even without a watch event."""
    start_latencies: tuple[float, ...] = ()
    """Queued-to-started seconds of environments first seen started (for the metrics)."""
    overheads: tuple[float, ...] = ()
    """Per-scenario orchestration seconds of environments deleted (for the metrics)."""

    def __add__(self, other: Outcome) -> Outcome:
        return Outcome(
            actions=self.actions + other.actions,
            wakes=self.wakes + other.wakes,
            start_latencies=self.start_latencies + other.start_latencies,
            overheads=self.overheads + other.overheads,
        )
