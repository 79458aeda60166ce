"""CARLA ScenarioRunner-style scenarios run to a verdict with every criterion's outcome.

The scenarios (``carla_scenarios.follow_leading`` on ``carla/avenue.xodr``, one on the shipped
Town01) are written as ScenarioRunner's examples are: ``CARLA:`` header, the hero handed to the SUT
by ``external_control``, an act that starts once the hero moved, ``criteria_*`` tests in the
storyboard StopTrigger. Covers: the run ends when the stories end and passes with each criterion
reported; each judged criterion failing on its own (KeepLane on steering back across a border,
OnSidewalk, Collision, DrivenDistance); the external ego must drive for the act to start;
ScenarioRunner's rules chosen by any of its conventions, esmini's edge rule on the same file
without any never starting the act; entity actions and other actions ScenarioRunner cannot
build make the file Invalid, a second story never runs; the built-in autopilot for
``carla_autopilot`` (also on the hero, at Town01's speed limit); the environment in the run log
and the recording's metadata; on Town01 in CARLA's frame: a hero spawned off centre at walking
speed steers back within its lane, ``check`` and ``run`` judge a file alike, walkers walk where
they face with CARLA's size.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from mcap.reader import make_reader

from simtest_operator.drivermodel import SutConfig, Takeover
from simtest_operator.settings import SimulationSettings
from simtest_operator.sim import BackendChoice, open_simulation
from simtest_operator.verdicts import Verdict

from . import carla_scenarios as cs
from .carla_scenarios import run

CORPUS = Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev"


def test_follow_leading_passes_with_each_criterion_reported(tmp_path: Path) -> None:
    report = run(cs.write(tmp_path, cs.follow_leading()))
    outcome = report.outcome
    assert outcome.verdict is Verdict.PASSED, outcome.reason
    # The StopTrigger held only criteria: the run ended when the story did, long before 60 s.
    assert report.storyboard_complete and 5.0 < outcome.simulated_seconds < 30.0
    for name in ("WrongLaneTest", "OnSidewalkTest", "KeepLaneTest", "CollisionTest"):
        assert f"{name} passed" in outcome.reason
        assert outcome.metrics[f"criteria.{name}"] == 1.0
    assert "DrivenDistanceTest passed" in outcome.reason
    assert outcome.metrics["drivenDistance"] >= 50.0
    # The avenue has no signals: nothing to run, as in ScenarioRunner.
    assert "RunningStopTest passed (the map has no stop signs)" in outcome.reason
    assert "RunningRedLightTest passed (the map has no traffic lights)" in outcome.reason
    assert report.deviations == ()


def test_act_waits_for_the_externally_driven_ego(tmp_path: Path) -> None:
    path = cs.write(tmp_path, cs.follow_leading())
    scripted = run(path, sut=SutConfig(takeover=Takeover.NEVER), time_limit=15.0)
    # Nobody drives the hero: it never moves, the act never starts, the story never ends; the
    # failed criterion is the news (it outranks the timeout).
    assert not scripted.storyboard_complete
    assert scripted.outcome.verdict is Verdict.FAILED
    assert scripted.outcome.reason.startswith("criteria_DrivenDistanceTest failed: 0.0 m <= 50 m")
    assert max(s[4] for s in scripted.samples["hero"]) == 0.0
    driven = run(path)
    assert driven.outcome.verdict is Verdict.PASSED
    assert max(s[4] for s in driven.samples["hero"]) > 5.0


_LATE_STOP = """
        <Condition name="Late" delay="0" conditionEdge="rising">
          <ByValueCondition>
            <SimulationTimeCondition value="100" rule="greaterThan"/>
          </ByValueCondition>
        </Condition>"""


@pytest.mark.parametrize(
    ("stop", "hero_control", "logic_file", "rules"),
    [
        (_LATE_STOP, "", "avenue.xodr", "OpenSCENARIO (esmini)"),
        (cs.criteria("CollisionTest", distance=None), "", "avenue.xodr", "criteria_*"),
        (_LATE_STOP, cs.HERO_CONTROL, "avenue.xodr", "controller module external_control"),
        (_LATE_STOP, "", "Town01", "CARLA town Town01"),
    ],
)
def test_without_the_carla_header_its_conventions_choose_the_rules(
    tmp_path: Path, stop: str, hero_control: str, logic_file: str, rules: str
) -> None:
    # SimulationTime == 0 is true at the first evaluation only: esmini's rising edge never fires
    # there, ScenarioRunner's level-triggered, one-shot condition does and holds until the hero
    # has moved a metre. Without the CARLA: header, any of ScenarioRunner's conventions picks
    # its rules; a file with none of them runs under esmini's.
    town = logic_file == "Town01"
    text = cs.follow_leading(
        description="FollowLeadingVehicle",
        stop=stop,
        hero_control=hero_control,
        logic_file=logic_file,
        hero_position='<LanePosition roadId="4" laneId="-1" s="48.58" offset="0"/>'
        if town
        else '<LanePosition roadId="1" laneId="-1" s="20" offset="0"/>',
    )
    path = cs.write(tmp_path, text)
    # The SUT drives the hero from the start at 8 m/s (a driver with set speed 0 stands still).
    sut = SutConfig(takeover=Takeover.AFTER_INIT, desired_speed=8.0)
    report = run(path, sut=sut, time_limit=15.0)
    assert rules in report.rules
    lead_speeds = {s[4] for s in report.samples["adversary"]}
    if rules.startswith("OpenSCENARIO"):
        assert report.outcome.verdict is Verdict.TIMEOUT
        assert lead_speeds == {0.0}
    else:
        assert report.rules.startswith("ScenarioRunner (")
        assert max(lead_speeds) > 5.0, report.outcome.reason


@pytest.mark.parametrize(
    ("hero_position", "failing", "detail"),
    [
        (
            '<LanePosition roadId="1" laneId="-1" s="20" offset="1.4"/>',
            "KeepLaneTest",
            # astride at the start is no invasion; steering back into lane -1 is
            "hero crossed from lane -2 into lane -1 of road 1 at t=0.95 s",
        ),
        (
            '<LanePosition roadId="1" laneId="-3" s="20" offset="0"/>',
            "OnSidewalkTest",
            "hero on a sidewalk for 0.05 s > 0 s at t=0.05 s",
        ),
    ],
)
def test_lane_criteria_fail(tmp_path: Path, hero_position: str, failing: str, detail: str) -> None:
    # The adversary waits in the outer lane, out of the way.
    adversary = """
        <Private entityRef="adversary"><PrivateAction><TeleportAction><Position>
          <LanePosition roadId="1" laneId="-2" s="200" offset="0"/>
        </Position></TeleportAction></PrivateAction></Private>"""
    text = cs.follow_leading(hero_position=hero_position, adversary_init=adversary)
    outcome = run(cs.write(tmp_path, text)).outcome
    assert outcome.verdict is Verdict.FAILED
    assert outcome.reason.startswith(f"criteria_{failing} failed: {detail}")
    assert outcome.metrics[f"criteria.{failing}"] == 0.0
    assert outcome.metrics["criteria.CollisionTest"] == 1.0


def test_collision_and_driven_distance_fail(tmp_path: Path) -> None:
    # The adversary stands 50 m ahead; the run lasts until the hero drove 100 m.
    text = cs.follow_leading(stop=cs.criteria("CollisionTest", distance=5000), brake_after=100)
    blind = SutConfig(acc=False, aeb=False)
    path = cs.write(tmp_path, text)
    outcome = run(path, sut=blind, overrides={"leadingSpeed": "0"}).outcome
    assert outcome.verdict is Verdict.FAILED
    assert outcome.reason.startswith("hero collided with adversary")
    assert "CollisionTest failed (hero collided with adversary at t=" in outcome.reason
    assert "(+2 more: criteria_CollisionTest, criteria_DrivenDistanceTest)" in outcome.reason
    assert outcome.metrics["criteria.CollisionTest"] == 0.0
    assert outcome.metrics["criteria.DrivenDistanceTest"] == 0.0


def test_a_criterion_scenario_runner_cannot_build_makes_the_run_invalid(tmp_path: Path) -> None:
    # ScenarioRunner raises while building criteria_HoverTest (no such class in
    # OpenScenarioParser's globals) and refuses the file: "The scenario cannot be loaded".
    text = cs.follow_leading(stop=cs.criteria("CollisionTest", "HoverTest"))
    report = run(cs.write(tmp_path, text))
    assert report.outcome.verdict is Verdict.INVALID
    assert report.outcome.reason.startswith(
        "ScenarioRunner cannot load the file: criteria_HoverTest (line "
    )
    assert report.outcome.reason.endswith("ScenarioRunner has no such test")
    assert report.outcome.simulated_seconds == 0.0
    assert [d.code for d in report.deviations] == ["carla-criterion-unknown"]
    # Its class names are case-sensitive: OnSideWalkTest is no class (OnSidewalkTest is).
    text = cs.follow_leading(stop=cs.criteria("CollisionTest", "OnSideWalkTest"))
    report = run(cs.write(tmp_path, text))
    assert report.outcome.verdict is Verdict.INVALID
    assert "criteria_OnSideWalkTest" in report.outcome.reason


_LATE = cs.vehicle("late", "simulation")
_ADD_AND_DELETE = """
            <Event name="LateArrives" priority="parallel">
              <Action name="AddLate"><GlobalAction><EntityAction entityRef="late">
                <AddEntityAction><Position>
                  <LanePosition roadId="1" laneId="-2" s="150" offset="0"/>
                </Position></AddEntityAction>
              </EntityAction></GlobalAction></Action>
              <StartTrigger><ConditionGroup><Condition name="t2" delay="0" conditionEdge="rising">
                <ByValueCondition><SimulationTimeCondition value="2" rule="greaterThan"/>
                </ByValueCondition></Condition></ConditionGroup></StartTrigger>
            </Event>
            <Event name="LateLeaves" priority="parallel">
              <Action name="DeleteLate"><GlobalAction><EntityAction entityRef="late">
                <DeleteEntityAction/>
              </EntityAction></GlobalAction></Action>
              <StartTrigger><ConditionGroup><Condition name="t5" delay="0" conditionEdge="rising">
                <ByValueCondition><SimulationTimeCondition value="5" rule="greaterThan"/>
                </ByValueCondition></Condition></ConditionGroup></StartTrigger>
            </Event>"""


def test_entity_actions_in_a_story_make_the_run_invalid(tmp_path: Path) -> None:
    # convert_maneuver_to_atomic builds a GlobalAction only for traffic-signal states, the
    # environment and (newer releases) parameters; an EntityAction raises "Global actions are not
    # yet supported" while the story is built, so ScenarioRunner cannot load the file. (esmini's
    # rules add and delete entities: tests/sim/test_declared_jumps.py.)
    text = cs.follow_leading(extra_entities=_LATE, extra_events=_ADD_AND_DELETE)
    report = run(cs.write(tmp_path, text))
    assert report.outcome.verdict is Verdict.INVALID
    assert report.outcome.reason.startswith(
        "ScenarioRunner cannot load the file: action 'AddLate' (line "
    )
    assert report.outcome.reason.endswith("Global actions are not yet supported")
    deletion = _ADD_AND_DELETE[_ADD_AND_DELETE.index('<Event name="LateLeaves"') :]
    text = cs.follow_leading(extra_entities=_LATE, extra_events=deletion)
    reason = run(cs.write(tmp_path, text, name="delete.xosc")).outcome.reason
    assert reason.startswith("ScenarioRunner cannot load the file: action 'DeleteLate'"), reason


def test_carla_autopilot_drives_a_non_ego_vehicle(tmp_path: Path) -> None:
    adversary = """
        <Private entityRef="adversary">
          <PrivateAction><TeleportAction><Position>
            <LanePosition roadId="1" laneId="-2" s="40" offset="0"/>
          </Position></TeleportAction></PrivateAction>
          <PrivateAction><ControllerAction><AssignControllerAction>
            <Controller name="Autopilot"><Properties>
              <Property name="module" value="carla_autopilot"/>
            </Properties></Controller>
          </AssignControllerAction></ControllerAction></PrivateAction>
        </Private>"""
    report = run(cs.write(tmp_path, cs.follow_leading(adversary_init=adversary)))
    # The autopilot brings it from rest to the towns' 30 km/h (the test street sets no speed
    # limit); like CARLA's it takes none of the story's SpeedActions.
    speeds = [sample[4] for sample in report.samples["adversary"]]
    assert speeds[0] == 0.0 and max(speeds) == pytest.approx(30.0 / 3.6, abs=0.2)
    assert "SpeedAction on the autopilot of adversary" in report.outcome.ignored_elements
    assert not any("Autopilot" in label for label in report.intended)


def test_environment_recorded_in_log_and_recording(tmp_path: Path) -> None:
    weather = """
            <Event name="Rain" priority="parallel">
              <Action name="Rain"><GlobalAction><EnvironmentAction>
                <Environment name="Rain">
                  <TimeOfDay animation="false" dateTime="2020-03-20T18:00:00"/>
                  <Weather cloudState="rainy"><Precipitation precipitationType="rain" intensity="0.9"/>
                  </Weather><RoadCondition frictionScaleFactor="0.6"/>
                </Environment>
              </EnvironmentAction></GlobalAction></Action>
              <StartTrigger><ConditionGroup><Condition name="t3" delay="0" conditionEdge="rising">
                <ByValueCondition><SimulationTimeCondition value="3" rule="greaterThan"/>
                </ByValueCondition></Condition></ConditionGroup></StartTrigger>
            </Event>"""  # noqa: E501
    out = tmp_path / "out"
    report = run(cs.write(tmp_path, cs.follow_leading(extra_events=weather)), out=out)
    assert report.outcome.verdict is Verdict.PASSED, report.outcome.reason
    log = (out / "run.log").read_text(encoding="utf-8")
    assert "environment Noon at t=0 s (recorded, not rendered)" in log
    # SimulationTime > 3 counts from the act's start at t=1.05 s
    assert "environment Rain at t=4.05 s (recorded, not rendered)" in log
    with (out / "recording.mcap").open("rb") as stream:
        records = [
            m.metadata
            for m in make_reader(stream).iter_metadata()
            if m.name == "simtest.environment"
        ]
    assert [r["name"] for r in records] == ["Noon", "Rain"]
    assert records[1]["Weather.Precipitation.intensity"] == "0.9"
    assert records[1]["RoadCondition.frictionScaleFactor"] == "0.6"
    assert records[0]["Weather.Sun.elevation"] == "1.31"


def test_town01_scenario(tmp_path: Path) -> None:
    text = cs.follow_leading(
        logic_file="Town01",
        hero_position='<LanePosition roadId="4" laneId="-1" s="48.58" offset="0"/>',
        stop=cs.criteria("CollisionTest", "KeepLaneTest", "WrongLaneTest", "OnSidewalkTest"),
    )
    path = tmp_path / "town01.xosc"
    path.write_text(text, encoding="utf-8")
    report = run(path)
    outcome = report.outcome
    assert outcome.verdict is Verdict.PASSED, outcome.reason
    for name in ("CollisionTest", "KeepLaneTest", "WrongLaneTest", "OnSidewalkTest"):
        assert outcome.metrics[f"criteria.{name}"] == 1.0
    assert outcome.metrics["drivenDistance"] >= 50.0


@pytest.mark.parametrize("left", [-0.65, 0.75])
def test_hero_off_centre_at_walking_speed_steers_back_within_its_lane(
    tmp_path: Path, left: float
) -> None:
    # The hero starts at rest 0.65-0.75 m off centre: lane keeping turns it as a car can turn
    # at that speed, so it creeps back instead of swinging round into the next lane.
    report = run(cs.write(tmp_path, cs.town01_drive(hero_left=left)))
    outcome = report.outcome
    assert outcome.verdict is Verdict.PASSED, outcome.reason
    assert outcome.metrics["criteria.KeepLaneTest"] == 1.0
    hero = report.samples["hero"]
    assert max(abs(sample[3]) for sample in hero) < 0.2  # rad, once per second
    assert hero[-1][2] == pytest.approx(-cs.TOWN01_LANE_Y, abs=0.05)  # back on the centre


def test_check_and_run_judge_a_carla_file_alike(tmp_path: Path) -> None:
    # Without a kept recording (``scenario check``) the run still records to a scratch file
    # and a pass meets the evidence checks of ``scenario run``; both agree, and the hero's
    # box never jumps against its velocity (it used to swing 1.8 m round its rear axle).
    text = cs.town01_drive(hero_left=-0.65, stop=cs.criteria("CollisionTest", distance=20))
    path = cs.write(tmp_path, text)
    checked = run(path).outcome
    out = tmp_path / "out"
    recorded = run(path, out=out).outcome
    assert (checked.verdict, checked.reason) == (recorded.verdict, recorded.reason)
    assert recorded.verdict is Verdict.PASSED, recorded.reason
    assert "evidence: complete" in (out / "run.log").read_text(encoding="utf-8")


TOWN01_LIMIT = 25 * 0.44704
"""m/s: Town01's roads are ``<speed max="25" unit="mph"/>``."""


