"""ScenarioRunner criteria in the evaluator and the verdict: the value as the test's second
argument whatever its parameterRef (a distance, a speed, ``optional``), strict comparisons and
last-tick MaxVelocityTest, criteria ScenarioRunner cannot build not evaluated, optional failures
not failing the run, a collision taken standing not the ego's, a failed criterion outranking a
timeout, outcomes in the reason and as ``criteria.*`` metrics, no criteria -> unchanged reason."""

from __future__ import annotations

from simtest_operator.evaluation import (
    Criteria,
    OnlineEvaluator,
    RunFacts,
    ScenarioCriteria,
    Status,
    judge,
)
from simtest_operator.openscenario import model
from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState, WorldSnapshot
from simtest_operator.verdicts import Verdict

BOX = BoundingBox(center_x=1.5, length=4.0, width=2.0)


def car(name: str, x: float) -> EntityState:
    return EntityState(
        id=0, name=name, kind=EntityKind.VEHICLE, category="car", x=x, y=0.0, speed=10.0, box=BOX
    )


def criterion(test: str, *arguments: tuple[str, str], known: bool = True) -> model.Criterion:
    return model.Criterion(test=test, known=known, arguments=arguments)


def drive(checks: ScenarioCriteria, metres: float) -> OnlineEvaluator:
    evaluator = OnlineEvaluator(Criteria(), ego="hero", scenario_criteria=checks)
    for step in range(11):
        x = metres * step / 10
        evaluator.observe(WorldSnapshot(time=step * 0.5, entities=(car("hero", x),)))
    return evaluator


def facts(complete: bool = True) -> RunFacts:
    return RunFacts(simulated_seconds=5.0, wall_seconds=0.1, storyboard_complete=complete)


def test_driven_distance_takes_the_value_whatever_its_parameter_ref_and_is_strict() -> None:
    # ScenarioRunner calls DrivenDistanceTest(ego, value): the value is the distance even when
    # parameterRef names "distance_acceptable", and only more than it succeeds.
    for ref, metres, status, detail in (
        ("distance_success", 120.0, Status.PASSED, "120.0 m > 100 m"),
        ("distance_acceptable", 80.0, Status.FAILED, "80.0 m <= 100 m"),
        ("anything", 100.0, Status.FAILED, "100.0 m <= 100 m"),
    ):
        checks = ScenarioCriteria([criterion("DrivenDistanceTest", (ref, "100"))], roads=None)
        (outcome,) = drive(checks, metres).criterion_outcomes()
        assert (outcome.status, outcome.detail) == (status, detail)


def test_velocity_criteria_are_judged_at_the_last_tick() -> None:
    # 50 m in 5 s: average 10 m/s, and the last tick drives at 10 m/s (car() speed).
    checks = ScenarioCriteria(
        [
            criterion("MaxVelocityTest", ("max_velocity", "12")),
            criterion("MaxVelocityTest", ("max_velocity", "9")),
            criterion("AverageVelocityTest", ("avg_velocity_success", "9")),
            criterion("AverageVelocityTest", ("avg_velocity_success", "10")),
        ],
        roads=None,
    )
    outcomes = drive(checks, 50.0).criterion_outcomes()
    assert [o.status for o in outcomes] == [
        Status.PASSED,
        Status.FAILED,
        Status.PASSED,
        Status.FAILED,
    ]
    assert outcomes[1].detail == "10.00 m/s at the end > 9 m/s"
    assert outcomes[3].detail == "average 10.00 m/s <= 10 m/s"


