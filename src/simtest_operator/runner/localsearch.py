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

from simtest_operator.errors import ScenarioError
from simtest_operator.runner import preparing, resolving, searchresults, storing
from simtest_operator.runner.preparing import SearchPlan
from simtest_operator.runner.searching import SearchFeed
from simtest_operator.scenarios.pinned import FrozenList, PinnedScenario
from simtest_operator.search import SearchSpace, summarise
from simtest_operator.verdicts import ScenarioOutcome

SUMMARY_FILE = "search.json"
"""The search's summary in the output folder (next to ``frozen.json``)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Searched:
    """What a finished (or stopped) local search found."""

    search: searchresults.Recorded
    record: Mapping[str, Any]
    """What the results store keeps with the campaign (``settings.search``)."""
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
        target = resolving.search_target(search.base, search.path, space)
        proposed = plan.frozen.scenarios
        if proposed and (proposed[0].source, proposed[0].sha256) != (target.source, target.sha256):
            raise ScenarioError(
                f"spec.search.scenario {search.spec.scenario!r} no longer leads to the file "
                f"this search ran ({proposed[0].source} at sha256 {proposed[0].sha256[:12]}...):"
                " the distribution changed; choose another --output"
            )
        outcomes = {
            p.proposal.index: resolving.search_outcome(results[p.id].verdict, results[p.id].metrics)
            for p in proposed
            if p.proposal is not None and p.id in plan.finished and p.id in results
        }
        pins = [p.proposal for p in proposed if p.proposal is not None]
        replayed = resolving.replay_search(search.spec, space, pins, outcomes)
        local = cls(plan, search, space, store, paths, proposed=proposed)
        local.feed = SearchFeed(
            replayed.searcher,
            target,
            parallel=parallel,
            batch_size=plan.policy.batch_size,
            pending=[p for p in proposed if p.id not in plan.finished and p.id in paths],
            told=replayed.unpinned,
            on_proposed=local._proposed,
        )
        return local

    @property
    def frozen(self) -> FrozenList:
        """The frozen list: every proposal so far."""
        return dataclasses.replace(self._plan.frozen, scenarios=tuple(self._entries))

    def _proposed(self, pins: Sequence[PinnedScenario]) -> None:
        """New proposals join the frozen list (on disk before they run) and the store."""
        path = self._space.scenario or self._search.path  # a distribution's scenario file
        for pinned in pins:
            self._paths[pinned.id] = path
            self._store.register(pinned, path)
        self._entries.extend(pins)
        self._plan.output.write_frozen(self.frozen)

    def finish(self, results: Mapping[str, ScenarioOutcome]) -> Searched:
        """Summarise every proposal with a final outcome; write ``search.json``."""
        final = {key: (o.verdict.value, dict(o.metrics)) for key, o in results.items()}
        runs = searchresults.outcomes_of(self._entries, final)
        spec = self._search.spec
        summary = summarise(self._space, runs, spec.objectives)
        record = resolving.search_record(spec, self._space, self._entries, summary)
        path = self._plan.output.root / SUMMARY_FILE
        self._plan.output.write_json(path, record)
        search = searchresults.Recorded(
            spec=spec, space=self._space, scenario=spec.scenario, records=runs, summary=summary
        )
        return Searched(search=search, record=record, waves=tuple(self.feed.waves), path=path)
