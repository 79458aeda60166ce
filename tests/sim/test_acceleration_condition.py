"""AccelerationCondition reads the acceleration as esmini measures it: the world-frame change of
velocity over the last step; without a direction its magnitude (a car braking at 8 m/s^2 reads
+8), with ``longitudinal``/``lateral`` its signed component along/left of the heading."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from simtest_operator.runner import scenario_execution
from simtest_operator.sim import BackendChoice, SutConfig, Takeover
from tests.sim.test_reference_match import compare

DATA = Path(__file__).parent / "data"

_STOP_GROUP = """<ConditionGroup><Condition name="Braking" delay="0" conditionEdge="none">
  <ByEntityCondition>
    <TriggeringEntities triggeringEntitiesRule="any"><EntityRef entityRef="Lead"/>
    </TriggeringEntities>
    <EntityCondition><AccelerationCondition {attributes}/></EntityCondition>
  </ByEntityCondition>
</Condition></ConditionGroup>
</StopTrigger>"""


def _end_time(tmp_path: Path, attributes: str) -> float:
    # the lead brakes at 8 m/s^2 from 25 m/s from t = 2 s; without the acceleration stop the
    # storyboard ends 3 s after the brake event (about 8.2 s)
    shutil.copy(DATA / "straight.xodr", tmp_path / "straight.xodr")
    text = (DATA / "hard_braking_lead.xosc").read_text(encoding="utf-8")
    text = text.replace(
        '<ControllerAction><ActivateControllerAction longitudinal="true" lateral="true"/>'
        "</ControllerAction>",
        '<VisibilityAction graphics="true" traffic="true" sensors="true"/>',
    )
    text = text.replace("</StopTrigger>", _STOP_GROUP.format(attributes=attributes))
    path = tmp_path / "braking.xosc"
    path.write_text(text, encoding="utf-8")
    report = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=path,
            nets_dir=tmp_path,
            record=False,
            backend=BackendChoice.MEMORY,
            sut=SutConfig(takeover=Takeover.NEVER),
        )
    )
    assert report.storyboard_complete, report.outcome.reason
    return report.outcome.simulated_seconds


@pytest.mark.parametrize(
    "attributes",
    [
        'value="5" rule="greaterThan"',  # magnitude: braking reads +8
        'value="-5" rule="lessThan" direction="longitudinal"',
    ],
)
def test_braking_is_seen(attributes: str, tmp_path: Path) -> None:
    # braking starts in the step from 2.05 s; the stop trigger reads it at 2.10 s
    assert _end_time(tmp_path, attributes) == pytest.approx(2.1)


@pytest.mark.parametrize(
    "attributes",
    [
        'value="-5" rule="lessThan"',  # a magnitude is never negative
        'value="1" rule="greaterThan" direction="lateral"',
        'value="5" rule="greaterThan" direction="longitudinal"',
    ],
)
def test_braking_is_not_seen(attributes: str, tmp_path: Path) -> None:
    assert _end_time(tmp_path, attributes) > 8.0


def test_a_lane_change_never_reads_exactly_zero(tmp_path: Path) -> None:
    # cut-in_simple stops 2 s after the cut-in car's acceleration is 0 (and after 10 s): only
    # when it stands, as in esmini, whose lane change takes the lateral part of a step's travel
    # at the rate of the step start; measured at the step end instead, a sinusoidal change is
    # symmetric about its middle and reads 0 there (the run would stop at 10.15 s)
    comparison = compare("xosc/cut-in_simple.xosc", tmp_path)
    assert comparison.end_difference == pytest.approx(0.0)
    assert comparison.match, comparison
