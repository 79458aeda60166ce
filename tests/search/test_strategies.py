"""Each strategy on a cheap synthetic system with two known failure regions."""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.api.v1alpha1 import SearchSpec, SearchStrategy
from simtest_operator.search import Searcher, SearchSpace
from simtest_operator.search.analysis import summarise
from tests.search.conftest import synthetic

PARAMETERS = [
    {"name": "EgoSpeed", "min": 15, "max": 35},
    {"name": "CutInGap", "min": 5, "max": 40},
    {"name": "TargetSpeed", "min": 5, "max": 30},
]


def run(cut_in: Path, strategy: SearchStrategy, budget: int, seed: int = 0) -> Searcher:
    spec = SearchSpec.model_validate(
        {
            "scenario": str(cut_in),
            "parameters": PARAMETERS,
            "strategy": strategy,
            "budget": budget,
            "seed": seed,
        }
    )
    searcher = Searcher(spec, SearchSpace.from_spec(spec, cut_in))
    while searcher.remaining:
        for proposal in searcher.ask(8):
            searcher.tell(proposal.index, synthetic(proposal.values))
    return searcher


def failures(searcher: Searcher) -> int:
    return sum(outcome.failed for _, outcome in searcher.records)


@pytest.mark.parametrize("strategy", [SearchStrategy.GRID, SearchStrategy.RANDOM])
def test_baselines_find_some_failures(cut_in: Path, strategy: SearchStrategy) -> None:
    searcher = run(cut_in, strategy, 125)
    assert 0 < failures(searcher) < 40


def test_tpe_concentrates_on_failures(cut_in: Path) -> None:
    random = failures(run(cut_in, SearchStrategy.RANDOM, 80))
    tpe = failures(run(cut_in, SearchStrategy.TPE, 80))
    assert tpe >= 2 * random


def test_boundary_strategy_finds_both_regions_and_the_boundary(cut_in: Path) -> None:
    searcher = run(cut_in, SearchStrategy.BOUNDARY, 80)
    random = run(cut_in, SearchStrategy.RANDOM, 80)
    summary = summarise(searcher.space, searcher.records, searcher.spec.objectives)
    gaps = [float(r.centre["CutInGap"]) for r in summary.regions]
    assert min(gaps) < 13 and max(gaps) > 29  # the corner and the pocket
    assert summary.failures == failures(searcher)
    assert failures(searcher) > failures(random)
