"""Fixtures for the OpenSCENARIO loader tests: the dev corpus location and a scenario writer."""

from __future__ import annotations

import textwrap
from collections.abc import Callable
from pathlib import Path

import pytest

ScenarioWriter = Callable[..., Path]

_TEMPLATE = """<?xml version="1.0" encoding="UTF-8"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="{minor}" date="2024-01-01T00:00:00" description="test"
              author="tests"/>
  <ParameterDeclarations>
{parameters}
  </ParameterDeclarations>
  <CatalogLocations>
{catalogs}
  </CatalogLocations>
  <RoadNetwork>
{road}
  </RoadNetwork>
  <Entities>
{entities}
  </Entities>
  <Storyboard>
    <Init>
      <Actions>
{init}
      </Actions>
    </Init>
{stories}
    <StopTrigger>
{stop}
    </StopTrigger>
  </Storyboard>
</OpenSCENARIO>
"""

CAR = """<ScenarioObject name="{name}">
  <Vehicle name="car" vehicleCategory="car">
    <BoundingBox><Center x="1.4" y="0" z="0.75"/><Dimensions width="2" length="5" height="1.5"/>
    </BoundingBox>
    <Performance maxSpeed="69" maxAcceleration="10" maxDeceleration="10"/>
    <Axles>
      <FrontAxle maxSteering="0.5" wheelDiameter="0.8" trackWidth="1.7" positionX="2.9"
                 positionZ="0.4"/>
      <RearAxle maxSteering="0" wheelDiameter="0.8" trackWidth="1.7" positionX="0" positionZ="0.4"/>
    </Axles>
    <Properties/>
  </Vehicle>
</ScenarioObject>"""


@pytest.fixture(scope="session")
def corpus_dir() -> Path:
    """The shared development corpus (../shared/scenarios-dev next to the repository)."""
    path = Path(__file__).resolve().parents[2].parent / "shared" / "scenarios-dev"
    if not path.is_dir():
        pytest.skip(f"development corpus not found at {path} (read-only shared data is absent)")
    return path


@pytest.fixture
def write_scenario(tmp_path: Path) -> ScenarioWriter:
    """Write a scenario file from parts; returns its path. Unset parts get small defaults."""

    def write(
        *,
        name: str = "scenario.xosc",
        minor: int = 2,
        parameters: str = "",
        catalogs: str = "",
        road: str = "",
        entities: str | None = None,
        init: str = "",
        stories: str = "",
        stop: str = "",
    ) -> Path:
        text = _TEMPLATE.format(
            minor=minor,
            parameters=textwrap.indent(textwrap.dedent(parameters), "    "),
            catalogs=textwrap.indent(textwrap.dedent(catalogs), "    "),
            road=textwrap.indent(textwrap.dedent(road), "    "),
            entities=CAR.format(name="Ego") if entities is None else textwrap.dedent(entities),
            init=textwrap.dedent(init),
            stories=textwrap.dedent(stories),
            stop=textwrap.dedent(stop),
        )
        path = tmp_path / name
        path.write_text(text, encoding="utf-8")
        return path

    return write
