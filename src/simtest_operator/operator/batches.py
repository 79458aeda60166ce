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
import itertools
from collections.abc import Iterable, Iterator, Mapping, Sequence
from collections.abc import Set as AbstractSet
from typing import Protocol

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

    @classmethod
    def folded(cls, position: int, record: ResultRecord) -> ScenarioState:
        """A scenario whose final result ``record`` is in its batch's status."""
        return cls(
            position=position,
            id=record.id,
            state=State.FOLDED,
            attempt=record.attempts,
            result=record,
            durable=True,
        )


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Layout:
    """How the frozen list is sliced (built once per frozen list: it indexes every id)."""

    ids: tuple[str, ...]
    batch_size: int
    starts: tuple[int, ...] = ()
    """First positions of the batches when they are not equal slices: a search's waves, one
    batch each (:mod:`~simtest_operator.operator.searching`); empty for slices of
    ``batch_size``."""
    index: Mapping[str, int] = dataclasses.field(init=False, repr=False, compare=False)
    """List position of each id."""

    def __post_init__(self) -> None:
        index = {scenario_id: position for position, scenario_id in enumerate(self.ids)}
        object.__setattr__(self, "index", index)

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


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Progress:
    """Every scenario's state, kept sparse: a step costs what is open, not the campaign's size.

    Each batch of the layout is one of three kinds. *Closed*: its object's status holds every
    result and no environment refers to it, so its scenarios are all ``FOLDED`` and only their
    counters matter (``closed``, kept across steps by
    :class:`~simtest_operator.operator.status.counting.Tally`). *Absent*: no object and no
    environment, so its scenarios are all ``PENDING`` (or ``SKIPPED`` under a cancellation).
    *Open*: everything else -- at most the batches of the live environments plus the newest --
    whose states are listed in ``explicit``. The three cover the list, so this says what a dense
    tuple of every state says.
    """

    layout: Layout
    explicit: Mapping[int, ScenarioState]
    """The states of every position of the open batches, in list order."""
    open: tuple[int, ...]
    """The open batches' indices, ascending."""
    present: Mapping[int, BatchView]
    """The batch objects by index (closed ones included)."""
    closed: Mapping[str, int]
    """Counters (wire names) of the closed batches' scenarios."""
    closed_scenarios: int
    """How many scenarios the closed batches hold."""
    tail: int
    """The first batch of the absent tail: no batch from here on is open or present."""
    gaps: tuple[int, ...] = ()
    """Absent batches before the tail (a batch object deleted from under the campaign)."""
    skipped_absent: bool = False
    """A cancellation ended the absent batches' scenarios ``SKIPPED``."""

    @classmethod
    def dense(cls, states: Sequence[ScenarioState], layout: Layout) -> Progress:
        """Every state given, every batch open (tests, small lists)."""
        open_ = tuple(sorted({layout.batch_of(s.position) for s in states}))
        return cls(
            layout=layout,
            explicit={s.position: s for s in states},
            open=open_,
            present={},
            closed={},
            closed_scenarios=0,
            tail=layout.batch_count(),
        )

    @property
    def absent_scenarios(self) -> int:
        """Scenarios of the absent batches."""
        return len(self.layout.ids) - self.closed_scenarios - len(self.explicit)

    def absent(self) -> Iterator[int]:
        """The absent batches' indices, ascending (lazily: usually the tail of the list)."""
        yield from self.gaps
        yield from range(self.tail, self.layout.batch_count())

    def state(self, position: int) -> ScenarioState:
        """The state of one position, explicit or implied by its batch's kind."""
        known = self.explicit.get(position)
        if known is not None:
            return known
        scenario_id = self.layout.ids[position]
        batch = self.present.get(self.layout.batch_of(position))
        record = next((r for r in batch.results if r.id == scenario_id), None) if batch else None
        if record is None:
            state = State.SKIPPED if self.skipped_absent else State.PENDING
            return ScenarioState(position=position, id=scenario_id, state=state)
        return ScenarioState.folded(position, record)

    def of_batch(self, index: int) -> list[ScenarioState]:
        """The states of one open batch, in list order."""
        return [self.explicit[p] for p in self.layout.positions(index)]

    @property
    def complete(self) -> bool:
        """Nothing more will happen to any scenario."""
        if self.absent_scenarios and not self.skipped_absent:
            return False
        return all(s.state.settled for s in self.explicit.values())


