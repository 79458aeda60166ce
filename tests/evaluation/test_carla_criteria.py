"""ScenarioRunner criteria in the evaluator and the verdict: DrivenDistanceTest with success and
acceptable distances and without a usable argument, lane, red light and stop criteria without a
road network not evaluated, a failed criterion outranking a timeout, outcomes in the
reason and as ``criteria.*`` metrics, no criteria -> unchanged reason."""

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


def test_driven_distance_success_acceptable_and_failure() -> None:
    args = (("distance_success", "100"), ("distance_acceptable", "60"))
    for metres, status, detail in (
        (120.0, Status.PASSED, "120.0 m >= 100 m"),
        (80.0, Status.PASSED, "80.0 m >= acceptable 60 m"),
        (40.0, Status.FAILED, "40.0 m < 100 m"),
    ):
        evaluator = drive(
            ScenarioCriteria([criterion("DrivenDistanceTest", *args)], roads=None), metres
        )
        (outcome,) = evaluator.criterion_outcomes()
        assert (outcome.status, outcome.detail) == (status, detail)


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
        "no numeric distance_success given",
        "no road network",
    ]
    result = judge(drive(checks, 50.0), facts())
    assert result.verdict is Verdict.PASSED
    assert not any(key.startswith("criteria.") for key in result.metrics)
    assert "HoverTest not evaluated (unknown criterion)" in result.reason


def test_failed_criterion_outranks_timeout_and_is_a_metric() -> None:
    checks = ScenarioCriteria(
        [criterion("CollisionTest"), criterion("DrivenDistanceTest", ("distance_success", "100"))],
        roads=None,
    )
    result = judge(drive(checks, 30.0), facts(complete=False))
    assert result.verdict is Verdict.FAILED
    assert result.reason.startswith("criteria_DrivenDistanceTest failed: 30.0 m < 100 m; ")
    assert result.reason.endswith(
        "ScenarioRunner criteria: CollisionTest passed, DrivenDistanceTest failed (30.0 m < 100 m)"
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
