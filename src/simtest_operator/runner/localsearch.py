"""The search of a local run: its feed, its growing frozen list, its summary and record.

:mod:`.searching` decides what runs; this module keeps what a search leaves behind: every
proposal in ``frozen.json`` before it runs and in the results store, ``search.json`` with the
summary, and the record the store keeps with the campaign (``settings.search``), which the report,
the results UI and ``simtest search export`` read.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from simtest_operator.api.v1alpha1.search import SearchSpec
from simtest_operator.runner import preparing, resolving, storing
from simtest_operator.runner.searching import SearchFeed, SearchPlan, replayed
from simtest_operator.scenarios.pinned import FrozenList, PinnedScenario
from simtest_operator.search import (
    Outcome,
    Proposal,
    SearchSpace,
    SearchSummary,
    plot_pairs,
    summarise,
)
from simtest_operator.verdicts import ScenarioOutcome, Verdict

SUMMARY_FILE = "search.json"
"""The search's summary in the output folder (next to ``frozen.json``)."""

Plot = tuple[str, str, bytes | str]
"""(parameter x, parameter y, PNG) of one pair plot."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Searched:
    """What a finished (or stopped) local search found."""

    summary: SearchSummary
    record: Mapping[str, Any]
    """What the results store keeps with the campaign (``settings.search``)."""
    plots: tuple[Plot, ...]
    waves: tuple[int, ...]
    """Proposals per ask made by this invocation, in order."""
    path: Path
    """``search.json`` in the output folder."""


class LocalSearch:
    """A search run by ``simtest run``: the feed, the growing frozen list, the summary."""

    def __init__(
        self,
        plan: preparing.Plan,
        search: SearchPlan,
        space: SearchSpace,
        store: storing.ResultWriter,
        paths: dict[str, Path],
        *,
        proposed: Sequence[PinnedScenario],
    ) -> None:
        self._plan = plan
        self._search = search
        self._space = space
        self._store = store
        self._paths = paths
        self._entries: list[PinnedScenario] = list(proposed)
        self.feed: SearchFeed

    @classmethod
    def start(
        cls,
        plan: preparing.Plan,
        search: SearchPlan,
        store: storing.ResultWriter,
        paths: dict[str, Path],
        results: Mapping[str, ScenarioOutcome],
        *,
        parallel: int,
    ) -> LocalSearch:
        """Replay what an earlier invocation proposed (a resumed run) and feed the rest."""
        space = SearchSpace.from_spec(search.spec, search.path)
        proposed = plan.frozen.scenarios
        finished = {k: v for k, v in results.items() if k in plan.finished}
        searcher, unpinned = replayed(search, space, proposed, finished)
        local = cls(plan, search, space, store, paths, proposed=proposed)
        local.feed = SearchFeed(
            searcher,
            search.base,
            parallel=parallel,
            batch_size=plan.policy.batch_size,
            pending=[p for p in proposed if p.id not in plan.finished and p.id in paths],
            told=unpinned,
            on_proposed=local._proposed,
        )
        return local

    @property
    def frozen(self) -> FrozenList:
        """The frozen list: every proposal so far."""
        return dataclasses.replace(self._plan.frozen, scenarios=tuple(self._entries))

    def _proposed(self, pins: Sequence[PinnedScenario]) -> None:
        """New proposals join the frozen list (on disk before they run) and the store."""
        for pinned in pins:
            self._paths[pinned.id] = self._search.path
            self._store.register(pinned, self._search.path)
        self._entries.extend(pins)
        self._plan.output.write_frozen(self.frozen)

    def finish(self, results: Mapping[str, ScenarioOutcome]) -> Searched:
        """Summarise every proposal with a final outcome; write ``search.json``."""
        records = run_records(self._entries, results)
        summary = summarise(self._space, records, self._search.spec.objectives)
        plots = tuple(plot_pairs(self._space, records, summary))
        record = store_record(self._search.spec, self._entries, summary)
        path = self._plan.output.root / SUMMARY_FILE
        self._plan.output.write_json(path, record)
        return Searched(
            summary=summary, record=record, plots=plots, waves=tuple(self.feed.waves), path=path
        )


def run_records(
    entries: Sequence[PinnedScenario], results: Mapping[str, ScenarioOutcome]
) -> list[tuple[Proposal, Outcome]]:
    """(proposal, outcome) of every proposal with a final verdict, in index order."""
    records = []
    for pinned in entries:
        outcome = results.get(pinned.id)
        if pinned.proposal is None or outcome is None or outcome.verdict is Verdict.SKIPPED:
            continue
        told = resolving.search_outcome(outcome.verdict, outcome.metrics)
        records.append((resolving.proposal_of(pinned.proposal), told))
    return records


def store_record(
    spec: SearchSpec, entries: Sequence[PinnedScenario], summary: SearchSummary
) -> dict[str, Any]:
    """The search as the results store keeps it: the spec, every proposal, the summary."""
    return {
        "spec": spec.to_wire(),
        "proposals": [
            {"id": p.id, **p.proposal.to_json()} for p in entries if p.proposal is not None
        ],
        "summary": summary.model_dump(mode="json", by_alias=True),
    }
