"""OpenSCENARIO 1.3 monitors: declared with an initial value, set by SetMonitorAction, reported
as ``monitor.<name>`` metrics; one still false at the end fails the run with a reason naming it;
setting an undeclared monitor, or declaring one twice, is refused."""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import load_scenario, model
from simtest_operator.verdicts import Verdict
from tests.sim import osc_scenarios as osc

DECLARED = (
    '<MonitorDeclarations><MonitorDeclaration name="reached" value="false"/>'
    '<MonitorDeclaration name="calm" value="true"/></MonitorDeclarations>'
)


def _text(*, monitor: str = "reached", value: str = "true", declarations: str = DECLARED) -> str:
    action = (
        f'<GlobalAction><SetMonitorAction monitorRef="{monitor}" value="{value}"/></GlobalAction>'
    )
    return osc.scenario(
        entities=osc.CAR.format(name="Ego"),
        init=osc.place("Ego"),
        stories=osc.story('<EntityRef entityRef="Ego"/>', action, osc.at_time(1.0)),
        stop=osc.at_time(2.0, name="end"),
        declarations=declarations,
    )


def test_declarations_and_actions_are_read(tmp_path: Path) -> None:
    scenario = load_scenario(osc.write(tmp_path, _text()))
    assert [(m.name, m.value) for m in scenario.monitors] == [("reached", False), ("calm", True)]
    group = scenario.storyboard.stories[0].acts[0].maneuver_groups[0]
    body = group.maneuvers[0].events[0].actions[0].body
    assert isinstance(body, model.SetMonitorAction)
    assert (body.monitor_ref, body.value) == ("reached", True)
    assert not scenario.unsupported()


def test_monitors_set_true_pass_and_are_reported(tmp_path: Path) -> None:
    outcome = osc.run(osc.write(tmp_path, _text()), tmp_path).outcome
    assert outcome.verdict is Verdict.PASSED, outcome.reason
    assert outcome.metrics["monitor.reached"] == 1.0
    assert outcome.metrics["monitor.calm"] == 1.0


def test_a_monitor_false_at_the_end_fails_the_run(tmp_path: Path) -> None:
    outcome = osc.run(osc.write(tmp_path, _text(monitor="calm", value="false")), tmp_path).outcome
    assert outcome.verdict is Verdict.FAILED
    # In declaration order: both are false at the end.
    assert (
        outcome.reason == "monitor reached is false at the end (t=2.05 s) (+1 more: monitor.calm)"
    )
    assert outcome.metrics["monitor.calm"] == 0.0
    assert outcome.metrics["monitor.reached"] == 0.0


def test_setting_an_undeclared_monitor_is_invalid(tmp_path: Path) -> None:
    outcome = osc.run(osc.write(tmp_path, _text(monitor="nobody")), tmp_path).outcome
    assert outcome.verdict is Verdict.INVALID
    assert "monitor 'nobody' is not declared" in outcome.reason


def test_a_monitor_declared_twice_is_refused(tmp_path: Path) -> None:
    twice = (
        '<MonitorDeclarations><MonitorDeclaration name="m" value="false"/>'
        '<MonitorDeclaration name="m" value="true"/></MonitorDeclarations>'
    )
    with pytest.raises(ScenarioError, match="declared twice"):
        load_scenario(osc.write(tmp_path, _text(declarations=twice)))
