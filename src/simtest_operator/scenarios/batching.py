"""Batches: contiguous slices of the frozen list, and the order in which scenarios may start.

The operator turns each slice into a ScenarioBatch object; the local runner uses the same slices
so results name the same batch index either way. Two start policies exist (DESIGN §4): *window*
keeps up to N scenarios in flight and starts the next one as soon as any finishes, *barrier*
(the seed paper's behaviour, for comparison) starts a batch only when the previous one is done.
"""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Sequence

from simtest_operator.scenarios.pinned import PinnedScenario


class StartPolicy(enum.StrEnum):
    """When the next scenario may start."""

    WINDOW = "window"
    """As soon as a slot is free."""
    BARRIER = "barrier"
    """Only when every scenario of the previous batch has finished."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Batch:
    """One slice of the frozen list."""

    index: int
    scenarios: tuple[PinnedScenario, ...]


def plan(scenarios: Sequence[PinnedScenario], *, batch_size: int) -> tuple[Batch, ...]:
    """Cut ``scenarios`` into slices of ``batch_size`` (the last may be shorter)."""
    if batch_size < 1:
        raise ValueError("batch_size must be at least 1")
    return tuple(
        Batch(index=start // batch_size, scenarios=tuple(scenarios[start : start + batch_size]))
        for start in range(0, len(scenarios), batch_size)
    )


def batch_index(position: int, *, batch_size: int) -> int:
    """Batch index of the scenario at ``position`` in the frozen list."""
    return position // batch_size


@dataclasses.dataclass(slots=True)
class Dispatcher:
    """Hands out scenarios in list order under a start policy.

    Mutable on purpose: one instance per run, owned by the executor's scheduling loop. ``done``
    reports a finished scenario so a barrier can open the next batch.
    """

    batches: tuple[Batch, ...]
    policy: StartPolicy = StartPolicy.WINDOW
    _batch: int = 0
    _offset: int = 0
    _open: dict[int, int] = dataclasses.field(default_factory=dict)

    def next(self) -> tuple[int, PinnedScenario] | None:
        """The next scenario allowed to start with its batch index, or None for now."""
        while self._batch < len(self.batches):
            batch = self.batches[self._batch]
            if self._offset < len(batch.scenarios):
                if (
                    self.policy is StartPolicy.BARRIER
                    and self._offset == 0
                    and any(self._open.values())
                ):
                    return None
                scenario = batch.scenarios[self._offset]
                self._offset += 1
                self._open[batch.index] = self._open.get(batch.index, 0) + 1
                return batch.index, scenario
            self._batch += 1
            self._offset = 0
        return None

    def done(self, batch: int) -> None:
        """A scenario of ``batch`` finished (for good; retries keep it open)."""
        self._open[batch] -= 1

    def drain(self) -> list[tuple[int, PinnedScenario]]:
        """Everything not handed out yet, ignoring the policy (for marking it as not run)."""
        rest: list[tuple[int, PinnedScenario]] = []
        while self._batch < len(self.batches):
            batch = self.batches[self._batch]
            rest.extend((batch.index, s) for s in batch.scenarios[self._offset :])
            self._batch += 1
            self._offset = 0
        return rest

    @property
    def exhausted(self) -> bool:
        """Whether every scenario has been handed out."""
        return self._batch >= len(self.batches) or (
            self._batch == len(self.batches) - 1
            and self._offset >= len(self.batches[self._batch].scenarios)
        )


def without(batches: Sequence[Batch], finished: set[str] | frozenset[str]) -> tuple[Batch, ...]:
    """The batches minus the ``finished`` scenario ids, keeping the original batch indices."""
    kept = (
        Batch(index=b.index, scenarios=tuple(s for s in b.scenarios if s.id not in finished))
        for b in batches
    )
    return tuple(batch for batch in kept if batch.scenarios)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ExecutionPolicy:
    """How a campaign's scenarios run, whoever runs them (local executor or operator)."""

    batch_size: int = 10
    policy: StartPolicy = StartPolicy.WINDOW
    max_parallel: int | None = None
    """Scenarios in flight at once; None leaves it to the executor (local: all cores)."""
    timeout_seconds: float = 60.0
    """Wall-clock limit of one attempt; past it the run is killed and ends as Timeout."""
    retries: int = 2
    """Extra attempts after a verdict of Error; other verdicts are final."""
