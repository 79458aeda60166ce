"""The simulation declares the jumps the scenario commands, dated by the snapshot that first
shows them, so the evidence checks excuse exactly those: a teleport of a placed entity (not its
first pose), a trajectory that starts away from the entity, a lane change or offset of step
shape, the stop at a road's end, and an entity deleted and added again. Motion that is
continuous (a lane change over time, a trajectory starting where the entity is) declares
nothing."""

from __future__ import annotations

from simtest_operator.openscenario import model
from simtest_operator.snapshots import JumpCause
from tests.sim.worlds import DT, Bench, lane, speed, teleport


def _declared(bench: Bench) -> list[tuple[float, int, JumpCause]]:
    return [(round(j.time, 9), j.entity, j.cause) for j in bench.world.discontinuities]


def _at(steps: int) -> float:
    """The time of the snapshot after ``steps`` steps."""
    return round(steps * DT, 9)


def _lane_change(
    shape: model.DynamicsShape, seconds: float, lane_id: int
) -> model.LaneChangeAction:
    return model.LaneChangeAction(
        dynamics=model.TransitionDynamics(
            shape=shape, dimension=model.DynamicsDimension.TIME, value=seconds
        ),
        target=model.AbsoluteTargetLane(lane_id=lane_id),
    )


def _trajectory(dx: float) -> model.FollowTrajectoryAction:
    start = model.RelativeObjectPosition(
        entity_ref="Car", dx=dx, dy=0.0,
        orientation=model.Orientation(type=model.ReferenceContext.RELATIVE, h=0.0),
    )  # fmt: skip
    shape = model.Clothoid(curvature=0.0, curvature_prime=0.0, length=50.0, position=start)
    return model.FollowTrajectoryAction(
        trajectory=model.Trajectory(name="t", closed=False, shape=shape),
        following_mode=model.FollowingMode.POSITION,
    )


def test_a_teleport_of_a_placed_entity_is_declared_its_first_pose_is_not() -> None:
    bench = Bench("Other", "Car")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.step(4)
    assert _declared(bench) == []
    bench.start("Car", teleport(lane(-1, 200.0)))
    bench.step()
    assert _declared(bench) == [(_at(5), 1, JumpCause.TELEPORT)]


def test_a_step_lane_change_is_declared_a_timed_one_is_not() -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.start("Car", speed(10.0))
    bench.start("Car", _lane_change(model.DynamicsShape.CUBIC, 2.0, -2))
    bench.step(50)
    assert _declared(bench) == []
    bench.start("Car", _lane_change(model.DynamicsShape.STEP, 0.0, -2))  # there already
    bench.step()
    assert _declared(bench) == []
    bench.start("Car", _lane_change(model.DynamicsShape.STEP, 0.0, -1))
    bench.step()
    assert _declared(bench) == [(_at(52), 0, JumpCause.LATERAL_STEP)]


def test_a_trajectory_starting_away_from_the_entity_is_declared() -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.start("Car", _trajectory(0.0))
    bench.step()
    assert _declared(bench) == []
    bench.start("Car", _trajectory(30.0))
    bench.step()
    assert _declared(bench) == [(_at(2), 0, JumpCause.TRAJECTORY_START)]


def test_the_stop_at_the_end_of_the_road_is_declared_once() -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 990.0)))
    bench.start("Car", speed(20.0))  # at the end (s = 1000) in step 11
    bench.step(15)
    assert bench.actor("Car").stuck
    assert _declared(bench) == [(_at(11), 0, JumpCause.ROAD_END)]


def test_an_entity_deleted_and_added_again_is_declared_both_times() -> None:
    bench = Bench("Car")
    bench.start("Car", teleport(lane(-1, 10.0)))
    bench.step(2)
    bench.dispatcher.start_global(model.DeleteEntityAction(entity_ref="Car"))
    bench.step(2)
    bench.dispatcher.start_global(model.AddEntityAction(entity_ref="Car", position=lane(-1, 500.0)))
    bench.step()
    assert _declared(bench) == [
        (_at(3), 0, JumpCause.DELETED),
        (_at(5), 0, JumpCause.ADDED),
    ]
