"""The searcher: budget, determinism, out-of-order tells and replay after a restart."""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.api.v1alpha1 import SearchSpec, SearchStrategy
from simtest_operator.search import Outcome, Proposal, ReplayError, Searcher, SearchSpace
from simtest_operator.verdicts import Verdict
from tests.search.conftest import synthetic

PARAMETERS = [
    {"name": "EgoSpeed", "min": 15, "max": 35},
    {"name": "CutInGap", "min": 5, "max": 40, "step": 1},
    {"name": "TargetSpeed", "min": 5, "max": 30},
]


def make(cut_in: Path, strategy: SearchStrategy, budget: int = 28, seed: int = 7) -> Searcher:
    """A small budget: the boundary strategy fits its classifier after 16 Sobol points."""
    spec = SearchSpec.model_validate(
        {
            "scenario": str(cut_in),
            "parameters": PARAMETERS,
            "strategy": strategy,
            "budget": budget,
            "seed": seed,
        }
    )
    return Searcher(spec, SearchSpace.from_spec(spec, cut_in))


def drive(searcher: Searcher, batch: int) -> list[tuple[int, Outcome]]:
    """Run the search in waves of ``batch``, telling each wave in reverse order."""
    tells = []
    while searcher.remaining:
        wave = searcher.ask(batch)
        for proposal in reversed(wave):
            outcome = synthetic(proposal.values)
            searcher.tell(proposal.index, outcome)
            tells.append((proposal.index, outcome))
    return tells


@pytest.mark.parametrize("strategy", list(SearchStrategy))
def test_the_budget_is_never_exceeded(cut_in: Path, strategy: SearchStrategy) -> None:
    searcher = make(cut_in, strategy, budget=13)
    first = searcher.ask(10)
    assert [p.index for p in first] == list(range(10))
    assert all(p.basis == 0 for p in first)
    # The grid stops at the largest even grid within the budget: 3 x 2 x 2.
    rest = 2 if strategy is SearchStrategy.GRID else 3
    assert len(searcher.ask(10)) == rest
    assert searcher.ask(5) == []
    assert searcher.remaining == 0 and searcher.asked == 10 + rest
    for p in first:
        searcher.tell(p.index, synthetic(p.values))
    assert searcher.told == 10


@pytest.mark.parametrize("strategy", list(SearchStrategy))
def test_proposals_are_a_function_of_seed_asks_and_tells(
    cut_in: Path, strategy: SearchStrategy
) -> None:
    one, two = make(cut_in, strategy), make(cut_in, strategy)
    drive(one, 4)
    drive(two, 4)
    assert one.proposals == two.proposals
    assert all(35 >= p.values["EgoSpeed"] >= 15 for p in one.proposals)  # type: ignore[operator]
    assert all(float(p.values["CutInGap"]).is_integer() for p in one.proposals)
    if strategy is not SearchStrategy.GRID:
        other = make(cut_in, strategy, seed=8)
        drive(other, 4)
        assert other.proposals != one.proposals


@pytest.mark.parametrize("strategy", list(SearchStrategy))
def test_batching_does_not_change_the_proposals(cut_in: Path, strategy: SearchStrategy) -> None:
    one, two = make(cut_in, strategy, budget=30), make(cut_in, strategy, budget=30)
    together = one.ask(20)
    apart = two.ask(7) + two.ask(13)
    assert together == apart


@pytest.mark.parametrize("strategy", list(SearchStrategy))
def test_replay_reproduces_a_search_told_out_of_order(
    cut_in: Path, strategy: SearchStrategy
) -> None:
    searcher = make(cut_in, strategy)
    tells = drive(searcher, 6)
    replayed = Searcher.replay(searcher.spec, searcher.space, searcher.proposals, tells)
    assert replayed.proposals == searcher.proposals
    assert replayed.records == searcher.records
    # Half-way: the restarted searcher continues exactly as the original would have.
    half = make(cut_in, strategy)
    wave = half.ask(6)
    for p in reversed(wave[2:]):
        half.tell(p.index, synthetic(p.values))
    told = [(i, o) for i, o in tells if i in {p.index for p in wave[2:]}]
    resumed = Searcher.replay(half.spec, half.space, half.proposals, told)
    assert resumed.ask(3) == half.ask(3)


def test_replay_detects_another_search(cut_in: Path) -> None:
    searcher = make(cut_in, SearchStrategy.RANDOM)
    tells = drive(searcher, 5)
    other = make(cut_in, SearchStrategy.RANDOM, seed=99)
    with pytest.raises(ReplayError, match="replays as"):
        Searcher.replay(other.spec, other.space, searcher.proposals, tells)
    forged = [Proposal(index=0, values=searcher.proposals[0].values, basis=3)]
    with pytest.raises(ReplayError, match="unrecorded"):
        Searcher.replay(searcher.spec, searcher.space, forged, [])


def test_each_proposal_is_told_once(cut_in: Path) -> None:
    searcher = make(cut_in, SearchStrategy.RANDOM)
    (p,) = searcher.ask(1)
    searcher.tell(p.index, Outcome(Verdict.PASSED))
    with pytest.raises(ValueError, match="already told"):
        searcher.tell(p.index, Outcome(Verdict.PASSED))
    with pytest.raises(ValueError, match="never asked"):
        searcher.tell(5, Outcome(Verdict.PASSED))


def test_overrides_are_openscenario_text() -> None:
    proposal = Proposal(index=0, values={"EgoSpeed": 25.0, "Gap": 12.5, "Mode": "fast"}, basis=0)
    assert proposal.overrides() == {"EgoSpeed": "25", "Gap": "12.5", "Mode": "fast"}