@pytest.mark.parametrize("control", [cs.HERO_AUTOPILOT, cs.HERO_ACTIVATE])
def test_autopilot_drives_the_hero_at_the_speed_limit(tmp_path: Path, control: str) -> None:
    # carla_autopilot, or ScenarioRunner's ActivateControllerAction (ChangeAutoPilot), hands the
    # hero to CARLA's autopilot: from rest up to the road's limit, not creeping at 0.1 m/s; like
    # the autopilot it takes no SpeedAction (the story's 8.33 m/s is listed as ignored).
    report = run(cs.write(tmp_path, cs.town01_drive(hero_control=control, distance=80)))
    outcome = report.outcome
    assert outcome.verdict is Verdict.PASSED, outcome.reason
    assert outcome.metrics["drivenDistance"] == pytest.approx(80.0, abs=1.0)
    assert "DrivenDistanceTest passed (80." in outcome.reason
    speeds = [sample[4] for sample in report.samples["hero"]]
    assert speeds[0] == 0.0 and TOWN01_LIMIT - 0.2 < max(speeds) <= TOWN01_LIMIT
    assert outcome.simulated_seconds < 12.0
    assert "SpeedAction on the autopilot of hero" in outcome.ignored_elements


def _crossing(tmp_path: Path, *, description: str = "CARLA:Town01Drive") -> Path:
    entities, init, group = cs.walker_crossing(x=150, speed=1.5, after=15)
    text = cs.town01_drive(entities=entities, init=init, groups=group, distance=60)
    return cs.write(tmp_path, text.replace("CARLA:Town01Drive", description))


