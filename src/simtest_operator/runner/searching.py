"""A search on this machine: the searcher's proposals are the executor's work.

:class:`SearchFeed` stands where the frozen list's dispatcher stands for an ordinary run. It asks
the searcher for as many proposals as workers are free (the first wave fills every worker), and
for the next ones as each result comes back -- no barrier between waves, so the workers stay busy.
Every proposal enters the frozen list the moment it is made, with its index, values, basis and
the results told before it (:func:`~simtest_operator.runner.resolving.pin_proposal`): ``--frozen``
reruns exactly the proposed list, and a resumed run replays the searcher
(:func:`~simtest_operator.runner.resolving.replay_search`) and continues.
"""

from __future__ import annotations

import collections
from collections.abc import Callable, Sequence

from simtest_operator.runner import resolving
from simtest_operator.scenarios import batching
from simtest_operator.scenarios.pinned import PinnedScenario
from simtest_operator.search import Outcome, Proposal, Searcher
from simtest_operator.verdicts import ScenarioOutcome


class SearchFeed:
    """The executor's work during a search (the :class:`~.scheduling.Feed` protocol).

    Owned by the executor's scheduling loop; ``tell`` is called from its event callback when a
    proposal's final outcome arrives, before the loop fills the freed worker again."""

    def __init__(
        self,
        searcher: Searcher,
        base: PinnedScenario,
        *,
        parallel: int,
        batch_size: int,
        pending: Sequence[PinnedScenario] = (),
        told: Sequence[int] = (),
        on_proposed: Callable[[Sequence[PinnedScenario]], None] = lambda pins: None,
    ) -> None:
        """``pending``: proposals made before (a resumed run) still to run, handed out first;
        ``told``: tells not yet pinned to a proposal."""
        self._searcher = searcher
        self._base = base
        self._parallel = parallel
        self._batch_size = batch_size
        self._queue: collections.deque[PinnedScenario] = collections.deque(pending)
        self._told: list[int] = list(told)
        self._on_proposed = on_proposed
        self._in_flight = 0
        self._done = False
        self.records: list[tuple[Proposal, Outcome]] = []
        """Every (proposal, outcome) told, in the order told."""
        self.waves: list[int] = []
        """The size of each ask, in order."""

    def next(self) -> tuple[int, PinnedScenario] | None:
        """The next proposal to run; asks for a wave when none is queued and workers are free."""
        if not self._queue:
            self._ask()
        if not self._queue:
            return None
        pinned = self._queue.popleft()
        assert pinned.proposal is not None
        self._in_flight += 1
        return batching.batch_index(pinned.proposal.index, batch_size=self._batch_size), pinned

    def _ask(self) -> None:
        free = self._parallel - self._in_flight
        if free <= 0 or self._done:
            return
        proposals = self._searcher.ask(free)
        if not proposals:
            self._done = True  # budget spent, or the strategy has nothing left (a small grid)
            return
        pins = []
        for proposal in proposals:
            pins.append(resolving.pin_proposal(self._base, proposal, told=self._told))
            self._told = []
        self.waves.append(len(pins))
        self._on_proposed(pins)
        self._queue.extend(pins)

    def done(self, batch: int) -> None:
        """A proposal has its final outcome (told separately)."""
        self._in_flight -= 1

    def tell(self, pinned: PinnedScenario, outcome: ScenarioOutcome) -> None:
        """Teach the searcher a proposal's final outcome."""
        if pinned.proposal is None:
            return
        told = resolving.search_outcome(outcome.verdict, outcome.metrics)
        self._searcher.tell(pinned.proposal.index, told)
        self._told.append(pinned.proposal.index)
        self.records.append((resolving.proposal_of(pinned.proposal), told))

    def drain(self) -> list[tuple[int, PinnedScenario]]:
        """Proposals made but not handed out (the run was stopped)."""
        rest = [
            (batching.batch_index(p.proposal.index, batch_size=self._batch_size), p)
            for p in self._queue
            if p.proposal is not None
        ]
        self._queue.clear()
        return rest

    @property
    def exhausted(self) -> bool:
        """Nothing queued and the searcher has nothing more to propose."""
        if self._queue:
            return False
        return self._done or self._searcher.remaining == 0
