"""Online evaluation: collision (ego and bystanders), TTC/THW/distance/decel metrics, threshold
violations with time stamps, off-road callable, verdict precedence (Invalid > Error > Failed >
Timeout > Passed), metric completeness, and criteria overrides (valid and rejected)."""

from __future__ import annotations

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.evaluation import Criteria, OnlineEvaluator, RunFacts, judge
from simtest_operator.snapshots import BoundingBox, EntityKind, EntityState, WorldSnapshot
from simtest_operator.verdicts import Verdict

BOX = BoundingBox(center_x=1.5, length=4.0, width=2.0)


def car(name: str, x: float, y: float = 0.0, speed: float = 0.0, acc: float = 0.0) -> EntityState:
    return EntityState(
        id=0, name=name, kind=EntityKind.VEHICLE, category="car", x=x, y=y, speed=speed,
        acceleration=acc, box=BOX,
    )  # fmt: skip


def facts(**kw: object) -> RunFacts:
    base: dict[str, object] = {
        "simulated_seconds": 10.0, "wall_seconds": 0.1, "storyboard_complete": True,
    }  # fmt: skip
    base.update(kw)
    return RunFacts(**base)  # type: ignore[arg-type]


def test_clean_following_passes_with_metrics() -> None:
    ev = OnlineEvaluator(Criteria(), ego="Ego")
    ev.observe(
        WorldSnapshot(time=0.0, entities=(car("Ego", 0, speed=20.0), car("L", 44, speed=20.0)))
    )
    ev.observe(
        WorldSnapshot(
            time=0.1, entities=(car("Ego", 2, speed=19, acc=-3.0), car("L", 46, speed=18))
        )
    )
    result = judge(ev, facts())
    assert result.verdict is Verdict.PASSED
    assert result.metrics["minDistance"] == pytest.approx(40.0)
    assert result.metrics["minTHW"] == pytest.approx(40.0 / 20.0)
    assert result.metrics["minTTC"] == pytest.approx(40.0 / 1.0)
    assert result.metrics["maxDecel"] == pytest.approx(3.0)
    assert result.metrics["realTimeFactor"] == pytest.approx(100.0)
    assert result.metrics["ignoredElements"] == 0.0


def test_ego_collision_fails_and_bystander_collision_is_only_listed() -> None:
    ev = OnlineEvaluator(Criteria(), ego="Ego")
    ev.observe(WorldSnapshot(time=1.0, entities=(car("Ego", 0), car("A", 50), car("B", 52))))
    assert judge(ev, facts()).verdict is Verdict.PASSED
    ev.observe(WorldSnapshot(time=2.0, entities=(car("Ego", 0), car("A", 3), car("B", 52))))
    result = judge(ev, facts())
    assert result.verdict is Verdict.FAILED
    assert result.reason == "Ego collided with A at t=2.00 s"
    assert [(c.first, c.second, c.time) for c in ev.collisions] == [
        ("A", "B", 1.0),
        ("Ego", "A", 2.0),
    ]


def test_thresholds_and_off_road() -> None:
    criteria = Criteria(min_ttc=3.0, max_decel=5.0)
    ev = OnlineEvaluator(criteria, ego="Ego", off_road=lambda s: s.y > 10)
    ev.observe(WorldSnapshot(time=0.5, entities=(car("Ego", 0, speed=20), car("L", 24, speed=10))))
    ev.observe(WorldSnapshot(time=0.6, entities=(car("Ego", 0, y=11, acc=-8.0),)))
    assert [v.criterion for v in ev.violations] == ["minTTC", "maxDecel", "offRoad"]
    result = judge(ev, facts())
    assert result.verdict is Verdict.FAILED
    assert result.reason.startswith("time to collision 2.00 s < 3 s at t=0.50 s (+2 more")


def test_verdict_precedence() -> None:
    ev = OnlineEvaluator(Criteria(), ego="Ego")
    ev.observe(WorldSnapshot(time=0.0, entities=(car("Ego", 0), car("A", 1))))
    assert judge(ev, facts(invalid_reason="x")).verdict is Verdict.INVALID
    assert judge(ev, facts(error_reason="y")).verdict is Verdict.ERROR
    assert judge(ev, facts(storyboard_complete=False)).verdict is Verdict.FAILED
    clean = OnlineEvaluator(Criteria(), ego="Ego")
    assert judge(clean, facts(storyboard_complete=False)).verdict is Verdict.TIMEOUT
    assert judge(clean, facts(wall_limit_hit=True)).reason.startswith("wall-clock limit")


def test_overrides() -> None:
    c = Criteria().with_overrides({"minTTC": 1.5, "collision": False, "timeLimit": 20})
    assert (c.min_ttc, c.collision, c.time_limit) == (1.5, False, 20.0)
    with pytest.raises(ScenarioError, match="unknown criterion"):
        Criteria().with_overrides({"minTtc": 1})
    with pytest.raises(ScenarioError, match="non-negative"):
        Criteria().with_overrides({"maxDecel": -1})
