"""ParameterValueDistribution expansion into concrete runs.

Covers: value sets x sets x ranges as a cartesian product in stable order; stable ids
(``<stem>#<k>-<hash>``, same across calls, hash depends on the assignment); range end points and
float noise; every run loading with its overrides; stochastic distributions reproducible from
``randomSeed`` or the caller's seed and respecting ranges; rejection of parameters the scenario
does not declare, user-defined distributions, empty and oversize ranges; is_distribution and
file_kind.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.errors import ScenarioError, UnsupportedFeatureError
from simtest_operator.openscenario import (
    FileKind,
    expand_distribution,
    file_kind,
    is_distribution,
    load_scenario,
)
from tests.openscenario.conftest import ScenarioWriter

GLOBALS = """<ParameterDeclaration name="Vehicle" parameterType="string" value="a"/>
<ParameterDeclaration name="Other" parameterType="string" value="b"/>
<ParameterDeclaration name="Speed" parameterType="double" value="10"/>
<ParameterDeclaration name="Factor" parameterType="double" value="1"/>"""

HEAD = """<?xml version="1.0" encoding="utf-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="2" date="2024-01-01T00:00:00" description="d" author="t"/>
  <ParameterValueDistribution>
    <ScenarioFile filepath="scenario.xosc"/>
"""
TAIL = """  </ParameterValueDistribution>
</OpenSCENARIO>
"""

DETERMINISTIC = """<Deterministic>
  <DeterministicMultiParameterDistribution><ValueSetDistribution>
    <ParameterValueSet>
      <ParameterAssignment parameterRef="Vehicle" value="x"/>
      <ParameterAssignment parameterRef="Other" value="y"/>
    </ParameterValueSet>
    <ParameterValueSet><ParameterAssignment parameterRef="Other" value="z"/></ParameterValueSet>
  </ValueSetDistribution></DeterministicMultiParameterDistribution>
  <DeterministicSingleParameterDistribution parameterName="Speed">
    <DistributionSet><Element value="70"/><Element value="110"/></DistributionSet>
  </DeterministicSingleParameterDistribution>
  <DeterministicSingleParameterDistribution parameterName="Factor">
    <DistributionRange stepWidth="0.1"><Range lowerLimit="1.1" upperLimit="1.3"/>
    </DistributionRange>
  </DeterministicSingleParameterDistribution>
</Deterministic>
"""


def write_distribution(directory: Path, body: str, name: str = "dist.xosc") -> Path:
    path = directory / name
    path.write_text(HEAD + body + TAIL)
    return path


def test_deterministic_product_with_stable_ids(write_scenario: ScenarioWriter) -> None:
    scenario = write_scenario(parameters=GLOBALS)
    path = write_distribution(scenario.parent, DETERMINISTIC)
    runs = expand_distribution(path)
    assert len(runs) == 2 * 2 * 3
    assert [dict(r.overrides) for r in runs[:3]] == [
        {"Vehicle": "x", "Other": "y", "Speed": "70", "Factor": "1.1"},
        {"Vehicle": "x", "Other": "y", "Speed": "70", "Factor": "1.2"},
        {"Vehicle": "x", "Other": "y", "Speed": "70", "Factor": "1.3"},
    ]
    assert dict(runs[-1].overrides) == {"Other": "z", "Speed": "110", "Factor": "1.3"}
    assert runs[0].id.startswith("dist#1-") and runs[11].id.startswith("dist#12-")
    assert len({r.id.split("-")[-1] for r in runs}) == 12  # distinct assignment hashes
    assert [r.id for r in expand_distribution(path)] == [r.id for r in runs]  # stable
    assert all(r.scenario == scenario.resolve() for r in runs)
    for run in runs:
        loaded = load_scenario(run.scenario, overrides=run.overrides)
        speed = loaded.parameter("Speed")
        assert speed is not None and speed.value == float(run.overrides["Speed"])
    with pytest.raises(TypeError):
        runs[0].overrides["Speed"] = "1"  # type: ignore[index]


def test_kinds(write_scenario: ScenarioWriter) -> None:
    scenario = write_scenario(parameters=GLOBALS)
    path = write_distribution(scenario.parent, DETERMINISTIC)
    assert is_distribution(path)
    assert not is_distribution(scenario)
    assert file_kind(scenario) is FileKind.SCENARIO
    with pytest.raises(ScenarioError, match="is a distribution, not a scenario"):
        load_scenario(path)


STOCHASTIC = """<Stochastic numberOfTestRuns="20" {seed}>
  <StochasticDistribution parameterName="Speed">
    <NormalDistribution expectedValue="30" variance="4"><Range lowerLimit="27" upperLimit="33"/>
    </NormalDistribution>
  </StochasticDistribution>
  <StochasticDistribution parameterName="Factor">
    <UniformDistribution><Range lowerLimit="1" upperLimit="2"/></UniformDistribution>
  </StochasticDistribution>
  <StochasticDistribution parameterName="Vehicle">
    <ProbabilityDistributionSet>
      <Element value="car" weight="3"/><Element value="truck" weight="1"/>
    </ProbabilityDistributionSet>
  </StochasticDistribution>
  <StochasticDistribution parameterName="Other">
    <Histogram><Bin weight="1"><Range lowerLimit="0" upperLimit="1"/></Bin></Histogram>
  </StochasticDistribution>