def test_infinite_and_nan_values_build_as_scenario_runner_reads_them() -> None:
    # float("inf") and float("nan") are numbers to ScenarioRunner: the tests build (no refusal)
    # and compare as its code does: distance > inf never holds; speed > nan neither, so
    # MaxVelocityTest passes and AverageVelocityTest (avg > nan) fails.
    checks = ScenarioCriteria(
        [
            criterion("DrivenDistanceTest", ("distance_success", "inf")),
            criterion("MaxVelocityTest", ("max_velocity", "nan")),
            criterion("AverageVelocityTest", ("avg_velocity_success", "nan")),
        ],
        roads=None,
    )
    assert checks.refusal is None
    outcomes = drive(checks, 50.0).criterion_outcomes()
    assert [o.status for o in outcomes] == [Status.FAILED, Status.PASSED, Status.FAILED]


def test_a_max_velocity_exceeded_before_the_end_passes() -> None:
    # ScenarioRunner overwrites MaxVelocityTest's status at every tick: only the last one counts.
    checks = ScenarioCriteria([criterion("MaxVelocityTest", ("max_velocity", "5"))], roads=None)
    evaluator = OnlineEvaluator(Criteria(), ego="hero", scenario_criteria=checks)
    fast = car("hero", 0.0)
    slow = EntityState(
        id=0, name="hero", kind=EntityKind.VEHICLE, category="car", x=5.0, y=0.0, speed=2.0, box=BOX
    )
    evaluator.observe(WorldSnapshot(time=0.0, entities=(fast,)))
    evaluator.observe(WorldSnapshot(time=1.0, entities=(slow,)))
    (outcome,) = evaluator.criterion_outcomes()
    assert outcome.status is Status.PASSED


def test_criteria_scenario_runner_cannot_build_are_not_evaluated() -> None:
    checks = ScenarioCriteria(
        [
            criterion("DrivenDistanceTest", ("distance_success", "far")),
            criterion("DrivenDistanceTest"),
            criterion("MaxVelocityTest"),
            criterion("CollisionTest", ("other", "3")),
        ],
        roads=None,
    )
    outcomes = drive(checks, 50.0).criterion_outcomes()
    assert [o.status for o in outcomes] == [Status.NOT_EVALUATED] * 4
    assert [o.detail for o in outcomes] == [
        "value 'far' is not a number",
        "ScenarioRunner needs a value (distance)",
        "ScenarioRunner needs a value (max_velocity)",
        "ScenarioRunner reads a non-zero value as the other actor",
    ]
    # float('far') and DrivenDistanceTest(ego) raise while ScenarioRunner builds its criteria:
    # it refuses the file ("The scenario cannot be loaded"); CollisionTest(ego, 3.0) builds.
    assert checks.refusal == (
        "ScenarioRunner cannot load the file: criteria_DrivenDistanceTest: "
        "value 'far' is not a number"
    )
    collision_only = ScenarioCriteria([criterion("CollisionTest", ("other", "3"))], roads=None)
    assert collision_only.refusal is None


def test_a_non_zero_value_makes_keep_lane_and_wrong_lane_optional() -> None:
    # KeepLaneTest(ego, value): the value lands in ``optional``; an optional failure is reported
    # but does not fail the run (ScenarioManager.analyze_scenario skips optional criteria).
    checks = ScenarioCriteria(
        [criterion("CollisionTest"), criterion("KeepLaneTest", ("optional", "1"))], roads=None
    )
    evaluator = OnlineEvaluator(Criteria(collision=False), ego="hero", scenario_criteria=checks)
    evaluator.observe(WorldSnapshot(time=1.0, entities=(car("hero", 0.0),)))
    (collision, keep) = evaluator.criterion_outcomes()
    assert keep.optional and not collision.optional
    assert keep.describe() == "KeepLaneTest not evaluated (no road network; optional)"


def test_an_optional_failure_does_not_fail_the_run() -> None:
    from simtest_operator.evaluation.carla_criteria import Outcome

    optional = Outcome(name="KeepLaneTest", status=Status.FAILED, detail="x", optional=True)
    required = Outcome(name="KeepLaneTest", status=Status.FAILED, detail="x")
    assert not optional.decisive
    assert required.decisive


