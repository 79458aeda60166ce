"""Scenario states and work selection: which scenario is where, and what starts next.

Everything is derived from child objects — ScenarioBatch status (final results), live
SimEnvironments (attempts in flight) and their assessments — so a restarted operator computes
exactly what the previous one knew. A scenario is:

* ``FOLDED``: its final result is in its batch's status (durable, counted, never run again);
* ``DONE``: it has a final verdict that is not yet in the batch status;
* ``RETRY``: its latest attempt ended with ``Error`` and attempts remain;
* ``RUNNING``: its latest attempt is in flight;
* ``PENDING``: nothing has started it yet;
* ``SKIPPED``: the campaign was cancelled before its batch object existed — final, counted in the
  campaign counters only (see :mod:`cancelling`).

Work is picked in frozen-list order, retries first: in *window* mode as many units as there are
free slots, in *barrier* mode the whole next batch once every scenario of the previous one has a
final verdict (the seed paper's behaviour, kept for comparison).
"""

from __future__ import annotations

import bisect
import dataclasses
import enum
from collections.abc import Iterable, Mapping, Sequence

from simtest_operator.operator.environments import Assessment
from simtest_operator.operator.observed import BatchView, EnvironmentView, NodeView
from simtest_operator.operator.status.records import ResultRecord
from simtest_operator.verdicts import Verdict


