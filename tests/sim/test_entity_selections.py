"""EntitySelection: a selection's name stands for its members wherever a list of entities is
read (Actors, TriggeringEntities, an Init Private); ByType selects every object of a type;
selections nest; a member that is not declared, or a selection containing itself, is refused."""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import load_scenario
from simtest_operator.verdicts import Verdict
from tests.sim import osc_scenarios as osc

ENTITIES = (
    osc.CAR.format(name="Ego")
    + osc.CAR.format(name="Lead")
    + osc.WALKER.format(name="Walker")
    + '<EntitySelection name="Cars"><Members><ByType objectType="vehicle"/></Members>'
    "</EntitySelection>"
    '<EntitySelection name="Everyone"><Members><EntityRef entityRef="Cars"/>'
    '<EntityRef entityRef="Walker"/><EntityRef entityRef="Ego"/></Members></EntitySelection>'
)


def _text(*, actors: str = '<EntityRef entityRef="Cars"/>', init: str | None = None) -> str:
    slow = (
        '<Condition name="slow" delay="0" conditionEdge="rising"><ByEntityCondition>'
        '<TriggeringEntities triggeringEntitiesRule="all"><EntityRef entityRef="Cars"/>'
        '</TriggeringEntities><EntityCondition><SpeedCondition value="6" rule="lessThan"/>'
        "</EntityCondition></ByEntityCondition></Condition>"
    )
    if init is None:
        # Each placed on its own, then the selection's Private sets both cars' speed.
        init = (
            osc.place("Ego", s=20.0, speed=0.0)
            + osc.place("Lead", s=60.0, speed=0.0)
            + osc.place("Walker", lane=-2, s=5.0, speed=0.0)
            + f'<Private entityRef="Cars">{osc.speed_action(10.0)}</Private>'
        )
    return osc.scenario(
        entities=ENTITIES,
        init=init,
        stories=osc.story(actors, osc.speed_action(5.0), osc.at_time(2.0)),
        stop=slow,
    )


def test_selections_expand_to_their_members(tmp_path: Path) -> None:
    text = _text(actors='<EntityRef entityRef="Everyone"/>', init=osc.place("Everyone"))
    scenario = load_scenario(osc.write(tmp_path, text))
    assert not scenario.unsupported()
    init = scenario.storyboard.init.private
    assert [p.entity_ref for p in init] == ["Ego", "Lead", "Walker"]
    group = scenario.storyboard.stories[0].acts[0].maneuver_groups[0]
    assert group.actors.entity_refs == ("Ego", "Lead", "Walker")
    stop = scenario.storyboard.stop_trigger
    assert stop is not None
    body = stop.condition_groups[0].conditions[0].body
    assert body.triggering_entities == ("Ego", "Lead")  # type: ignore[union-attr]


def test_a_selection_runs_as_its_members(tmp_path: Path) -> None:
    report = osc.run(osc.write(tmp_path, _text()), tmp_path)
    assert report.outcome.verdict is not Verdict.INVALID, report.outcome.reason
    assert set(report.samples) == {"Ego", "Lead", "Walker"}
    # The selection's Private set both cars going (10 m/s for the first second).
    assert [round(report.samples[name][1][4]) for name in ("Ego", "Lead")] == [10, 10]
    # The storyboard stopped once all cars of the selection were below 6 m/s: just after 2 s.
    assert 2.0 < report.outcome.simulated_seconds < 2.5


@pytest.mark.parametrize(
    ("selection", "message"),
    [
        (
            '<EntitySelection name="X"><Members><EntityRef entityRef="Nobody"/></Members>'
            "</EntitySelection>",
            "'Nobody' of selection 'X' is not declared",
        ),
        (
            '<EntitySelection name="X"><Members><EntityRef entityRef="Y"/></Members>'
            '</EntitySelection><EntitySelection name="Y"><Members><EntityRef entityRef="X"/>'
            "</Members></EntitySelection>",
            "contains itself",
        ),
        (
            '<EntitySelection name="Ego"><Members><ByType objectType="vehicle"/></Members>'
            "</EntitySelection>",
            "duplicate entity name 'Ego'",
        ),
    ],
)
def test_bad_selections_are_refused(tmp_path: Path, selection: str, message: str) -> None:
    text = osc.scenario(entities=osc.CAR.format(name="Ego") + selection, init=osc.place("Ego"))
    with pytest.raises(ScenarioError, match=message):
        load_scenario(osc.write(tmp_path, text))