def test_a_walker_given_a_speed_walks_where_it_faces(tmp_path: Path) -> None:
    # The walker stands on the sidewalk facing the road; its SpeedAction sends it across the
    # hero's lane (ScenarioRunner's PedestrianControl), not along the sidewalk.
    path = _crossing(tmp_path)
    blind = run(path, sut=SutConfig(acc=False, aeb=False))
    walker = blind.samples["walker"]
    assert {sample[1] for sample in walker} == {150.0}
    assert walker[0][2] == pytest.approx(-203.44) and walker[-1][2] > -199.14
    assert blind.outcome.verdict is Verdict.FAILED
    assert blind.outcome.reason.startswith("hero collided with walker")
    assert blind.outcome.metrics["criteria.CollisionTest"] == 0.0
    braking = run(path).outcome
    assert braking.verdict is Verdict.PASSED, braking.reason


def test_walkers_have_carla_size(tmp_path: Path) -> None:
    # ScenarioRunner spawns a walker blueprint, about 0.5 m across, whatever the file's box
    # (1 m here); a file without ScenarioRunner's conventions keeps its box.
    def walker_box(path: Path, name: str = "walker") -> tuple[float, float]:
        opened = open_simulation(
            path,
            sut=SutConfig(),
            settings=SimulationSettings(),
            nets_dir=tmp_path / "nets",
            backend=BackendChoice.MEMORY,
        )
        snapshot = opened.simulation.start()
        opened.simulation.close()
        (state,) = (e for e in snapshot.entities if e.name == name)
        return state.box.length, state.box.width

    assert walker_box(_crossing(tmp_path)) == (0.5, 0.5)
    # Without the CARLA: header the file still shows ScenarioRunner's conventions (Town01,
    # criteria_*, external_control): its rules, and CARLA's walkers.
    plain = tmp_path / "plain"
    plain.mkdir()
    assert walker_box(_crossing(plain, description="Town01Drive")) == (0.5, 0.5)
    # A file under esmini's rules keeps its pedestrian's box (0.6 x 0.5 m in its catalog).
    esmini = CORPUS / "esmini" / "resources" / "xosc" / "pedestrian.xosc"
    assert walker_box(esmini, "pedestrian_adult") == pytest.approx((0.6, 0.5))