class Closed(Protocol):
    """The batches whose status holds every result, as
    :class:`~simtest_operator.operator.status.counting.Tally` keeps them across steps."""

    @property
    def open(self) -> AbstractSet[int]:
        """Indices of the batch objects that are not closed."""
        ...

    @property
    def total(self) -> Mapping[str, int]:
        """Counters (wire names) of every closed batch's scenarios."""
        ...

    def counts(self, index: int) -> Mapping[str, int] | None:
        """Counters of one closed batch (None: not closed)."""
        ...


def progress(
    layout: Layout,
    *,
    batches: Mapping[int, BatchView],
    closed: Closed,
    envs: Iterable[EnvironmentView],
    assessments: Mapping[str, Assessment],
    retries: int,
) -> Progress:
    """Every scenario's state, looking only at the open batches: those of ``closed.open`` and
    those of the live environments (open whatever their status says)."""
    latest: dict[str, tuple[int, EnvironmentView]] = {}
    busy: set[int] = set()
    for env in envs:
        for scenario_id in env.scenario_ids:
            position = layout.index.get(scenario_id)
            if position is not None:
                busy.add(layout.batch_of(position))
            seen = latest.get(scenario_id)
            if seen is None or env.attempt > seen[0]:
                latest[scenario_id] = (env.attempt, env)
    counts = dict(closed.total)
    for index in busy:
        held = closed.counts(index)
        for key, value in (held or {}).items():
            counts[key] -= value
    explicit: dict[int, ScenarioState] = {}
    open_ = tuple(sorted(busy | closed.open))
    for index in open_:
        batch = batches.get(index)
        folded: dict[str, ResultRecord] = {}
        for record in batch.results if batch is not None else ():
            folded.setdefault(record.id, record)
        for position in layout.positions(index):
            explicit[position] = _state(
                position, layout.ids[position], folded, latest, assessments, retries
            )
    top = max(max(batches, default=-1), max(busy, default=-1))
    covered = len(batches) + sum(1 for i in busy if i not in batches)
    gaps: tuple[int, ...] = ()
    if covered <= top:  # a batch object went missing in the middle (rare: a full pass)
        gaps = tuple(i for i in range(top) if i not in batches and i not in busy)
    return Progress(
        layout=layout,
        explicit=explicit,
        open=open_,
        present=batches,
        closed=counts,
        closed_scenarios=counts.get("total", 0),
        tail=top + 1,
        gaps=gaps,
    )


def _state(
    position: int,
    scenario_id: str,
    folded: Mapping[str, ResultRecord],
    latest: Mapping[str, tuple[int, EnvironmentView]],
    assessments: Mapping[str, Assessment],
    retries: int,
) -> ScenarioState:
    kept = folded.get(scenario_id)
    if kept is not None:
        return ScenarioState.folded(position, kept)
    entry = latest.get(scenario_id)
    if entry is None:
        return ScenarioState(position=position, id=scenario_id, state=State.PENDING)
    attempt, env = entry
    return _attempt_state(position, scenario_id, attempt, env, assessments, retries)


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


Run = tuple[int, int, Sequence[int]]
"""(batch index, attempt, positions): consecutive candidates of one batch and attempt."""


