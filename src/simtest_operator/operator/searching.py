"""A campaign's search (``spec.search``) in the operator: waves of proposals sized to the window.

The searcher is the one piece of campaign state that is not a pure function of the child
objects, so it lives beside the planner, in the campaign loop, and is rebuilt from them:

* each wave of proposals is one ScenarioBatch, created complete; its entries carry the
  proposal records (index, values, basis, the results told before it), so the batches *are* the
  search's frozen list (the ConfigMap pins the logical scenario they vary);
* before every planning step the searcher learns the results folded since, in proposal order
  (:meth:`CampaignSearch.learn`); after it, it asks for as many proposals as the window has room
  for (window minus what is in flight or queued: :meth:`CampaignSearch.advance`) -- no barrier,
  so as each result comes back the next proposal fills its slot;
* a restarted operator replays the searcher from the batches
  (:meth:`~simtest_operator.search.Searcher.replay`) and gets the same proposals.

The planner sees the waves as an ordinary frozen list
(:func:`~simtest_operator.operator.planning.inputs.waves`) and the progress as
:class:`~simtest_operator.operator.status.searchstatus.SearchProgress`.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Iterable, Mapping, Sequence
from importlib import import_module
from typing import Any

from simtest_operator.api.v1alpha1.search import SearchSpec, SearchStrategy
from simtest_operator.operator import bodies
from simtest_operator.operator.actions import Create, Kind, Observation
from simtest_operator.operator.observed import BatchView, CampaignView
from simtest_operator.operator.planning.inputs import waves
from simtest_operator.operator.status.searchstatus import SearchProgress
from simtest_operator.runner import resolving
from simtest_operator.scenarios.pinned import PinnedScenario
from simtest_operator.search import (
    Outcome,
    Proposal,
    Searcher,
    SearchSpace,
    criticality,
    summarise,
)

MAX_WAVE = 1000
"""Proposals per wave at most: a ScenarioBatch lists at most this many scenarios."""

MODEL_LIBRARIES: Mapping[SearchStrategy, tuple[str, ...]] = {
    SearchStrategy.TPE: ("optuna",),
    SearchStrategy.BOUNDARY: ("sklearn.gaussian_process", "scipy.stats"),
    SearchStrategy.HYBRID: ("sklearn.gaussian_process", "scipy.stats"),
}
"""What a model-based strategy imports on its first model proposal (seconds on a busy node)."""


def lookahead(strategy: SearchStrategy, window: int) -> int:
    """Proposals a model-based strategy keeps queued beyond the free slots (a quarter of the
    window): a model proposal takes 0.1-0.5 s of CPU on a busy node, and a slot that frees
    meanwhile starts the queued one at once instead of idling (the e2e search on 9 slots was
    65 % busy without). Each such proposal knows the results of its ask, not the last few; its
    record says which (``basis``), so replay stays exact."""
    return window // 4 if strategy in MODEL_LIBRARIES else 0


def preload(strategy: SearchStrategy) -> None:
    """Import the strategy's model libraries: done in a thread while the first wave runs, or the
    first proposal after the start-up design would stall every slot for the import (the e2e
    search kept its 9 slots 40 % busy)."""
    for name in MODEL_LIBRARIES.get(strategy, ()):
        import_module(name)


class CampaignSearch:
    """The searcher of one campaign and what it has been told; owned by the campaign loop."""

    def __init__(
        self, spec: SearchSpec, space: SearchSpace, searcher: Searcher, base: PinnedScenario
    ) -> None:
        self.spec = spec
        self.space = space
        self.searcher = searcher
        self.base = base
        self.told: set[int] = set()
        """Proposals the searcher has learnt from."""
        self.unpinned: list[int] = []
        """Proposals told since the last proposal was asked, in the order told."""
        self.failures = 0
        self.best: tuple[float, int] | None = None
        """(criticality under the first objective, proposal index) of the most critical run."""
        self.exhausted = False
        """The strategy proposed nothing although the budget allowed more (a small grid)."""
        self.wave: Create | None = None
        """The last wave's batch until the cache shows it (created again until then)."""
        self.waves = 0
        self._record: tuple[int, Mapping[str, Any]] | None = None
        self.preloading: asyncio.Future[None] | None = None
        """The model libraries' import, started with the search (kept: a running future)."""

    @classmethod
    async def replayed(
        cls,
        spec: SearchSpec,
        space: SearchSpace,
        base: PinnedScenario,
        batches: Iterable[BatchView],
    ) -> CampaignSearch:
        """The searcher as the waves left it: their proposals asked again after the results
        recorded before each, then told every result folded since (off the event loop: every
        proposal is asked again)."""
        mine = {b.index: b for b in batches}
        frozen, starts = waves(mine)
        outcomes = _folded(frozen, mine.values())
        pins = [p.proposal for p in frozen if p.proposal is not None]
        replayed = await asyncio.to_thread(resolving.replay_search, spec, space, pins, outcomes)
        search = cls(spec, space, replayed.searcher, base)
        search.preloading = asyncio.get_running_loop().run_in_executor(None, preload, spec.strategy)
        search.waves = len(starts)
        search.unpinned = list(replayed.unpinned)
        for index, outcome in replayed.pinned:
            search._learnt(index, outcome)
        for index in replayed.unpinned:
            search._learnt(index, outcomes[index])
        return search

    def progress(self) -> SearchProgress:
        """What the campaign's status says about the search."""
        best_value, best_scenario = None, None
        if self.best is not None:
            best_value = self._objective_value(self.best)
            best_scenario = f"{self.base.id}{resolving.SEARCH_SUFFIX}{self.best[1]}"
        return SearchProgress(
            strategy=self.spec.strategy.value,
            budget=self.spec.budget,
            asked=self.searcher.asked,
            told=self.searcher.told,
            failures=self.failures,
            best=best_value,
            best_scenario=best_scenario,
            open=not self.exhausted and self.searcher.remaining > 0,
        )

    def learn(self, batches: Iterable[BatchView]) -> None:
        """Before a planning step: tell the searcher the results folded since, in proposal
        order (so the status the step writes counts them)."""
        mine = {b.index: b for b in batches}
        frozen, _ = waves(mine)
        outcomes = _folded(frozen, mine.values())
        for index in sorted(set(outcomes) - self.told):
            self._tell(index, outcomes[index])

    async def advance(
        self, campaign: CampaignView, batches: Iterable[BatchView], observation: Observation
    ) -> Create | None:
        """After a planning step: the next wave's batch (None: the window is full, the search
        is over, or the cache is behind). The searcher is asked off the event loop (a
        ``boundary`` proposal fits a classifier: about a second), so other campaigns' steps and
        kopf's handlers go on meanwhile; only this campaign's loop touches its searcher, and it
        waits for the answer."""
        mine = {b.index: b for b in batches if b.campaign == campaign.name}
        frozen, starts = waves(mine)
        if self.wave is not None:
            if len(starts) < self.waves:
                return self.wave  # not visible yet: create it again (AlreadyExists is fine)
            self.wave = None
        if len(frozen) != self.searcher.asked:
            return None  # the cache has not caught up with our own writes
        spec = campaign.spec
        if spec is None or spec.suspend or spec.cancel or campaign.status.phase.finished:
            return None
        room = observation.window + lookahead(self.spec.strategy, observation.window)
        room -= observation.in_flight + observation.queued
        if room <= 0 or not self.progress().open:
            return None
        proposals = await asyncio.to_thread(self.searcher.ask, min(room, MAX_WAVE))
        if not proposals:
            self.exhausted = True
            return None
        pins = self._pins(proposals)
        self.wave = Create(
            kind=Kind.BATCH,
            body=bodies.batch(
                campaign=campaign.name,
                namespace=campaign.namespace,
                campaign_uid=campaign.uid,
                index=len(starts),
                scenarios=pins,
            ),
        )
        self.waves = len(starts) + 1
        return self.wave

    def _pins(self, proposals: Sequence[Proposal]) -> list[PinnedScenario]:
        pins = []
        for proposal in proposals:
            pins.append(resolving.pin_proposal(self.base, proposal, told=self.unpinned))
            self.unpinned = []
        return pins

    def _tell(self, index: int, outcome: Outcome) -> None:
        self.searcher.tell(index, outcome)
        self.unpinned.append(index)
        self._learnt(index, outcome)

    def _learnt(self, index: int, outcome: Outcome) -> None:
        self.told.add(index)
        if outcome.failed:
            self.failures += 1
        score = criticality(outcome, self.spec.objectives[0])
        if (
            score is not None
            and math.isfinite(score)
            and (self.best is None or score < self.best[0])
        ):
            self.best = (score, index)

    def _objective_value(self, best: tuple[float, int]) -> float:
        """The first objective's value at the most critical run: the metric as measured (its
        sign restored for ``maximize``), or the verdict's criticality score."""
        objective = self.spec.objectives[0]
        if objective.metric != "verdict" and objective.goal == "maximize":
            return -best[0]
        return best[0]

    async def record(
        self, batches: Iterable[BatchView]
    ) -> tuple[tuple[PinnedScenario, ...], Mapping[str, Any]]:
        """The search's frozen list and the record the results store keeps with the campaign
        (``settings.search``: the spec, the dimensions, every proposal, the summary); computed
        once the search is over (the loop asks only then), again only if more results came.
        The summary fits the boundary classifier: off the event loop."""
        mine = {b.index: b for b in batches}
        frozen, _ = waves(mine)
        outcomes = _folded(frozen, mine.values())
        if self._record is None or self._record[0] != len(outcomes):
            runs = [
                (resolving.proposal_of(p.proposal), outcomes[p.proposal.index])
                for p in frozen
                if p.proposal is not None and p.proposal.index in outcomes
            ]
            summary = await asyncio.to_thread(summarise, self.space, runs, self.spec.objectives)
            record = resolving.search_record(self.spec, self.space, frozen, summary)
            self._record = (len(outcomes), record)
        return frozen, self._record[1]


def _folded(frozen: Sequence[PinnedScenario], batches: Iterable[BatchView]) -> dict[int, Outcome]:
    """Outcomes of the proposals whose final result is folded into their batch, by index."""
    index_of = {p.id: p.proposal.index for p in frozen if p.proposal is not None}
    outcomes: dict[int, Outcome] = {}
    for batch in batches:
        for record in batch.results:
            index = index_of.get(record.id)
            if index is not None:
                outcomes[index] = resolving.search_outcome(record.verdict, dict(record.metrics))
    return outcomes