def test_a_failed_end_of_road_test_ends_the_run(tmp_path: Path) -> None:
    # ScenarioRunner's EndofRoadTest returns SUCCESS once it failed, which ends its criteria
    # group and the scenario: the run stops there, long before the act (1 km) or time limit.
    from tests.evaluation.test_lane_criteria import TWO_ROADS

    (tmp_path / "two.xodr").write_bytes(TWO_ROADS)
    adversary = """
        <Private entityRef="adversary"><PrivateAction><TeleportAction><Position>
          <LanePosition roadId="2" laneId="-1" s="90" offset="0"/>
        </Position></TeleportAction></PrivateAction></Private>"""
    text = cs.follow_leading(
        stop=cs.criterion("EndofRoadTest", "duration", "1") + cs.criteria(distance=None),
        hero_position='<LanePosition roadId="1" laneId="-1" s="80" offset="0"/>',
        adversary_init=adversary,
        act_distance=1000.0,
        logic_file="two.xodr",
    )
    outcome = run(cs.write(tmp_path, text), time_limit=40.0).outcome
    assert outcome.verdict is Verdict.FAILED
    assert outcome.reason.startswith("criteria_EndofRoadTest failed: hero left road 1 at t=")
    failed_at = float(outcome.reason.split(" at t=")[2].split(" s")[0])
    assert outcome.simulated_seconds == pytest.approx(failed_at, abs=1e-6)
    assert outcome.simulated_seconds < 20.0