def select(
    states: Progress | Sequence[ScenarioState], layout: Layout, selection: Selection
) -> tuple[Unit, ...]:
    """Units to start now, in order (only as many candidates are looked at as they take)."""
    if selection.suspended:
        return ()
    known = states if isinstance(states, Progress) else Progress.dense(states, layout)
    if selection.barrier:
        open_batch = _first_unfinished(known)
        if open_batch is None:
            return ()
        listed = list(_runs_of_batch(known, open_batch))
        runs: Iterable[Run] = listed
        total = sum(len(positions) for _, _, positions in listed)
        budget = (
            total
            if selection.barrier_limit is None
            else max(selection.barrier_limit - selection.in_flight, 0)
        )
    else:
        retries = [s for s in known.explicit.values() if s.state is State.RETRY]
        pending = sum(1 for s in known.explicit.values() if s.state is State.PENDING)
        total = len(retries) + pending + known.absent_scenarios
        runs = itertools.chain(_grouped(retries, layout), _pending_runs(known))
        budget = max(selection.free_slots, 0)
    return tuple(
        _group(
            runs,
            total,
            layout,
            chunk=max(selection.chunk, 1),
            spread=max(selection.spread, 1),
            limit=budget,
        )
    )


def _first_unfinished(known: Progress) -> int | None:
    """The batch of the first scenario in list order without a final verdict."""
    first = next(
        (known.layout.batch_of(p) for p, s in known.explicit.items() if not s.state.final), None
    )
    absent = next(known.absent(), None) if known.absent_scenarios else None
    found = [i for i in (first, absent) if i is not None]
    return min(found) if found else None


def _runs_of_batch(known: Progress, index: int) -> Iterator[Run]:
    """One batch's candidates: its retries, then its pending scenarios."""
    if index not in known.open:
        yield (index, 0, known.layout.positions(index))
        return
    mine = known.of_batch(index)
    yield from _grouped([s for s in mine if s.state is State.RETRY], known.layout)
    yield from _grouped([s for s in mine if s.state is State.PENDING], known.layout)


def _pending_runs(known: Progress) -> Iterator[Run]:
    """Pending scenarios in list order: the open batches' and the absent batches' merged."""
    absent = known.absent()
    following = next(absent, None)
    for index in known.open:
        while following is not None and following < index:
            yield (following, 0, known.layout.positions(following))
            following = next(absent, None)
        pending = [s for s in known.of_batch(index) if s.state is State.PENDING]
        yield from _grouped(pending, known.layout)
    while following is not None:
        yield (following, 0, known.layout.positions(following))
        following = next(absent, None)


def _grouped(states: Sequence[ScenarioState], layout: Layout) -> Iterator[Run]:
    """Consecutive states of one batch and attempt as runs."""
    start = 0
    for i in range(1, len(states) + 1):
        if i == len(states) or (
            layout.batch_of(states[i].position) != layout.batch_of(states[start].position)
            or states[i].attempt != states[start].attempt
        ):
            first = states[start]
            yield (
                layout.batch_of(first.position),
                first.attempt,
                [s.position for s in states[start:i]],
            )
            start = i


def _group(
    runs: Iterable[Run], total: int, layout: Layout, *, chunk: int, spread: int, limit: int
) -> list[Unit]:
    """Units of at most ``chunk`` consecutive candidates of one run, and at most the remaining
    candidates (``total`` at first) over ``spread``, each run's rest split evenly (9 as 5 + 4,
    not 8 + 1); at most ``limit`` units (the rest of a long queue is not even looked at)."""
    units: list[Unit] = []
    left = total
    for batch_index, attempt, positions in runs:
        taken = 0
        while taken < len(positions):
            if len(units) >= limit:
                return units
            rest = len(positions) - taken
            size = min(chunk, -(-left // spread))
            size = -(-rest // -(-rest // size))  # the run's rest in equal parts of <= size
            part = tuple(positions[taken : taken + size])
            units.append(
                Unit(
                    batch_index=batch_index,
                    first=layout.slot_of(part[0]),
                    attempt=attempt + 1,
                    positions=part,
                )
            )
            taken += len(part)
            left -= len(part)
    return units


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