</Stochastic>
"""


def test_stochastic_is_reproducible(write_scenario: ScenarioWriter) -> None:
    scenario = write_scenario(parameters=GLOBALS)
    seeded = write_distribution(scenario.parent, STOCHASTIC.format(seed='randomSeed="7"'), "s.xosc")
    first, second = expand_distribution(seeded), expand_distribution(seeded, seed=99)
    assert [dict(r.overrides) for r in first] == [dict(r.overrides) for r in second]
    assert len(first) == 20
    for run in first:
        assert 27 <= float(run.overrides["Speed"]) <= 33
        assert 1 <= float(run.overrides["Factor"]) <= 2
        assert run.overrides["Vehicle"] in ("car", "truck")
        assert 0 <= float(run.overrides["Other"]) <= 1
    unseeded = write_distribution(scenario.parent, STOCHASTIC.format(seed=""), "u.xosc")
    a, b = expand_distribution(unseeded, seed=1), expand_distribution(unseeded, seed=2)
    assert [dict(r.overrides) for r in a] != [dict(r.overrides) for r in b]
    assert [dict(r.overrides) for r in a] == [
        dict(r.overrides) for r in expand_distribution(unseeded, seed=1)
    ]


@pytest.mark.parametrize(
    ("body", "error", "message"),
    [
        (
            DETERMINISTIC.replace('parameterName="Speed"', 'parameterName="Sped"'),
            ScenarioError,
            "declares no parameter",
        ),
        (
            """<Deterministic><DeterministicSingleParameterDistribution parameterName="Speed">
            <UserDefinedDistribution type="mine">1,2</UserDefinedDistribution>
            </DeterministicSingleParameterDistribution></Deterministic>""",
            UnsupportedFeatureError,
            "user-defined",
        ),
        (
            """<Deterministic><DeterministicSingleParameterDistribution parameterName="Speed">
            <DistributionRange stepWidth="0.000001"><Range lowerLimit="0" upperLimit="1000"/>
            </DistributionRange></DeterministicSingleParameterDistribution></Deterministic>""",
            ScenarioError,
            "limit",
        ),
        (
            """<Deterministic><DeterministicSingleParameterDistribution parameterName="Speed">
            <DistributionSet/></DeterministicSingleParameterDistribution></Deterministic>""",
            ScenarioError,
            "no values",
        ),
    ],
    ids=["unknown-parameter", "user-defined", "oversize", "empty"],
)
def test_rejects(
    write_scenario: ScenarioWriter, body: str, error: type[Exception], message: str
) -> None:
    scenario = write_scenario(parameters=GLOBALS)
    path = write_distribution(scenario.parent, body)
    with pytest.raises(error, match=message):
        expand_distribution(path)