_FREESPACE_EVENT = """
            <Event name="Near" priority="parallel">
              <Action name="NearSpeed">
                <PrivateAction><LongitudinalAction><SpeedAction>
                  <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
                  <SpeedActionTarget><AbsoluteTargetSpeed value="5"/></SpeedActionTarget>
                </SpeedAction></LongitudinalAction></PrivateAction>
              </Action>
              <StartTrigger><ConditionGroup>
                <Condition name="CloseToTheEnd" delay="0" conditionEdge="rising">
                  <ByEntityCondition>
                    <TriggeringEntities triggeringEntitiesRule="any">
                      <EntityRef entityRef="adversary"/></TriggeringEntities>
                    <EntityCondition><DistanceCondition value="10" freespace="true"
                        alongRoute="false" rule="lessThan"><Position>
                      <LanePosition roadId="1" laneId="-1" s="500" offset="0"/>
                    </Position></DistanceCondition></EntityCondition>
                  </ByEntityCondition>
                </Condition>
              </ConditionGroup></StartTrigger>
            </Event>"""


def test_a_condition_scenario_runner_cannot_build_makes_the_run_invalid(tmp_path: Path) -> None:
    # OpenScenarioParser raises NotImplementedError for a free-space DistanceCondition while it
    # builds the event's start trigger: "The scenario cannot be loaded".
    text = cs.follow_leading(extra_events=_FREESPACE_EVENT)
    report = run(cs.write(tmp_path, text))
    assert report.outcome.verdict is Verdict.INVALID
    assert report.outcome.reason.startswith(
        "ScenarioRunner cannot load the file: condition 'CloseToTheEnd' (line "
    )
    assert report.outcome.reason.endswith(
        "DistanceCondition: freespace attribute is currently not implemented"
    )
    # The storyboard's StopTrigger is built for its criteria only: there the condition is no bar.
    condition = _FREESPACE_EVENT[
        _FREESPACE_EVENT.index("<Condition ") : _FREESPACE_EVENT.index("</ConditionGroup>")
    ]
    stop = cs.criteria("CollisionTest") + condition
    report = run(cs.write(tmp_path, cs.follow_leading(stop=stop), name="stop.xosc"))
    assert report.outcome.verdict is not Verdict.INVALID, report.outcome.reason
    # Under esmini's rules the same file runs.
    time_stop = """
        <Condition name="Late" delay="0" conditionEdge="rising"><ByValueCondition>
          <SimulationTimeCondition value="5" rule="greaterThan"/></ByValueCondition></Condition>"""
    esmini = cs.follow_leading(stop=time_stop, extra_events=_FREESPACE_EVENT, description="plain")
    esmini = esmini.replace("external_control", "some_driver")
    report = run(cs.write(tmp_path, esmini, name="plain.xosc"))
    assert report.rules.startswith("OpenSCENARIO"), report.rules
    assert report.outcome.verdict is not Verdict.INVALID, report.outcome.reason


