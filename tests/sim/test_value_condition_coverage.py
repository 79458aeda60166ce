"""TimeOfDayCondition against the environment's TimeOfDay (animated with simulation time or
standing still, each rule, with a zone offset, no time of day at all), and the user-defined
elements a tool of the user's would run: ``UserDefinedAction`` (Init and story) and
``UserDefinedValueCondition`` are accepted, do nothing and are listed as ignored."""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import load_scenario, model
from simtest_operator.verdicts import Verdict
from tests.sim import osc_scenarios as osc

NOON = "2026-06-01T12:00:00"


def _environment(*, animation: bool, date_time: str = NOON) -> str:
    return (
        '<GlobalAction><EnvironmentAction><Environment name="day">'
        f'<TimeOfDay animation="{str(animation).lower()}" dateTime="{date_time}"/>'
        "</Environment></EnvironmentAction></GlobalAction>"
    )


def _stop_on(condition: str, *, fallback: float = 5.0) -> str:
    """A stop trigger: ``condition`` or, in another group, ``fallback`` seconds."""
    return (
        f"<StopTrigger><ConditionGroup>{condition}</ConditionGroup><ConditionGroup>"
        + osc.at_time(fallback, name="fallback")
        + "</ConditionGroup></StopTrigger>"
    )


def _run(tmp_path: Path, *, environment: str, condition: str) -> float:
    text = osc.scenario(
        entities=osc.CAR.format(name="Ego"), init=osc.place("Ego"), environment=environment
    ).replace("</Storyboard>", _stop_on(condition) + "</Storyboard>")
    report = osc.run(osc.write(tmp_path, text), tmp_path)
    assert report.outcome.verdict is Verdict.PASSED, report.outcome.reason
    return report.outcome.simulated_seconds


def _time_of_day(date_time: str, rule: str) -> str:
    return osc.by_value(
        f'<TimeOfDayCondition dateTime="{date_time}" rule="{rule}"/>', name="tod", edge="none"
    )


def test_an_animated_time_of_day_runs_with_simulation_time(tmp_path: Path) -> None:
    ended = _run(
        tmp_path,
        environment=_environment(animation=True),
        condition=_time_of_day("2026-06-01T12:00:03", "greaterThan"),
    )
    assert 3.0 < ended < 3.2


def test_a_still_time_of_day_stands(tmp_path: Path) -> None:
    ended = _run(
        tmp_path,
        environment=_environment(animation=False),
        condition=_time_of_day("2026-06-01T12:00:03", "greaterThan"),
    )
    assert ended > 5.0  # only the fallback stopped it


@pytest.mark.parametrize(
    ("date_time", "rule"),
    [
        ("2026-06-01T11:59:59", "greaterThan"),
        (NOON, "equalTo"),
        (NOON, "lessOrEqual"),
        ("2026-06-01T13:00:00", "lessThan"),
        ("2026-06-01T14:00:00+02:00", "equalTo"),  # 12:00 UTC
    ],
)
def test_rules_compare_the_time_of_day(tmp_path: Path, date_time: str, rule: str) -> None:
    ended = _run(
        tmp_path,
        environment=_environment(animation=False),
        condition=_time_of_day(date_time, rule),
    )
    assert ended < 0.2


def test_without_a_time_of_day_the_condition_is_false(tmp_path: Path) -> None:
    ended = _run(tmp_path, environment="", condition=_time_of_day(NOON, "greaterOrEqual"))
    assert ended > 5.0


def test_a_date_time_that_is_not_iso_is_refused(tmp_path: Path) -> None:
    text = osc.scenario(
        entities=osc.CAR.format(name="Ego"),
        init=osc.place("Ego"),
        stop=_time_of_day("noon", "greaterThan"),
    )
    with pytest.raises(ScenarioError, match="not an ISO 8601"):
        load_scenario(osc.write(tmp_path, text))


def test_user_defined_elements_are_ignored_and_listed(tmp_path: Path) -> None:
    command = (
        '<UserDefinedAction><CustomCommandAction type="honk">twice</CustomCommandAction>'
        "</UserDefinedAction>"
    )
    text = osc.scenario(
        entities=osc.CAR.format(name="Ego"),
        init=command + osc.place("Ego"),
        stories=osc.story('<EntityRef entityRef="Ego"/>', command, osc.at_time(1.0)),
    ).replace(
        "</Storyboard>",
        _stop_on(
            osc.by_value('<UserDefinedValueCondition name="radar" value="1" rule="equalTo"/>'),
            fallback=2.0,
        )
        + "</Storyboard>",
    )
    path = osc.write(tmp_path, text)
    scenario = load_scenario(path)
    assert not scenario.unsupported()
    story_action = scenario.storyboard.stories[0].acts[0].maneuver_groups[0].maneuvers[0]
    assert isinstance(story_action.events[0].actions[0].body, model.IgnoredAction)
    report = osc.run(path, tmp_path)
    assert report.outcome.verdict is Verdict.PASSED, report.outcome.reason
    assert 2.0 < report.outcome.simulated_seconds < 2.2  # the user value never became true
    assert {"UserDefinedAction (honk)", "UserDefinedValueCondition"} <= set(
        report.outcome.ignored_elements
    )
