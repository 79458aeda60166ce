"""The libsumo backend on real SUMO: angle and front-bumper conversions, mirroring of engine
actors (off by default, exact moveToXY placement when on), background traffic from a .sumocfg
read back at its reference point, the one-simulation-per-process guard, and a whole scenario
on SUMO with its recording read back (our reader and omega-prime with validation)."""

from __future__ import annotations

import contextlib
import dataclasses
import io
import math
import warnings
from pathlib import Path
from typing import Any

import pytest

from simtest_operator.errors import SimulationError
from simtest_operator.evaluation import quality
from simtest_operator.recording import objects, read_trajectories
from simtest_operator.runner import scenario_execution
from simtest_operator.sim import SutConfig, Takeover, netcache
from simtest_operator.sim.backends import ActorSpec, BackendConfig
from simtest_operator.sim.sumo import SumoBackend, odr_heading, sumo_angle
from simtest_operator.snapshots import EntityKind, JumpCause
from simtest_operator.verdicts import Verdict

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev" / "esmini" / "resources"


def libsumo() -> Any:
    with contextlib.redirect_stdout(io.StringIO()):
        import libsumo as lib
    return lib


@pytest.fixture(scope="module")
def net(tmp_path_factory: pytest.TempPathFactory) -> Path:
    cache = tmp_path_factory.mktemp("nets")
    return netcache.ensure_net(CORPUS / "xodr" / "straight_500m.xodr", cache_dir=cache).path


def test_angle_conversions() -> None:
    assert sumo_angle(0.0) == pytest.approx(90.0)
    assert sumo_angle(math.pi / 2) == pytest.approx(0.0)
    for heading in (-3.0, -1.0, 0.0, 0.5, 3.0):
        assert odr_heading(sumo_angle(heading)) == pytest.approx(heading)


def test_mirroring_places_front_bumper_exactly(net: Path) -> None:
    backend = SumoBackend()
    backend.start(BackendConfig(net_file=net, mirror=True))
    try:
        backend.add(
            ActorSpec(name="car", kind=EntityKind.VEHICLE, length=4.0, width=2.0, front_offset=3.0)
        )
        backend.place("car", x=100.0, y=-1.5, heading=0.0, speed=10.0)
        backend.step()  # inserted at its departure speed 0 in this step
        backend.place("car", x=100.5, y=-1.5, heading=0.0, speed=10.0)
        backend.step()
        lib = libsumo()
        assert lib.vehicle.getPosition("car") == pytest.approx((103.5, -1.5))
        assert lib.vehicle.getAngle("car") == pytest.approx(90.0)
        assert lib.vehicle.getSpeed("car") == pytest.approx(10.0)
        assert backend.states()["car"].x == pytest.approx(100.5)
        with pytest.raises(SimulationError, match="one scenario per process"):
            SumoBackend().start(BackendConfig(net_file=net))
    finally:
        backend.close()


def test_no_mirroring_without_sumo_traffic(net: Path) -> None:
    backend = SumoBackend()
    backend.start(BackendConfig(net_file=net))
    try:
        backend.add(
            ActorSpec(name="car", kind=EntityKind.VEHICLE, length=4.0, width=2.0, front_offset=3.0)
        )
        backend.place("car", x=100.0, y=-1.5, heading=0.0, speed=10.0)
        backend.step()
        assert libsumo().vehicle.getIDList() == ()
        assert set(backend.states()) == {"car"}
    finally:
        backend.close()


@pytest.mark.slow
def test_background_traffic_from_sumocfg_is_reported() -> None:
    backend = SumoBackend()
    backend.start(BackendConfig(sumo_config=CORPUS / "sumo_inputs" / "straight.sumocfg"))
    try:
        for _ in range(100):
            backend.step()
        external = [s for s in backend.states().values() if s.external]
        assert external, "SUMO vehicles from the route file should be driving"
        lib = libsumo()
        for state in external:
            front_x, front_y = lib.vehicle.getPosition(state.name)
            assert state.x + state.front_offset * math.cos(state.heading) == pytest.approx(front_x)
            assert state.y + state.front_offset * math.sin(state.heading) == pytest.approx(front_y)
    finally:
        backend.close()


@pytest.mark.slow
def test_scenario_on_sumo_with_recording(tmp_path: Path) -> None:
    report = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=CORPUS / "xosc" / "cut-in.xosc",
            nets_dir=tmp_path / "nets",
            output_dir=tmp_path / "out",
            sut=SutConfig(takeover=Takeover.NEVER),
        )
    )
    outcome = report.outcome
    assert outcome.verdict is Verdict.FAILED and "collided" in outcome.reason
    assert outcome.metrics["realTimeFactor"] > 10
    recording = Path(outcome.artifacts["recording"])
    assert (tmp_path / "out" / "result.json").is_file() and (tmp_path / "out" / "run.log").is_file()
    trajectories = read_trajectories(recording)
    assert len(trajectories) == 2
    frames = {len(samples) for samples in trajectories.values()}
    assert frames == {round(outcome.simulated_seconds * 10) + 1}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        import omega_prime

        loaded = omega_prime.Recording.from_file(
            str(recording), validate=True, parse_map=True, apply_proj=False
        )
    assert loaded.host_vehicle_idx == 0
    assert loaded.df["idx"].n_unique() == 2


@pytest.mark.slow
def test_jumps_of_sumo_driven_traffic_are_declared_as_the_traffic_models(tmp_path: Path) -> None:
    # esmini's cut-in_sumo: SUMO drives vehicles from its own route file over a hand-made net
    # whose turnaround lanes (radius 1.9 m, shorter than a car) do not meet their approaches,
    # so SUMO moves them metres in one step. Those steps are declared SUMO's (the run is judged,
    # not faulted for incomplete evidence), the scenario's own entities declare nothing, and the
    # recording carries the declarations that make it complete evidence when judged again.
    report = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=CORPUS / "xosc" / "cut-in_sumo.xosc",
            nets_dir=tmp_path / "nets",
            output_dir=tmp_path / "out",
            sut=SutConfig(takeover=Takeover.NEVER),
        )
    )
    assert report.outcome.verdict is Verdict.PASSED, report.outcome.reason
    decoded = objects.read_objects(Path(report.outcome.artifacts["recording"]))
    jumps = decoded.discontinuities
    assert jumps and {j.cause for j in jumps} == {JumpCause.TRAFFIC_MODEL}
    assert min(j.entity for j in jumps) >= 2  # Ego and OverTaker are 0 and 1
    seconds = report.outcome.simulated_seconds
    assert quality.assess(decoded, simulated_seconds=seconds).complete
    blind = dataclasses.replace(decoded, discontinuities=())
    issues = quality.assess(blind, simulated_seconds=seconds).issues
    assert any("against its velocity" in issue for issue in issues), issues