def _event(name: str, action: str) -> str:
    """An event of the adversary starting at once with one action (its whole body)."""
    return cs.event(name, action, cs.at(0), private=False)


_UNBUILT_ACTIONS = {
    "FollowTrajectoryAction": (
        """<PrivateAction><RoutingAction><FollowTrajectoryAction>
             <Trajectory name="t" closed="false"><Shape><Polyline>
               <Vertex time="0"><Position><WorldPosition x="0" y="0"/></Position></Vertex>
               <Vertex time="1"><Position><WorldPosition x="10" y="0"/></Position></Vertex>
             </Polyline></Shape></Trajectory>
             <TimeReference><None/></TimeReference>
             <TrajectoryFollowingMode followingMode="position"/>
           </FollowTrajectoryAction></RoutingAction></PrivateAction>""",
        "Private FollowTrajectory actions are not yet supported",
    ),
    "timeGap": (
        """<PrivateAction><LongitudinalAction><LongitudinalDistanceAction entityRef="hero"
             timeGap="2" freespace="false" continuous="true"/>
           </LongitudinalAction></PrivateAction>""",
        "LongitudinalDistanceAction: timeGap is not implemented",
    ),
    "AbsoluteTargetLane": (
        """<PrivateAction><LateralAction><LaneChangeAction><LaneChangeActionDynamics
             dynamicsShape="linear" value="2" dynamicsDimension="time"/>
           <LaneChangeTarget><AbsoluteTargetLane value="-2"/></LaneChangeTarget>
           </LaneChangeAction></LateralAction></PrivateAction>""",
        "it reads a RelativeTargetLane only",
    ),
    "VariableAction": (
        """<GlobalAction><VariableAction variableRef="count"><SetAction value="3"/>
           </VariableAction></GlobalAction>""",
        "Global actions are not yet supported",
    ),
    "VisibilityAction": (
        """<PrivateAction><VisibilityAction graphics="false" traffic="true" sensors="true"/>
           </PrivateAction>""",
        "Visibility actions are not yet supported",
    ),
    "lamp states": (
        """<GlobalAction><InfrastructureAction><TrafficSignalAction>
             <TrafficSignalStateAction name="1" state="on;off;off"/>
           </TrafficSignalAction></InfrastructureAction></GlobalAction>""",
        "CARLA only supports Green, Red, Yellow or Off",
    ),
}


