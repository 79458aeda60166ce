"""A search campaign through the planner on the in-memory cluster: waves sized to the window.

Covers: each wave is one ScenarioBatch, created complete, its entries carrying the proposal
records (index, values, basis, the results told before it); the first wave fills the window and
each result is followed by a new proposal (no barrier), so the slots stay busy; the campaign ends
when the budget is spent, not when the first wave is done; the status stays bounded
(``status.search``); a restarted operator replays the searcher from the batches at any step and
gets the proposals the batches hold; the same seed and results give the same waves.
"""

from __future__ import annotations

import asyncio
import dataclasses
import datetime
import json
import shutil
import time
from collections.abc import Coroutine, Mapping
from pathlib import Path
from typing import Any, TypeVar, cast

import pytest

from simtest_operator.api.v1alpha1.search import SearchSpec
from simtest_operator.operator import observed, planning, resolving, searching
from simtest_operator.operator.actions import Kind, Plan
from simtest_operator.operator.batches import Layout
from simtest_operator.operator.client import Client
from simtest_operator.operator.searching import CampaignSearch
from simtest_operator.scenarios import FrozenList, PinnedScenario, sha256_hex
from simtest_operator.search import Proposal, Searcher, SearchSpace
from tests.operator.fakecluster import FakeCluster, Script, campaign_body

CUT_IN = Path(__file__).parents[2] / "scenarios/library/cut-in/cut-in_highway_v25_gap15_dv10.xosc"
SEARCH = {
    "scenario": "cut-in.xosc",
    "parameters": [
        {"name": "EgoSpeed", "min": 15, "max": 35},
        {"name": "CutInGap", "min": 5, "max": 40},
    ],
    "strategy": "random",
    "budget": 20,
    "seed": 3,
}


T = TypeVar("T")


