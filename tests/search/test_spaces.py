"""Search spaces from a spec and from a ParameterValueDistribution."""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.api.v1alpha1 import SearchSpec
from simtest_operator.errors import ScenarioError, UnsupportedFeatureError
from simtest_operator.search import Dimension, SearchSpace


def make_spec(scenario: Path, parameters: list[dict[str, object]], **more: object) -> SearchSpec:
    return SearchSpec.model_validate(
        {"scenario": str(scenario), "parameters": parameters, "budget": 50} | more
    )


def test_from_spec_keeps_order_ranges_steps_and_choices(cut_in: Path) -> None:
    spec = make_spec(
        cut_in,
        [
            {"name": "EgoSpeed", "min": 15, "max": 35},
            {"name": "CutInGap", "min": 5, "max": 40, "step": 5},
            {"name": "LaneChangeTime", "choices": ["1.5", "2.5"]},
        ],
    )
    space = SearchSpace.from_spec(spec, cut_in)
    assert space.names == ("EgoSpeed", "CutInGap", "LaneChangeTime")
    assert space.scenario == cut_in
    assert space.decode([0.5, 0.33, 0.9]) == {
        "EgoSpeed": 25.0,
        "CutInGap": 15.0,
        "LaneChangeTime": "2.5",
    }
    values = {"EgoSpeed": 20.0, "CutInGap": 40.0, "LaneChangeTime": "1.5"}
    assert space.decode(space.encode(values)) == values
    assert SearchSpace.from_spec(spec, cut_in.read_bytes()).dimensions == space.dimensions


def test_undeclared_parameters_are_refused(cut_in: Path) -> None:
    spec = make_spec(cut_in, [{"name": "Nope", "min": 0, "max": 1}])
    with pytest.raises(ScenarioError, match="declares no parameter"):
        SearchSpace.from_spec(spec, cut_in)


def test_a_plain_scenario_needs_parameters(cut_in: Path) -> None:
    with pytest.raises(ScenarioError, match="at least one parameter"):
        SearchSpace.from_spec(make_spec(cut_in, []), cut_in)


def write_distribution(tmp_path: Path, scenario: Path, body: str) -> Path:
    path = tmp_path / "cut-in.xosc"
    path.write_text(
        f"""<?xml version="1.0"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="2" date="2026-01-01T00:00:00" description="d" author="a"/>
  <ParameterValueDistribution>
    <ScenarioFile filepath="{scenario}"/>
    {body}
  </ParameterValueDistribution>
</OpenSCENARIO>
"""
    )
    return path


def test_from_a_deterministic_distribution(tmp_path: Path, cut_in: Path) -> None:
    path = write_distribution(
        tmp_path,
        cut_in,
        """<Deterministic>
      <DeterministicSingleParameterDistribution parameterName="EgoSpeed">
        <DistributionRange stepWidth="5">
          <Range lowerLimit="15" upperLimit="35"/>
        </DistributionRange>
      </DeterministicSingleParameterDistribution>
      <DeterministicSingleParameterDistribution parameterName="LaneChangeTime">
        <DistributionSet><Element value="1.5"/><Element value="3"/></DistributionSet>
      </DeterministicSingleParameterDistribution>
    </Deterministic>""",
    )
    space = SearchSpace.from_distribution(path)
    assert space.scenario == cut_in.resolve()
    assert space.dimensions == (
        Dimension(name="EgoSpeed", low=15.0, high=35.0, step=5.0),
        Dimension(name="LaneChangeTime", choices=("1.5", "3")),
    )
    assert len(space.grid(1000)) == 5 * 2
    # The spec narrows a distribution's dimension and adds another.
    spec = make_spec(
        path,
        [{"name": "EgoSpeed", "min": 20, "max": 30}, {"name": "CutInGap", "min": 5, "max": 40}],
    )
    narrowed = SearchSpace.from_spec(spec, path)
    assert narrowed.names == ("EgoSpeed", "LaneChangeTime", "CutInGap")
    assert narrowed.dimensions[0] == Dimension(name="EgoSpeed", low=20.0, high=30.0)


def test_from_a_stochastic_distribution(tmp_path: Path, cut_in: Path) -> None:
    path = write_distribution(
        tmp_path,
        cut_in,
        """<Stochastic numberOfTestRuns="10" randomSeed="1">
      <StochasticDistribution parameterName="EgoSpeed">
        <UniformDistribution><Range lowerLimit="15" upperLimit="35"/></UniformDistribution>
      </StochasticDistribution>
      <StochasticDistribution parameterName="TargetSpeed">
        <NormalDistribution expectedValue="15" variance="4">
          <Range lowerLimit="10" upperLimit="20"/>
        </NormalDistribution>
      </StochasticDistribution>
      <StochasticDistribution parameterName="CutInGap">
        <Histogram>
          <Bin weight="1"><Range lowerLimit="5" upperLimit="10"/></Bin>
          <Bin weight="2"><Range lowerLimit="10" upperLimit="30"/></Bin>
        </Histogram>
      </StochasticDistribution>
      <StochasticDistribution parameterName="LaneChangeTime">
        <ProbabilityDistributionSet>
          <Element value="2" weight="1"/><Element value="4" weight="1"/>
        </ProbabilityDistributionSet>
      </StochasticDistribution>
    </Stochastic>""",
    )
    space = SearchSpace.from_spec(make_spec(path, []), path)
    assert space.dimensions == (
        Dimension(name="EgoSpeed", low=15.0, high=35.0),
        Dimension(name="TargetSpeed", low=10.0, high=20.0),
        Dimension(name="CutInGap", low=5.0, high=30.0),
        Dimension(name="LaneChangeTime", choices=("2", "4")),
    )


def test_unbounded_distributions_are_no_dimension(tmp_path: Path, cut_in: Path) -> None:
    path = write_distribution(
        tmp_path,
        cut_in,
        """<Stochastic numberOfTestRuns="10">
      <StochasticDistribution parameterName="EgoSpeed">
        <NormalDistribution expectedValue="25" variance="4"/>
      </StochasticDistribution>
    </Stochastic>""",
    )
    with pytest.raises(UnsupportedFeatureError, match="unbounded"):
        SearchSpace.from_distribution(path)


def test_grid_spends_the_budget_evenly() -> None:
    space = SearchSpace(
        scenario=None,
        dimensions=(
            Dimension(name="a", low=0, high=10),
            Dimension(name="b", low=0, high=10),
            Dimension(name="c", choices=("x", "y")),
        ),
    )
    grid = space.grid(50)
    assert len(grid) == 5 * 5 * 2
    assert len({tuple(sorted(v.items())) for v in grid}) == len(grid)
    assert {v["a"] for v in grid} == {0.0, 2.5, 5.0, 7.5, 10.0}
    assert len(space.grid(3)) == 3
