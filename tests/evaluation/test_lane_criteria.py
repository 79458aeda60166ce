"""ScenarioRunner's lane and road criteria on a straight avenue (lanes 1, -1, -2 driving, 2 and -3
sidewalks): KeepLaneTest only on a corner crossing a lane border (not for a car that starts
astride one), WrongLaneTest only on a change into a lane running the other way (not for a car
that starts against the traffic), OnSidewalkTest and OffRoadTest by time spent (a single tick
starts the clock), counting off-road as outside the lanes, with their ``duration``;
EndofRoadTest after leaving the start road for ``duration`` seconds; an optional KeepLaneTest."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

from simtest_operator.evaluation import Criteria, OnlineEvaluator, RunFacts, ScenarioCriteria, judge
from simtest_operator.evaluation.carla_criteria import Status
from simtest_operator.opendrive import RoadNetwork
from simtest_operator.openscenario import model
from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState, WorldSnapshot
from simtest_operator.verdicts import Verdict

AVENUE = RoadNetwork.from_file(Path(__file__).parents[1] / "sim" / "carla" / "avenue.xodr")
BOX = BoundingBox(center_x=1.5, length=4.0, width=2.0)

TWO_ROADS = b"""<?xml version="1.0"?>
<OpenDRIVE><header revMajor="1" revMinor="4" name="two"/>
  <road name="a" length="100" id="1" junction="-1">
    <link><successor elementType="road" elementId="2" contactPoint="start"/></link>
    <planView><geometry s="0" x="0" y="0" hdg="0" length="100"><line/></geometry></planView>
    <lanes><laneSection s="0"><center><lane id="0" type="driving" level="false"/></center>
      <right><lane id="-1" type="driving" level="false">
        <width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane></right>
    </laneSection></lanes>
  </road>
  <road name="b" length="100" id="2" junction="-1">
    <link><predecessor elementType="road" elementId="1" contactPoint="end"/></link>
    <planView><geometry s="0" x="100" y="0" hdg="0" length="100"><line/></geometry></planView>
    <lanes><laneSection s="0"><center><lane id="0" type="driving" level="false"/></center>
      <right><lane id="-1" type="driving" level="false">
        <width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane></right>
    </laneSection></lanes>
  </road>
</OpenDRIVE>
"""

Pose = tuple[float, float, float]
"""x, y, heading of the car's reference point (rear axle; the box centre is 1.5 m ahead)."""


def criterion(test: str, value: str | None = None) -> model.Criterion:
    arguments = (("arg", value),) if value is not None else ()
    return model.Criterion(test=test, known=True, arguments=arguments)


def drive(
    poses: Sequence[Pose],
    *criteria: model.Criterion,
    roads: RoadNetwork = AVENUE,
    step: float = 0.5,
) -> OnlineEvaluator:
    checks = ScenarioCriteria(criteria, roads=roads)
    evaluator = OnlineEvaluator(Criteria(), ego="hero", scenario_criteria=checks)
    for k, (x, y, heading) in enumerate(poses):
        hero = EntityState(
            id=0,
            name="hero",
            kind=EntityKind.VEHICLE,
            category="car",
            x=x,
            y=y,
            heading=heading,
            speed=8.0,
            box=BOX,
        )
        evaluator.observe(WorldSnapshot(time=k * step, entities=(hero,)))
    return evaluator


def straight(y: float, *, ticks: int = 8, heading: float = 0.0) -> list[Pose]:
    return [(20.0 + 4.0 * k, y, heading) for k in range(ticks)]


def status(evaluator: OnlineEvaluator) -> list[Status]:
    return [o.status for o in evaluator.criterion_outcomes()]


def test_keep_lane_fails_on_a_crossing_not_on_a_start_astride() -> None:
    # Astride the -1/-2 border from the start (1.4 m right of lane -1's centre): no corner
    # crosses a border, so CARLA's lane-invasion sensor never fires.
    assert status(drive(straight(-1.75 - 1.4), criterion("KeepLaneTest"))) == [Status.PASSED]
    change = [(20.0 + 4.0 * k, -1.75 - 0.5 * k, 0.0) for k in range(8)]
    (outcome,) = drive(change, criterion("KeepLaneTest")).criterion_outcomes()
    assert outcome.status is Status.FAILED
    assert outcome.detail.startswith("hero crossed from lane -1 into lane -2 of road 1 at t=")