def test_unusable_or_unknown_criteria_are_not_evaluated() -> None:
    checks = ScenarioCriteria(
        [
            criterion("DrivenDistanceTest", ("distance_success", "far")),
            criterion("KeepLaneTest"),
            criterion("RunningRedLightTest"),
            criterion("RunningStopTest"),
            criterion("HoverTest", known=False),
        ],
        roads=None,
    )
    outcomes = drive(checks, 50.0).criterion_outcomes()
    assert [o.status for o in outcomes] == [Status.NOT_EVALUATED] * 5
    assert [o.detail for o in outcomes][:2] == [
        "value 'far' is not a number",
        "no road network",
    ]
    assert outcomes[-1].describe() == "HoverTest not evaluated (ScenarioRunner has no such test)"
    result = judge(drive(checks, 50.0), facts())
    assert not any(key.startswith("criteria.") for key in result.metrics)
    assert checks.refusal is not None and "criteria_DrivenDistanceTest" in checks.refusal
    only_unknown = ScenarioCriteria([criterion("HoverTest", known=False)], roads=None)
    assert only_unknown.refusal == (
        "ScenarioRunner cannot load the file: criteria_HoverTest: ScenarioRunner has no such test"
    )


def test_failed_criterion_outranks_timeout_and_is_a_metric() -> None:
    checks = ScenarioCriteria(
        [criterion("CollisionTest"), criterion("DrivenDistanceTest", ("distance_success", "100"))],
        roads=None,
    )
    result = judge(drive(checks, 30.0), facts(complete=False))
    assert result.verdict is Verdict.FAILED
    assert result.reason.startswith("criteria_DrivenDistanceTest failed: 30.0 m <= 100 m; ")
    assert result.reason.endswith(
        "ScenarioRunner criteria: CollisionTest passed, DrivenDistanceTest failed (30.0 m <= 100 m)"
    )
    assert result.metrics["criteria.CollisionTest"] == 1.0
    assert result.metrics["criteria.DrivenDistanceTest"] == 0.0
    assert result.metrics["drivenDistance"] == 30.0


def test_collision_test_names_the_other_entity() -> None:
    checks = ScenarioCriteria([criterion("CollisionTest")], roads=None)
    evaluator = OnlineEvaluator(Criteria(collision=False), ego="hero", scenario_criteria=checks)
    evaluator.observe(WorldSnapshot(time=1.0, entities=(car("hero", 0.0), car("lead", 3.0))))
    result = judge(evaluator, facts())
    # The campaign does not judge collisions here; the scenario's own test still does.
    assert result.verdict is Verdict.FAILED
    assert result.reason.startswith(
        "criteria_CollisionTest failed: hero collided with lead at t=1.00 s"
    )


def test_without_criteria_the_reason_is_unchanged() -> None:
    evaluator = OnlineEvaluator(Criteria(), ego="hero")
    evaluator.observe(WorldSnapshot(time=0.0, entities=(car("hero", 0.0),)))
    assert judge(evaluator, facts()).reason == "storyboard complete at t=5.00 s, all criteria held"


def test_a_collision_taken_standing_still_is_not_the_egos() -> None:
    # CollisionTest skips collisions while the ego is slower than 0.1 m/s (its EPSILON).
    checks = ScenarioCriteria([criterion("CollisionTest")], roads=None)
    evaluator = OnlineEvaluator(Criteria(collision=False), ego="hero", scenario_criteria=checks)
    standing = EntityState(
        id=0, name="hero", kind=EntityKind.VEHICLE, category="car", x=0.0, y=0.0, box=BOX
    )
    evaluator.observe(WorldSnapshot(time=1.0, entities=(standing, car("rear", -3.0))))
    (outcome,) = evaluator.criterion_outcomes()
    assert outcome.status is Status.PASSED
    assert outcome.detail == "hit by rear while standing (not the ego's fault)"
    assert judge(evaluator, facts()).verdict is Verdict.PASSED