class State(enum.StrEnum):
    """Where a scenario is."""

    PENDING = "Pending"
    RUNNING = "Running"
    RETRY = "Retry"
    DONE = "Done"
    FOLDED = "Folded"
    SKIPPED = "Skipped"

    @property
    def final(self) -> bool:
        """The scenario has its final verdict (whether or not it is recorded yet)."""
        return self in (State.DONE, State.FOLDED, State.SKIPPED)

    @property
    def settled(self) -> bool:
        """Nothing more will happen to the scenario: recorded in its batch, or cancelled
        before its batch existed."""
        return self in (State.FOLDED, State.SKIPPED)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ScenarioState:
    """One scenario of the frozen list."""

    position: int
    """Index in the frozen list."""
    id: str
    state: State
    attempt: int = 0
    """Latest attempt started (0: none)."""
    result: ResultRecord | None = None
    """The final result (DONE, FOLDED) or the latest attempt's (RETRY)."""
    durable: bool = False
    """For DONE: the result is recorded in the SimEnvironment status, so it may be folded."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Layout:
    """How the frozen list is sliced."""

    ids: tuple[str, ...]
    batch_size: int
    starts: tuple[int, ...] = ()
    """First positions of the batches when they are not equal slices: a search's waves, one
    batch each (:mod:`~simtest_operator.operator.searching`); empty for slices of
    ``batch_size``."""

    def batch_of(self, position: int) -> int:
        """Batch index of a list position."""
        if self.starts:
            return bisect.bisect_right(self.starts, position) - 1
        return position // self.batch_size

    def slot_of(self, position: int) -> int:
        """Position inside its batch."""
        if self.starts:
            return position - self.starts[self.batch_of(position)]
        return position % self.batch_size

    def batch_count(self) -> int:
        """Number of batches."""
        if self.starts:
            return len(self.starts)
        return (len(self.ids) + self.batch_size - 1) // self.batch_size

    def positions(self, batch_index: int) -> range:
        """List positions of a batch."""
        if self.starts:
            end = (
                self.starts[batch_index + 1]
                if batch_index + 1 < len(self.starts)
                else len(self.ids)
            )
            return range(self.starts[batch_index], end)
        start = batch_index * self.batch_size
        return range(start, min(start + self.batch_size, len(self.ids)))


def scenario_states(
    layout: Layout,
    *,
    batches: Iterable[BatchView],
    envs: Iterable[EnvironmentView],
    assessments: Mapping[str, Assessment],
    retries: int,
) -> tuple[ScenarioState, ...]:
    """The state of every scenario in list order."""
    folded: dict[str, ResultRecord] = {}
    for batch in batches:
        for record in batch.results:
            folded.setdefault(record.id, record)
    latest: dict[str, tuple[int, EnvironmentView]] = {}
    for env in envs:
        for scenario_id in env.scenario_ids:
            seen = latest.get(scenario_id)
            if seen is None or env.attempt > seen[0]:
                latest[scenario_id] = (env.attempt, env)
    states = []
    for position, scenario_id in enumerate(layout.ids):
        kept = folded.get(scenario_id)
        if kept is not None:
            states.append(
                ScenarioState(
                    position=position,
                    id=scenario_id,
                    state=State.FOLDED,
                    attempt=kept.attempts,
                    result=kept,
                    durable=True,
                )
            )
            continue
        entry = latest.get(scenario_id)
        if entry is None:
            states.append(ScenarioState(position=position, id=scenario_id, state=State.PENDING))
            continue
        attempt, env = entry
        states.append(_attempt_state(position, scenario_id, attempt, env, assessments, retries))
    return tuple(states)


def _attempt_state(
    position: int,
    scenario_id: str,
    attempt: int,
    env: EnvironmentView,
    assessments: Mapping[str, Assessment],
    retries: int,
) -> ScenarioState:
    assessment = assessments.get(env.name)
    if assessment is None or assessment.results is None:
        return ScenarioState(
            position=position, id=scenario_id, state=State.RUNNING, attempt=attempt
        )
    record = next((r for r in assessment.results if r.id == scenario_id), None)
    if record is None:  # the environment ended without a word about this scenario
        record = ResultRecord(
            id=scenario_id,
            verdict=Verdict.ERROR,
            reason="no result for this scenario",
            attempts=attempt,
        )
    if record.verdict.retriable and attempt < retries + 1:
        return ScenarioState(
            position=position, id=scenario_id, state=State.RETRY, attempt=attempt, result=record
        )
    return ScenarioState(
        position=position,
        id=scenario_id,
        state=State.DONE,
        attempt=attempt,
        result=dataclasses.replace(record, attempts=attempt),
        durable=env.finished,
    )


def unstored_by_environment(
    newly_folded: Iterable[ScenarioState], envs: Iterable[EnvironmentView]
) -> tuple[tuple[str, tuple[str, ...]], ...]:
    """(environment name, scenario ids) of results folded now whose pod could not store them in
    the results database: one entry per environment, for one Warning event each. A scenario
    whose environment is already gone (an operator restart in between) is listed under ``""``."""
    unstored = {(s.id, s.attempt) for s in newly_folded if s.result and not s.result.results_stored}
    out: list[tuple[str, tuple[str, ...]]] = []
    for env in sorted(envs, key=lambda e: e.name):
        ids = tuple(i for i in env.scenario_ids if (i, env.attempt) in unstored)
        if ids:
            out.append((env.name, ids))
            unstored -= {(i, env.attempt) for i in ids}
    if unstored:
        out.append(("", tuple(sorted(i for i, _ in unstored))))
    return tuple(out)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Unit:
    """Work for one SimEnvironment: one scenario, or a queue of them on a warm simulator."""

    batch_index: int
    first: int
    """Slot (position inside the batch) of the first scenario; names the environment."""
    attempt: int
    positions: tuple[int, ...]
    """Frozen-list positions of the scenarios, in order."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Selection:
    """Parameters of :func:`select`."""

    free_slots: int
    """Window mode: units that may start now."""
    barrier: bool
    barrier_limit: int | None
    """Barrier mode: explicit maxParallel (None submits the whole batch, as the paper does)."""
    in_flight: int
    chunk: int
    """Scenarios per unit at most: 1 for PerScenario, the warm-worker queue length for Reuse."""
    spread: int = 1
    """Simulators the work is spread over (the slots). A warm queue takes at most
    ``ceil(remaining / spread)`` scenarios, so the last queues shrink and the slots finish
    together instead of one long queue running on alone (guided self-scheduling)."""
    suspended: bool


