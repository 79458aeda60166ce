"""The velocity a state reports is the motion the simulation gave the entity: the rate of its
reference point along its lane or path and across it, whatever its heading (an entity placed at
an angle to its lane crabs along it; a trajectory may give headings of its own; a lane change
tilts the heading towards the motion, which must not count the lateral part twice). The box
centre turns round the reference point at the yaw rate. Files of the development corpus that
exercise this end with the evidence gate satisfied (each ended ``Error`` before: the recorded
velocity did not explain the recorded positions)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from simtest_operator.openscenario import model
from simtest_operator.runner import scenario_execution
from simtest_operator.sim import BackendChoice, SutConfig, Takeover
from simtest_operator.snapshots import JumpCause
from simtest_operator.verdicts import Verdict
from tests.sim.worlds import DT, Bench, lane, speed, teleport

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev" / "esmini"
UNITTEST = CORPUS / "EnvironmentSimulator" / "Unittest" / "xosc"
RESOURCES = CORPUS / "resources" / "xosc"


def _worst_step_error(bench: Bench, name: str, steps: int) -> float:
    """Over ``steps`` steps, the largest difference (m/s) between the state's velocity after a
    step and the step's displacement over its duration (the motion is integrated backwards:
    a step moves by the velocity at its end)."""
    car = bench.actor(name)
    worst = 0.0
    for _ in range(steps):
        x0, y0 = car.x, car.y
        bench.step()
        vx, vy = car.state().velocity()
        worst = max(worst, math.hypot(vx - (car.x - x0) / DT, vy - (car.y - y0) / DT))
    return worst


def _lane_change(seconds: float) -> model.LaneChangeAction:
    return model.LaneChangeAction(
        dynamics=model.TransitionDynamics(
            shape=model.DynamicsShape.CUBIC, dimension=model.DynamicsDimension.TIME, value=seconds
        ),
        target=model.AbsoluteTargetLane(lane_id=-2),
    )


def test_an_entity_placed_across_its_lane_moves_along_the_lane() -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 10.0, h=math.pi / 2)))
    bench.start("Car", speed(10.0))
    assert _worst_step_error(bench, "Car", 10) < 1e-9
    car = bench.actor("Car")
    assert car.heading == pytest.approx(math.pi / 2)
    assert car.state().velocity() == pytest.approx((10.0, 0.0))


@pytest.mark.parametrize("cruise", [10.0, 1.0])
def test_a_lane_change_reports_its_lateral_motion_once(cruise: float) -> None:
    """At 1 m/s the lateral rate exceeds the speed and the heading turns right across the
    road: the velocity is still the step's motion."""
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.start("Car", speed(cruise))
    bench.start("Car", _lane_change(2.0))
    assert _worst_step_error(bench, "Car", 50) < 1e-9
    assert bench.actor("Car").lane_id == -2


def test_a_trajectory_turning_its_heading_through_a_segment_moves_along_the_segment() -> None:
    """A timed polyline with a right-angle corner: along the second segment the heading turns
    from the first segment's direction to the second's (as the reference player interpolates
    it) while the entity moves straight along the segment."""
    vertices = tuple(
        model.Vertex(position=model.WorldPosition(x=x, y=y), time=t)
        for x, y, t in ((100.0, -5.25, 0.0), (150.0, -5.25, 5.0), (150.0, 44.75, 10.0))
    )
    action = model.FollowTrajectoryAction(
        trajectory=model.Trajectory(
            name="corner", closed=False, shape=model.Polyline(vertices=vertices)
        ),
        following_mode=model.FollowingMode.POSITION,
        timing=model.Timing(domain=model.ReferenceContext.RELATIVE, scale=1.0, offset=0.0),
    )
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-2, 100.0)))
    bench.start("Car", action)
    assert _worst_step_error(bench, "Car", 150) < 1e-9
    car = bench.actor("Car")
    assert car.heading == pytest.approx(math.pi / 4)  # half-way along the second segment
    assert car.state().velocity() == pytest.approx((0.0, 10.0))


def test_a_rigid_lateral_distance_snaps_as_a_declared_jump() -> None:
    bench = Bench("Ref", "Car")
    bench.start("Ref", teleport(lane(-1, 20.0)))
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.step()
    bench.start(
        "Car",
        model.LateralDistanceAction(
            entity_ref="Ref", freespace=False, continuous=False, distance=3.5,
            displacement=model.LateralDisplacement.RIGHT,
        ),
    )  # fmt: skip
    bench.step()
    assert bench.actor("Car").lane_id == -1
    assert bench.actor("Car").offset == pytest.approx(-3.5)
    assert [(j.entity, j.cause) for j in bench.world.discontinuities] == [
        (1, JumpCause.LATERAL_STEP)
    ]


@pytest.mark.parametrize(
    "scenario",
    [
        UNITTEST / "trajectory_heading.xosc",  # vertex headings across the path
        UNITTEST / "trajectory_speed.xosc",
        UNITTEST / "trajectory_special_cases.xosc",
        RESOURCES / "follow_trajectory_by_front_axle.xosc",
        RESOURCES / "trajectory-test.xosc",  # a NURBS starting at another heading
        UNITTEST / "lat_dist_entity_basic.xosc",  # entities placed across the road
        UNITTEST / "friction_and_lane_change_edge_case.xosc",  # lane change at 1 m/s
        RESOURCES / "routing-test.xosc",  # a 90 degree junction turn at 50 m/s
    ],
    ids=lambda path: path.name,
)
def test_corpus_motion_satisfies_the_evidence_gate(scenario: Path, tmp_path: Path) -> None:
    report = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=scenario,
            nets_dir=tmp_path,
            record=False,
            backend=BackendChoice.MEMORY,
            sut=SutConfig(takeover=Takeover.NEVER),
        )
    )
    assert report.outcome.verdict is Verdict.PASSED, report.outcome.reason
