"""esmini's ghosts: an entity with a FollowGhostController (or an ExternalController with
``useGhost``) gets a copy ``<name>_ghost`` that runs its storyboard actions ``headstartTime``
seconds early (the simulation starts before 0), and the entity follows the ghost's trail."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from simtest_operator.runner import scenario_execution
from simtest_operator.sim import Takeover
from tests.sim import osc_scenarios as osc
from tests.sim.test_reference_match import compare

DATA = Path(__file__).parent / "data"

_FOLLOW = (
    '<Property name="esminiController" value="FollowGhostController"/>'
    '<Property name="headstartTime" value="2"/>'
)
_EXTERNAL = (
    '<Property name="esminiController" value="ExternalController"/>'
    '<Property name="useGhost" value="true"/>'
)
_ACTIVATE = (
    '<PrivateAction><ControllerAction><ActivateControllerAction longitudinal="true" '
    'lateral="true"/></ControllerAction></PrivateAction>'
)
_LANE_CHANGE = """
        <ManeuverGroup maximumExecutionCount="1" name="LeadSteers">
          <Actors selectTriggeringEntities="false">{actors}</Actors>
          <Maneuver name="LeadChangesLane">
            <Event name="LaneChangeEvent" priority="override">
              <Action name="LaneChange">
                <PrivateAction><LateralAction><LaneChangeAction>
                  <LaneChangeActionDynamics dynamicsShape="sinusoidal" dynamicsDimension="time"
                    value="2"/>
                  <LaneChangeTarget><AbsoluteTargetLane value="-2"/></LaneChangeTarget>
                </LaneChangeAction></LateralAction></PrivateAction>
              </Action>
              <StartTrigger><ConditionGroup>
                <Condition name="Steer" delay="0" conditionEdge="rising">
                  <ByValueCondition>{trigger}</ByValueCondition>
                </Condition>
              </ConditionGroup></StartTrigger>
            </Event>
          </Maneuver>
        </ManeuverGroup>"""


def _run(
    tmp_path: Path,
    controller: str,
    *,
    entity: str = "Lead",
    lane_change: str | None = None,
    actors: tuple[str, ...] = ("Lead",),
    activate: bool = True,
    takeover: Takeover = Takeover.NEVER,
) -> scenario_execution.RunReport:
    # hard_braking_lead: Ego at s = 20 and Lead at s = 60 of a straight road (lanes -1, -2), both
    # at 25 m/s; the lead brakes at 8 m/s^2 once the time passes 2 s; the storyboard ends 3 s
    # after that braking ended
    shutil.copy(DATA / "straight.xodr", tmp_path / "straight.xodr")
    text = (DATA / "hard_braking_lead.xosc").read_text(encoding="utf-8")
    text = osc.with_controller(text, entity, controller)
    if entity == "Lead" and activate:
        # after its Init's SpeedAction: the vehicle model starts at 25 m/s
        position = text.index("</Private>", text.index('<Private entityRef="Lead">'))
        text = text[:position] + _ACTIVATE + text[position:]
    if lane_change is not None:
        end = text.index("</ManeuverGroup>") + len("</ManeuverGroup>")
        refs = "".join(f'<EntityRef entityRef="{name}"/>' for name in actors)
        text = text[:end] + _LANE_CHANGE.format(trigger=lane_change, actors=refs) + text[end:]
    path = tmp_path / "ghost.xosc"
    path.write_text(text, encoding="utf-8")
    return osc.run(path, tmp_path, takeover=takeover)


def _at(samples: list[tuple[float, ...]], time: float) -> tuple[float, ...]:
    return next(sample for sample in samples if round(sample[0]) == time)


def test_ghost_runs_the_storyboard_ahead_and_the_entity_follows_its_trail(
    tmp_path: Path,
) -> None:
    report = _run(tmp_path, _FOLLOW)
    lead, ghost = report.samples["Lead"], report.samples["Lead_ghost"]
    # the ghost started 2 s early at 25 m/s from the same place (the entity stood meanwhile)
    assert _at(ghost, 0)[1] == pytest.approx(_at(lead, 0)[1] + 50.0, abs=0.5)
    # its braking (t > 2 s) moved 2 s earlier: it stands after 25/8 s, the entity brakes ~2 s
    # later along the same trail and stops where the ghost stopped
    assert _at(ghost, 4)[4] == 0.0
    assert _at(lead, 1)[4] == pytest.approx(25.0, abs=0.1)
    assert _at(lead, 3)[4] < 20.0
    assert lead[-1][1] == pytest.approx(ghost[-1][1], abs=2.0)
    assert lead[-1][2] == pytest.approx(ghost[-1][2], abs=0.05)
    # the storyboard (its StopTrigger is not moved) ends 3 s after the ghost's braking
    assert report.outcome.simulated_seconds == pytest.approx(25 / 8 + 3.0, abs=0.1)
    assert not report.intended
    assert "ghost" not in report.outcome.reason  # the ghost collides with nobody


def test_follower_steers_after_the_ghost_into_its_lane(tmp_path: Path) -> None:
    trigger = '<SimulationTimeCondition value="0.5" rule="greaterThan"/>'
    report = _run(tmp_path, _FOLLOW, lane_change=trigger)
    lead, ghost = report.samples["Lead"], report.samples["Lead_ghost"]
    # the ghost changed lanes from t = -1.5 to 0.5, the entity ~2 s later along its trail
    assert _at(ghost, 1)[2] == pytest.approx(-5.25, abs=0.01)
    assert _at(lead, 0)[2] == pytest.approx(-1.75, abs=0.01)
    assert _at(lead, 4)[2] == pytest.approx(-5.25, abs=0.3)


_BRAKE_STARTS = (
    '<StoryboardElementStateCondition storyboardElementType="event" '
    'storyboardElementRef="BrakeEvent" state="startTransition"/>'
)


def test_ghost_restart_replays_the_head_start_from_the_entity(tmp_path: Path) -> None:
    # the lane change waits for a storyboard state, which esmini does not hand to the ghost: when
    # it fires (t = 0.05 s, the ghost's braking moved to t > 0) the ghost is put back onto the
    # entity with its speed and replays its 2 s head start (braking, changing lanes) at once
    report = _run(tmp_path, _FOLLOW, lane_change=_BRAKE_STARTS)
    lead, ghost = report.samples["Lead"], report.samples["Lead_ghost"]
    assert _at(ghost, 0)[1] == pytest.approx(_at(lead, 0)[1] + 50.0, abs=0.5)
    # from the entity at 61.25 m: 2 s braking from 25 m/s at 8 m/s^2 is 34 m
    assert _at(ghost, 1)[1] == pytest.approx(61.25 + 34.0, abs=3.0)
    assert _at(ghost, 1)[2] == pytest.approx(-5.25, abs=0.01)
    assert _at(lead, 4)[2] == pytest.approx(-5.25, abs=0.1)
    assert not report.intended


def test_ghost_restart_for_several_actors_is_not_imitated(tmp_path: Path) -> None:
    report = _run(tmp_path, _FOLLOW, lane_change=_BRAKE_STARTS, actors=("Lead", "Ego"))
    assert "Lead_ghost" in report.samples
    assert report.intended == ("controller ctrl of Lead not imitated",)


def test_external_controller_with_ghost_stands_while_its_ghost_drives(tmp_path: Path) -> None:
    report = _run(tmp_path, _EXTERNAL)
    lead, ghost = report.samples["Lead"], report.samples["Lead_ghost"]
    assert [sample[1] for sample in lead] == pytest.approx([lead[0][1]] * len(lead))
    # 3 s head start by default: 3 s at 25 m/s less the braking from t = -1 s
    assert _at(ghost, 0)[1] == pytest.approx(lead[0][1] + 75.0 - 4.0, abs=0.5)
    assert not report.intended


def test_no_ghost_for_an_ego_the_sut_drives(tmp_path: Path) -> None:
    report = _run(tmp_path, _FOLLOW, entity="Ego", takeover=Takeover.ON_CONTROLLER)
    assert "Ego_ghost" not in report.samples
    assert report.intended == ("Ego driven by the SUT model",)


def test_the_sut_model_does_not_see_ghosts(tmp_path: Path) -> None:
    # the Lead's controller is never activated: it drives on at 25 m/s (its braking went to the
    # ghost, which stops ~150 m down the road); the SUT-driven Ego behind it drives through the
    # standing ghost after the Lead did
    report = _run(tmp_path, _FOLLOW, activate=False, takeover=Takeover.AFTER_INIT)
    ghost = report.samples["Lead_ghost"]
    assert ghost[-1][4] == 0.0
    ego = report.samples["Ego"]
    assert ego[-1][1] > ghost[-1][1]
    # it keeps its gap to the Lead (about 22.6 m/s) and never brakes for the ghost
    assert min(sample[4] for sample in ego) > 22.0


@pytest.mark.parametrize(
    "relative",
    [
        "trail_test.xosc",  # position mode along a clothoid lane change
        "init_test.xosc",  # time mode
        "ghost_restart2.xosc",  # restarts re-arming the teleporting events
        "timing_scenario_with_restarts.xosc",  # external controller with ghost, restarts
        "ghost_route.xosc",  # activated in the Init before its SpeedAction: starts from 0 m/s
    ],
)
def test_matches_the_reference_player(relative: str, tmp_path: Path) -> None:
    comparison = compare(relative, tmp_path)
    assert comparison.match, comparison