@pytest.mark.parametrize("case", sorted(_UNBUILT_ACTIONS))
def test_an_action_scenario_runner_cannot_build_makes_the_run_invalid(
    tmp_path: Path, case: str
) -> None:
    # OpenScenarioParser.convert_maneuver_to_atomic raises while the story is built: "The
    # scenario cannot be loaded". Under esmini's rules the same file runs.
    action, why = _UNBUILT_ACTIONS[case]
    report = run(cs.write(tmp_path, cs.follow_leading(extra_events=_event("Odd", action))))
    assert report.outcome.verdict is Verdict.INVALID
    assert report.outcome.reason.startswith(
        "ScenarioRunner cannot load the file: action 'Odd' (line "
    ), report.outcome.reason
    assert why in report.outcome.reason
    time_stop = """
        <Condition name="Late" delay="0" conditionEdge="rising"><ByValueCondition>
          <SimulationTimeCondition value="5" rule="greaterThan"/></ByValueCondition></Condition>"""
    esmini = cs.follow_leading(
        stop=time_stop, extra_events=_event("Odd", action), description="plain"
    ).replace("external_control", "some_driver")
    report = run(cs.write(tmp_path, esmini, name="plain.xosc"))
    assert report.rules.startswith("OpenSCENARIO"), report.rules
    assert report.outcome.verdict is not Verdict.INVALID, report.outcome.reason