class SearchCluster(FakeCluster):
    """The fake cluster plus what the campaign loop does for a search after every step."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(script=self._sut, **kwargs)
        self.search: CampaignSearch | None = None
        self.base = PinnedScenario(
            id="cut-in.xosc", source=CUT_IN.as_uri(), sha256=sha256_hex(CUT_IN.read_bytes())
        )
        self.busy: list[tuple[int, int]] = []
        """(pods running, slots) at each kubelet step while the search still proposes."""

    def start(self, search: Mapping[str, Any] = SEARCH, **execution: Any) -> None:
        body = campaign_body(**execution)
        body["spec"]["search"] = dict(search)
        self.start_campaign(
            body, FrozenList(campaign="camp", scenarios=(self.base,)), batch_size=10
        )

    def restart(self) -> None:
        """A new operator: the searcher rebuilt from the pinned logical scenario and the
        batches alone, as the campaign loop does."""
        view = observed.campaign_view(self.get(Kind.CAMPAIGN, "camp") or {})
        assert view.spec is not None and view.spec.search is not None
        batches = [observed.batch_view(b) for b in self.of(Kind.BATCH)]

        async def replay() -> CampaignSearch:
            assert view.spec is not None and view.spec.search is not None
            client = cast(Client, None)  # file sources: nothing is read through the API
            space, target = await resolving.search_space(
                client, view, self.base, config=self.config
            )
            return await CampaignSearch.replayed(view.spec.search, space, target, batches)

        self.search = asyncio.run(replay())

    def inputs(self, name: str = "camp") -> planning.Inputs:
        given = super().inputs(name)
        return dataclasses.replace(given, search=self.search.progress() if self.search else None)

    def step(self, seconds: float = 1.0, *, rounds: int = 4, limit: int | None = None) -> None:
        self.now += datetime.timedelta(seconds=seconds)
        for _ in range(rounds):
            self.kubelet()
            if self.search is None:
                self.restart()
            assert self.search is not None
            self.search.learn([observed.batch_view(b) for b in self.of(Kind.BATCH)])
            plan = self.plan()
            self.apply(plan, limit=limit)
            assert self.search is not None
            view = observed.campaign_view(self.get(Kind.CAMPAIGN, "camp") or {})
            batches = [observed.batch_view(b) for b in self.of(Kind.BATCH)]
            wave = asyncio.run(self.search.advance(view, batches, plan.observation))
            if wave is not None:
                self.apply(Plan(actions=(wave,)))
        running = sum(1 for p in self.of(Kind.POD) if p["status"]["phase"] == "Running")
        if self.search is not None and self.search.progress().open:
            self.busy.append((running, sum(self.nodes.values())))

    def _sut(self, scenario_id: str, attempt: int) -> Script:
        """Fails where the gap is short and ego fast; minTTC shrinks towards that corner."""
        values = self.values()[scenario_id]
        margin = (
            max(float(values["CutInGap"]) - 15.0, 0.0) / 5
            + max(30.0 - float(values["EgoSpeed"]), 0.0) / 5
        )
        verdict = "Failed" if margin == 0.0 else "Passed"
        seconds = 3.0 + int(scenario_id.rsplit("-", 1)[1]) % 4  # results come back one by one
        message = {"scenarioId": scenario_id, "verdict": verdict, "wallSeconds": seconds,
                   "metrics": {"minTTC": margin}}  # fmt: skip
        return Script(seconds=seconds, message=json.dumps(message))

    def values(self) -> dict[str, dict[str, float]]:
        return {
            p.id: {k: json.loads(v) for k, v in p.proposal.values.items()}
            for batch in self.of(Kind.BATCH)
            for p in observed.batch_view(batch).proposals
            if p.proposal is not None
        }

    def proposals(self) -> list[tuple[int, int, tuple[int, ...], dict[str, str]]]:
        """(index, basis, told, values) of every proposal, wave by wave."""
        out = []
        for batch in sorted(self.of(Kind.BATCH), key=lambda b: b["spec"]["index"]):
            for entry in batch["spec"]["scenarios"]:
                record = entry["proposal"]
                out.append(
                    (
                        record["index"],
                        record["basis"],
                        tuple(record.get("told", ())),
                        record["values"],
                    )
                )
        return out


def test_a_search_runs_its_budget_in_waves_that_keep_the_slots_busy() -> None:
    cluster = SearchCluster(nodes={"n0": 2, "n1": 2})
    cluster.start(maxParallel=4)
    cluster.run()
    status = cluster.status()
    assert status["total"] == 20 and len(cluster.results()) == 20
    assert status["phase"] in ("Failed", "Succeeded")
    search = status["search"]
    assert (search["asked"], search["told"], search["budget"]) == (20, 20, 20)
    assert search["failures"] == status["failed"]
    waves = sorted(cluster.of(Kind.BATCH), key=lambda b: b["spec"]["index"])
    assert len(waves[0]["spec"]["scenarios"]) == 4  # the first wave fills the window
    assert len(waves) > 5  # later waves follow the results, a few at a time
    proposals = cluster.proposals()
    assert [p[0] for p in proposals] == list(range(20))
    for index, basis, told, _ in proposals:
        assert basis == sum(len(p[2]) for p in proposals[: index + 1])
        assert all(t < index for t in told)
    assert proposals[-1][1] >= 12  # later proposals learnt from the results before them
    assert cluster.search is not None
    batches = [observed.batch_view(b) for b in cluster.of(Kind.BATCH)]
    frozen, record = asyncio.run(cluster.search.record(batches))
    assert [p.id for p in frozen] == [f"cut-in.xosc#search-{i}" for i in range(20)]
    assert record["summary"]["runs"] == 20 and record["summary"]["failures"] == status["failed"]
    assert [p["index"] for p in record["proposals"]] == list(range(20))
    assert [d["name"] for d in record["dimensions"]] == ["EgoSpeed", "CutInGap"]
    running, slots = map(sum, zip(*cluster.busy, strict=True))
    assert running / slots >= 0.9, f"slots busy {running / slots:.0%} while searching"


def test_an_operator_restart_at_any_step_replays_the_searcher_from_the_batches() -> None:
    cluster = SearchCluster(nodes={"n0": 3})
    cluster.start(maxParallel=3)
    original = cluster.search

    def forget(step: int) -> None:
        cluster.search = None  # every step a new operator: replay must reproduce every wave

    for step in range(1, 200):
        forget(step)
        cluster.step(1.0)
        if cluster.status().get("phase") in ("Failed", "Succeeded") and not cluster.of(
            Kind.ENVIRONMENT
        ):
            break
    assert original is None
    assert cluster.status()["search"]["asked"] == 20
    assert [p[0] for p in cluster.proposals()] == list(range(20))


def test_the_same_seed_and_results_give_the_same_waves() -> None:
    runs = []
    for _ in range(2):
        cluster = SearchCluster(nodes={"n0": 2})
        cluster.start(maxParallel=2)
        cluster.run()
        runs.append(cluster.proposals())
    assert runs[0] == runs[1]
    other = SearchCluster(nodes={"n0": 2})
    other.start({**SEARCH, "seed": 4}, maxParallel=2)
    other.run()
    assert other.proposals() != runs[0]


def test_a_search_campaign_is_not_complete_before_it_proposed_anything() -> None:
    cluster = SearchCluster(nodes={"n0": 2})
    cluster.start(maxParallel=2)
    cluster.restart()
    plan = cluster.plan()
    assert not plan.finished
    assert cluster.status().get("phase") != "Error"


def test_waves_lay_out_as_batches_of_their_own_sizes() -> None:
    layout = Layout(ids=tuple("abcdefg"), batch_size=1, starts=(0, 4, 5))
    assert [layout.batch_of(p) for p in range(7)] == [0, 0, 0, 0, 1, 2, 2]
    assert [layout.slot_of(p) for p in range(7)] == [0, 1, 2, 3, 0, 0, 1]
    assert [list(layout.positions(i)) for i in range(3)] == [[0, 1, 2, 3], [4], [5, 6]]
    assert layout.batch_count() == 3


def test_a_queued_search_asks_kueue_for_its_window_not_for_the_proposals_so_far() -> None:
    """Before a search proposed anything its list is empty: its Workload is sized by the
    budget (capped by the window), else Kueue would admit one simulator for the whole search."""
    cluster = SearchCluster(nodes={"n0": 2, "n1": 2})
    cluster.start(maxParallel=4, queueName="team-a")
    cluster.step()
    workload = cluster.get(Kind.WORKLOAD, "camp-simulators")
    assert workload is not None
    assert workload["spec"]["podSets"][0]["count"] == 4


def _slow_asks(monkeypatch: pytest.MonkeyPatch, seconds: float) -> None:
    """Every ask blocks its thread for ``seconds``, as a classifier fit does."""
    ask = Searcher.ask

    def slow(self: Searcher, n: int) -> list[Proposal]:
        time.sleep(seconds)
        return ask(self, n)

    monkeypatch.setattr(Searcher, "ask", slow)


async def _ticks_during(work: Coroutine[Any, Any, T]) -> tuple[T, int]:
    """``work``'s result and how often another coroutine got the event loop meanwhile."""
    ticks = 0
    done = asyncio.Event()

    async def tick() -> None:
        nonlocal ticks
        while not done.is_set():
            await asyncio.sleep(0.01)
            ticks += 1

    ticker = asyncio.create_task(tick())
    await asyncio.sleep(0)  # the ticker is waiting before the work starts
    ticks = 0
    try:
        result = await work
        during = ticks
    finally:
        done.set()
        await ticker
    return result, during


