"""A search's proposals in the frozen list: what pins them and what replays them.

Covers: a proposal pinned and read back is the same proposal (floats exactly, choices as text),
with the campaign's overrides under its values; the JSON wire form round-trips through the
frozen list; the replay inputs are rebuilt from the pins in tell order, and a gap in the
proposals, a tell whose result is gone or a basis that disagrees with the recorded tells is
refused rather than replayed into a different search.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from simtest_operator.errors import ScenarioError, SourceError
from simtest_operator.runner import resolving
from simtest_operator.scenarios import (
    FetchContext,
    FrozenList,
    PathSource,
    PinnedScenario,
    Selection,
    uris,
)
from simtest_operator.search import Outcome, Proposal
from simtest_operator.verdicts import Verdict

CUT_IN = Path(__file__).parents[2] / "scenarios/library/cut-in/cut-in_highway_v25_gap15_dv10.xosc"
BASE = PinnedScenario(
    id="cut-in.xosc", source="file:///s/cut-in.xosc", sha256="a" * 64, overrides={"Mode": "x"}
)


def test_a_pinned_proposal_reads_back_exactly() -> None:
    proposal = Proposal(index=3, values={"EgoSpeed": 0.1 + 0.2, "Lane": "left"}, basis=2)
    pinned = resolving.pin_proposal(BASE, proposal, told=(1, 0))
    assert pinned.id == "cut-in.xosc#search-3"
    assert (pinned.source, pinned.sha256) == (BASE.source, BASE.sha256)
    assert pinned.overrides["Mode"] == "x" and pinned.overrides["Lane"] == "left"
    assert pinned.proposal is not None and pinned.proposal.told == (1, 0)
    again = resolving.proposal_of(pinned.proposal)
    assert again == proposal and again.values["EgoSpeed"] == 0.30000000000000004
    listed = FrozenList(campaign="c", scenarios=(pinned,))
    assert FrozenList.from_json(listed.to_json()) == listed


def _pins(*told: tuple[int, ...]) -> list[PinnedScenario]:
    pins, basis = [], 0
    for index, before in enumerate(told):
        basis += len(before)
        proposal = Proposal(index=index, values={"EgoSpeed": 20.0 + index}, basis=basis)
        pins.append(resolving.pin_proposal(BASE, proposal, told=before))
    return pins


def test_replay_inputs_follow_the_recorded_tell_order() -> None:
    pins = [p.proposal for p in _pins((), (), (1,), (0,)) if p.proposal is not None]
    outcomes = {i: Outcome(Verdict.PASSED if i else Verdict.FAILED) for i in range(4)}
    proposals, tells = resolving.replay_inputs(pins, outcomes)
    assert [p.index for p in proposals] == [0, 1, 2, 3]
    assert [i for i, _ in tells] == [1, 0]
    assert tells[1][1].verdict is Verdict.FAILED


def test_a_search_record_that_would_replay_differently_is_refused() -> None:
    pins = [p.proposal for p in _pins((), (), (1,)) if p.proposal is not None]
    outcomes = {0: Outcome(Verdict.PASSED), 1: Outcome(Verdict.PASSED)}
    with pytest.raises(ScenarioError, match="proposal 1 is missing"):
        resolving.replay_inputs([pins[0], pins[2]], outcomes)
    with pytest.raises(ScenarioError, match="no longer recorded"):
        resolving.replay_inputs(pins, {0: Outcome(Verdict.PASSED)})
    wrong = [pins[0], pins[1], type(pins[2])(index=2, basis=2, told=(1,), values=pins[2].values)]
    with pytest.raises(ScenarioError, match="says 2 results were told"):
        resolving.replay_inputs(wrong, outcomes)


def test_a_search_names_a_file_of_its_selection(tmp_path: Path) -> None:
    suite = tmp_path / "suite"
    suite.mkdir()
    shutil.copy(CUT_IN, suite / "cut-in.xosc")
    selection = Selection(sources=(PathSource(path="suite"),))
    ctx = FetchContext(base_dir=tmp_path, cache_dir=tmp_path / "cache")
    frozen = resolving.freeze_search(selection, ctx, campaign="c", scenario="cut-in.xosc")
    (base,) = frozen.scenarios
    assert base.id == "cut-in.xosc" and base.source.endswith("/suite/cut-in.xosc")
    with pytest.raises(ScenarioError, match="not among the 1 scenario"):
        resolving.freeze_search(selection, ctx, campaign="c", scenario="other.xosc")


def test_a_distributions_scenario_is_pinned_from_the_distributions_source(tmp_path: Path) -> None:
    """:func:`uris.sibling`: the file a distribution names gets a URI of the same source."""
    tree = tmp_path / "tree"
    (tree / "dist").mkdir(parents=True)
    pvd, scenario = tree / "dist" / "d.xosc", tree / "s.xosc"
    commit = "a" * 40
    git = uris.git_uri("https://example.test/r.git", commit, "dist/d.xosc")
    assert uris.sibling(git, pvd, scenario) == uris.git_uri(
        "https://example.test/r.git", commit, "s.xosc"
    )
    archive = uris.http_uri("https://example.test/a.tgz", "dist/d.xosc")
    assert uris.sibling(archive, pvd, scenario) == "https://example.test/a.tgz#s.xosc"
    assert uris.sibling(uris.file_uri(pvd), pvd, scenario) == uris.file_uri(scenario)
    with pytest.raises(SourceError, match="outside the source"):
        uris.sibling(git, pvd, tmp_path / "elsewhere.xosc")
    single = uris.http_uri("https://example.test/d.xosc")
    with pytest.raises(SourceError, match="single downloaded file"):
        uris.sibling(single, tmp_path / "dl" / "d.xosc", tmp_path / "dl" / "s.xosc")