def select(
    states: Sequence[ScenarioState], layout: Layout, selection: Selection
) -> tuple[Unit, ...]:
    """Units to start now, in order."""
    if selection.suspended:
        return ()
    candidates = [s for s in states if s.state is State.RETRY] + [
        s for s in states if s.state is State.PENDING
    ]
    if selection.barrier:
        open_batch = next((layout.batch_of(s.position) for s in states if not s.state.final), None)
        if open_batch is None:
            return ()
        candidates = [c for c in candidates if layout.batch_of(c.position) == open_batch]
        budget = (
            len(candidates)
            if selection.barrier_limit is None
            else max(selection.barrier_limit - selection.in_flight, 0)
        )
    else:
        budget = max(selection.free_slots, 0)
    return tuple(
        _group(
            candidates,
            layout,
            chunk=max(selection.chunk, 1),
            spread=max(selection.spread, 1),
            limit=budget,
        )
    )


def _group(
    candidates: Sequence[ScenarioState], layout: Layout, *, chunk: int, spread: int, limit: int
) -> list[Unit]:
    """Consecutive candidates of one batch and attempt, at most ``chunk`` and at most the
    remaining candidates over ``spread`` at a time, split evenly within the batch (9 as 5 + 4,
    not 8 + 1); at most ``limit`` units (the rest of a long queue is not even looked at)."""
    units: list[Unit] = []
    current: list[ScenarioState] = []
    size = 0
    in_run = _run_lengths(candidates, layout)

    def flush() -> None:
        if current:
            first = current[0]
            units.append(
                Unit(
                    batch_index=layout.batch_of(first.position),
                    first=layout.slot_of(first.position),
                    attempt=first.attempt + 1,
                    positions=tuple(s.position for s in current),
                )
            )
            current.clear()

    for left, candidate in zip(range(len(candidates), 0, -1), candidates, strict=True):
        if len(units) >= limit:
            break
        if current and (
            len(current) >= size
            or layout.batch_of(candidate.position) != layout.batch_of(current[0].position)
            or candidate.attempt != current[0].attempt
        ):
            flush()
        if not current:
            size = min(chunk, -(-left // spread))
            rest = in_run[len(candidates) - left]
            size = -(-rest // -(-rest // size))  # the batch's rest in equal parts of <= size
        current.append(candidate)
    if len(units) < limit:
        flush()
    return units


def _run_lengths(candidates: Sequence[ScenarioState], layout: Layout) -> list[int]:
    """For each candidate, how many candidates from it on share its batch and attempt."""
    lengths = [0] * len(candidates)
    for i in range(len(candidates) - 1, -1, -1):
        same = i + 1 < len(candidates) and (
            layout.batch_of(candidates[i + 1].position) == layout.batch_of(candidates[i].position)
            and candidates[i + 1].attempt == candidates[i].attempt
        )
        lengths[i] = lengths[i + 1] + 1 if same else 1
    return lengths


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Capacity:
    """Simulator slots on the nodes a campaign's pods may use."""

    slots: int = 0
    nodes: int = 0


def cluster_slots(
    nodes: Mapping[str, NodeView] | None,
    *,
    per_node: int,
    node_selector: Mapping[str, str],
    tolerated: Iterable[tuple[str | None, str | None, str | None, str]],
) -> Capacity:
    """Simulator slots (and nodes) a simulator pod may use (zero when unknown)."""
    if nodes is None:
        return Capacity()
    tolerations = tuple(tolerated)
    total = 0
    usable = 0
    for node in nodes.values():
        labels = dict(node.labels)
        if not node.ready or node.unschedulable or node.slots <= 0:
            continue
        if any(labels.get(k) != v for k, v in node_selector.items()):
            continue
        if not all(_tolerates(taint, tolerations) for taint in node.taints):
            continue
        total += min(node.slots, per_node)
        usable += 1
    return Capacity(slots=total, nodes=usable)


def _tolerates(
    taint: tuple[str, str, str],
    tolerations: Sequence[tuple[str | None, str | None, str | None, str]],
) -> bool:
    key, value, effect = taint
    if effect == "PreferNoSchedule":
        return True
    for t_key, t_value, t_effect, operator in tolerations:
        if t_effect not in (None, "", effect):
            continue
        if operator == "Exists" and (t_key in (None, "") or t_key == key):
            return True
        if operator == "Equal" and t_key == key and (t_value or "") == value:
            return True
    return False