def test_an_optional_keep_lane_failure_keeps_the_run_passed() -> None:
    change = [(20.0 + 4.0 * k, -1.75 - 0.5 * k, 0.0) for k in range(8)]
    evaluator = drive(change, criterion("KeepLaneTest", "1"))
    (outcome,) = evaluator.criterion_outcomes()
    assert outcome.status is Status.FAILED and outcome.optional
    facts = RunFacts(simulated_seconds=4.0, wall_seconds=0.1, storyboard_complete=True)
    result = judge(evaluator, facts)
    assert result.verdict is Verdict.PASSED
    assert "KeepLaneTest failed (" in result.reason and "; optional)" in result.reason


def test_wrong_lane_fails_on_a_change_against_the_traffic_only() -> None:
    # Starting in lane 1 against its traffic is no lane change: ScenarioRunner stays silent.
    assert status(drive(straight(1.75), criterion("WrongLaneTest"))) == [Status.PASSED]
    # A change into the right-hand lane of the same direction is fine.
    right = [(20.0 + 4.0 * k, -1.75 - 0.5 * k, 0.0) for k in range(8)]
    assert status(drive(right, criterion("WrongLaneTest"))) == [Status.PASSED]
    # Across the centre line into lane 1: its direction is 180 deg from lane -1's.
    across = [(20.0 + 4.0 * k, -1.75 + 0.5 * k, 0.0) for k in range(8)]
    (outcome,) = drive(across, criterion("WrongLaneTest")).criterion_outcomes()
    assert outcome.status is Status.FAILED
    assert outcome.detail.startswith("hero entered lane 1 of road 1 against its traffic at t=")


def test_on_sidewalk_counts_time_on_the_sidewalk_and_off_the_road() -> None:
    sidewalk = -8.0
    one_tick = [(20.0, -1.75, 0.0), (24.0, sidewalk, 0.0), (28.0, -1.75, 0.0)]
    assert status(drive(one_tick, criterion("OnSidewalkTest"))) == [Status.PASSED]
    (outcome,) = drive(straight(sidewalk), criterion("OnSidewalkTest")).criterion_outcomes()
    assert outcome.status is Status.FAILED
    assert outcome.detail == "hero on a sidewalk for 0.50 s > 0 s at t=0.50 s"
    # Off the road altogether is "outside the lanes" for ScenarioRunner's OnSidewalkTest.
    (outcome,) = drive(straight(-14.0), criterion("OnSidewalkTest")).criterion_outcomes()
    assert outcome.detail.startswith("hero outside the lanes for 0.50 s")
    # The value is the duration: 3.5 s on the sidewalk is within 5 s.
    assert status(drive(straight(sidewalk), criterion("OnSidewalkTest", "5"))) == [Status.PASSED]


def test_off_road_is_time_off_the_driving_and_parking_lanes() -> None:
    assert status(drive(straight(-5.0), criterion("OffRoadTest"))) == [Status.PASSED]
    (outcome,) = drive(straight(-8.0), criterion("OffRoadTest")).criterion_outcomes()
    assert outcome.status is Status.FAILED
    assert outcome.detail == "hero off the road for 0.50 s > 0 s at t=0.50 s"
    assert status(drive(straight(-8.0), criterion("OffRoadTest", "3.5"))) == [Status.PASSED]


def test_end_of_road_fails_duration_seconds_after_leaving_the_start_road() -> None:
    roads = RoadNetwork.from_bytes(TWO_ROADS)
    poses = [(81.0 + 5.0 * k, -1.75, 0.0) for k in range(10)]  # on road 2 from t=2 s (x=101)
    (outcome,) = drive(poses, criterion("EndofRoadTest"), roads=roads).criterion_outcomes()
    assert outcome.status is Status.FAILED
    assert outcome.detail == "hero left road 1 at t=2.00 s at t=2.50 s"
    late = drive(poses, criterion("EndofRoadTest", "5"), roads=roads)
    assert status(late) == [Status.PASSED]
    assert status(drive(poses[:4], criterion("EndofRoadTest"), roads=roads)) == [Status.PASSED]


def test_a_car_turning_round_is_judged_on_lanes_not_heading() -> None:
    # U-turn in place inside lane -1 (heading flips, lane unchanged): no lane change, no failure.
    turn = [(30.0, -1.75, math.pi * k / 7) for k in range(8)]
    assert status(drive(turn, criterion("WrongLaneTest"))) == [Status.PASSED]