def test_asking_and_replaying_the_searcher_leave_the_event_loop_free(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A ``boundary`` proposal takes about a second of CPU; the operator's event loop serves
    every campaign and kopf's handlers, so the searcher works in a thread meanwhile."""
    cluster = SearchCluster(nodes={"n0": 2})
    cluster.start(maxParallel=2)
    cluster.restart()
    assert cluster.search is not None
    plan = cluster.plan()
    cluster.apply(plan)
    _slow_asks(monkeypatch, 0.3)
    view = observed.campaign_view(cluster.get(Kind.CAMPAIGN, "camp") or {})
    batches = [observed.batch_view(b) for b in cluster.of(Kind.BATCH)]
    wave, ticks = asyncio.run(
        _ticks_during(cluster.search.advance(view, batches, plan.observation))
    )
    assert wave is not None and len(wave.body["spec"]["scenarios"]) == 2
    assert ticks >= 2, "the event loop was blocked while the searcher was asked"
    cluster.apply(Plan(actions=(wave,)))
    view = observed.campaign_view(cluster.get(Kind.CAMPAIGN, "camp") or {})
    assert view.spec is not None and view.spec.search is not None
    space = SearchSpace.from_spec(view.spec.search, CUT_IN)
    batches = [observed.batch_view(b) for b in cluster.of(Kind.BATCH)]
    replay = CampaignSearch.replayed(view.spec.search, space, cluster.base, batches)
    replayed, ticks = asyncio.run(_ticks_during(replay))
    assert replayed.searcher.asked == 2
    assert ticks >= 2, "the event loop was blocked while the searcher was replayed"


def test_a_search_over_a_distribution_runs_the_scenario_it_names(tmp_path: Path) -> None:
    """The logical scenario is a ParameterValueDistribution: its ranges are the dimensions
    (``parameters`` narrow them) and every proposal runs the scenario file it names, pinned
    from the same source (its URI and sha256), under the distribution's id."""
    shutil.copy(CUT_IN, tmp_path / "cut-in.xosc")
    pvd = tmp_path / "cut-in-pvd.xosc"
    pvd.write_text(DISTRIBUTION)
    cluster = SearchCluster(nodes={"n0": 2})
    cluster.base = PinnedScenario(
        id="cut-in-pvd.xosc", source=pvd.as_uri(), sha256=sha256_hex(pvd.read_bytes())
    )
    narrowed = {**SEARCH, "scenario": "cut-in-pvd.xosc", "parameters": [
        {"name": "CutInGap", "min": 10, "max": 30}]}  # fmt: skip
    cluster.start(narrowed, maxParallel=2)
    cluster.run()
    assert cluster.status()["search"]["asked"] == 20
    target = tmp_path / "cut-in.xosc"
    entries = [e for b in cluster.of(Kind.BATCH) for e in b["spec"]["scenarios"]]
    assert len(entries) == 20
    assert {(e["source"], e["sha256"]) for e in entries} == {
        (target.as_uri(), sha256_hex(target.read_bytes()))
    }
    assert {e["id"].split("#")[0] for e in entries} == {"cut-in-pvd.xosc"}
    for values in cluster.values().values():
        assert 15 <= values["EgoSpeed"] <= 35 and (values["EgoSpeed"] * 2) % 1 == 0
        assert 10 <= values["CutInGap"] <= 30


DISTRIBUTION = """<?xml version="1.0"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="2" date="2026-01-01T00:00:00" description="d" author="a"/>
  <ParameterValueDistribution>
    <ScenarioFile filepath="cut-in.xosc"/>
    <Deterministic>
      <DeterministicSingleParameterDistribution parameterName="EgoSpeed">
        <DistributionRange stepWidth="0.5">
          <Range lowerLimit="15" upperLimit="35"/>
        </DistributionRange>
      </DeterministicSingleParameterDistribution>
      <DeterministicSingleParameterDistribution parameterName="CutInGap">
        <DistributionSet><Element value="5"/><Element value="40"/></DistributionSet>
      </DeterministicSingleParameterDistribution>
    </Deterministic>
  </ParameterValueDistribution>
</OpenSCENARIO>
"""


@pytest.mark.parametrize(
    ("strategy", "libraries"),
    [("hybrid", ("sklearn.gaussian_process", "scipy.stats")), ("tpe", ("optuna",)), ("random", ())],
)
def test_a_model_based_search_imports_its_libraries_while_the_first_wave_runs(
    monkeypatch: pytest.MonkeyPatch, strategy: str, libraries: tuple[str, ...]
) -> None:
    """Importing scikit-learn takes seconds on a busy node; asked only when the start-up design
    is spent, every slot would wait for it."""
    imported: list[str] = []
    monkeypatch.setattr(searching, "import_module", imported.append)
    spec = SearchSpec.model_validate({**SEARCH, "strategy": strategy})
    space = SearchSpace.from_spec(spec, CUT_IN)
    base = PinnedScenario(id="cut-in.xosc", source="file:///cut-in.xosc", sha256="0" * 64)

    async def replay() -> None:
        search = await CampaignSearch.replayed(spec, space, base, [])
        assert search.preloading is not None
        await search.preloading

    asyncio.run(replay())
    assert tuple(imported) == libraries


def test_a_model_based_search_keeps_a_quarter_of_the_window_queued_ahead() -> None:
    """A slot that frees while the model is fitted starts a queued proposal at once; a
    ``random`` search needs no lookahead (its first wave is the window, as above)."""
    cluster = SearchCluster(nodes={"n0": 4, "n1": 4})
    cluster.start({**SEARCH, "strategy": "hybrid", "budget": 24}, maxParallel=8)
    cluster.step()
    waves = sorted(cluster.of(Kind.BATCH), key=lambda b: b["spec"]["index"])
    assert len(waves[0]["spec"]["scenarios"]) == 8 + 2
    cluster.run()
    status = cluster.status()
    assert (status["search"]["asked"], status["total"]) == (24, 24)
    running, slots = map(sum, zip(*cluster.busy, strict=True))
    assert running / slots >= 0.9, f"slots busy {running / slots:.0%} while searching"
