"""A map netconvert cannot convert (``connected_junctions_simple.xodr`` crashes it: "Trying to
add PositionVectors of different lengths") runs on the in-memory backend when the scenario
brings no traffic: SUMO drives nothing else, the engine owns every scenario entity. A scenario
that brings traffic (a swarm, an esmini SumoController) still fails with netconvert's reason."""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.errors import SimulationError
from simtest_operator.openscenario import LoadOptions, load_scenario
from simtest_operator.runner import scenario_execution
from simtest_operator.settings import SimulationSettings
from simtest_operator.sim import SutConfig, Takeover, netcache, open_simulation
from simtest_operator.sim.session import brings_traffic
from simtest_operator.verdicts import Verdict

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev" / "esmini"
CONNECTED = (
    CORPUS / "EnvironmentSimulator" / "Unittest" / "xosc" / "connected_junctions_simple.xosc"
)
SWARM = CORPUS / "resources" / "xosc" / "swarm.xosc"
SUMO_CONTROLLED = CORPUS / "resources" / "xosc" / "cut-in_sumo.xosc"
LOADING = LoadOptions(source_root=CORPUS)


def test_the_scenario_runs_although_netconvert_fails(tmp_path: Path) -> None:
    report = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=CONNECTED,
            nets_dir=tmp_path / "nets",
            sut=SutConfig(takeover=Takeover.NEVER),
            record=False,
            loading=LOADING,
        )
    )
    assert report.outcome.verdict is Verdict.PASSED, report.outcome.reason


def test_which_scenarios_bring_traffic() -> None:
    assert not brings_traffic(load_scenario(CONNECTED, options=LOADING))
    assert brings_traffic(load_scenario(SWARM, options=LOADING))
    assert brings_traffic(load_scenario(SUMO_CONTROLLED, options=LOADING))


def test_a_scenario_with_traffic_still_needs_the_network(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def broken(xodr: Path, **_: object) -> netcache.ConvertedNet:
        raise SimulationError(f"netconvert failed on {xodr} with every fallback")

    monkeypatch.setattr(netcache, "ensure_net", broken)
    with pytest.raises(SimulationError, match="netconvert failed"):
        open_simulation(
            SWARM,
            sut=SutConfig(),
            settings=SimulationSettings(),
            nets_dir=tmp_path,
            loading=LOADING,
        )
    opened = open_simulation(
        CONNECTED,
        sut=SutConfig(),
        settings=SimulationSettings(),
        nets_dir=tmp_path,
        loading=LOADING,
    )
    assert opened.net_file is None  # no SUMO network: the in-memory backend