def test_scenario_runner_builds_every_story(tmp_path: Path) -> None:
    # ScenarioRunner builds every Story since 0.9.12 (OpenScenarioConfiguration.stories,
    # "Added support for storyboards with multiple stories"): a second story's brake happens,
    # and an action there that it cannot build bars the file like one in the first story.
    brake = """<PrivateAction><LongitudinalAction><SpeedAction>
        <SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>
        <SpeedActionTarget><AbsoluteTargetSpeed value="0"/></SpeedActionTarget>
      </SpeedAction></LongitudinalAction></PrivateAction>"""

    def second(events: str) -> str:
        return f"""
    <Story name="Second">
      <Act name="SecondAct">
        <ManeuverGroup name="SecondGroup" maximumExecutionCount="1">
          <Actors selectTriggeringEntities="false"><EntityRef entityRef="adversary"/></Actors>
          <Maneuver name="SecondManeuver">{events}</Maneuver>
        </ManeuverGroup>
        <StartTrigger><ConditionGroup>
          <Condition name="SecondStart" delay="0" conditionEdge="rising">
            <ByValueCondition><SimulationTimeCondition value="4" rule="greaterThan"/>
            </ByValueCondition></Condition>
        </ConditionGroup></StartTrigger>
      </Act>
    </Story>"""

    def with_story(events: str) -> str:
        return cs.follow_leading().replace("</Story>", "</Story>" + second(events), 1)

    alone = run(cs.write(tmp_path, cs.follow_leading(), name="one.xosc"))
    halted = run(cs.write(tmp_path, with_story(_event("Halt", brake)), name="two.xosc"))
    assert alone.outcome.verdict is not Verdict.INVALID, alone.outcome.reason
    assert halted.outcome.verdict is not Verdict.INVALID, halted.outcome.reason
    assert halted.samples != alone.samples
    assert not [e for e in halted.outcome.ignored_elements if e.startswith("Story")]
    # the adversary drives at 6 m/s from t = 2 s; the second story halts it after 4 s
    assert [s[4] for s in alone.samples["adversary"] if s[0] == 5.0] == [6.0]
    assert [s[4] for s in halted.samples["adversary"] if s[0] == 5.0] == [0.0]
    unbuilt = _UNBUILT_ACTIONS["VisibilityAction"][0]
    refused = run(cs.write(tmp_path, with_story(_event("Hide", unbuilt)), name="three.xosc"))
    assert refused.outcome.verdict is Verdict.INVALID
    assert refused.outcome.reason.startswith(
        "ScenarioRunner cannot load the file: action 'Hide' (line "
    ), refused.outcome.reason
