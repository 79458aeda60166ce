"""Storyboard state machine: act start/stop triggers, events without triggers, transitions
visible for one step (startTransition/endTransition chains), states, event priorities
(override/skip/parallel), maximumExecutionCount of events and maneuver groups, actor selection
from triggering entities, storyboard stop trigger, completion without a stop trigger."""

from __future__ import annotations

from collections.abc import Sequence

from simtest_operator.openscenario import model
from simtest_operator.sim.engine import init_order
from simtest_operator.sim.storyboard import Storyboard
from tests.sim import builders as b


class FakeRun:
    """An action run that finishes after ``steps`` settles (0: at once)."""

    def __init__(self, steps: int) -> None:
        self.left = steps
        self.finished = steps == 0
        self.stopped = False

    def cancel(self) -> None:
        self.finished = self.stopped = True

    def tick(self) -> None:
        if not self.finished:
            self.left -= 1
            self.finished = self.left <= 0


class Harness:
    """Drives a Storyboard with a clock; SimulationTime conditions read it, actions are fakes."""

    def __init__(
        self, storyboard: model.Storyboard, durations: dict[str, int] | None = None
    ) -> None:
        self.now = 0.0
        self.durations = durations or {}
        self.started: list[tuple[float, str, tuple[str, ...]]] = []
        self.runs: list[FakeRun] = []
        self.board = Storyboard(storyboard, raw=self.raw, start_action=self.start)

    def raw(self, body: model.ByEntity | model.ByValue) -> tuple[bool, frozenset[str]]:
        if isinstance(body, model.ByEntity):
            cond = body.condition
            assert isinstance(cond, model.SpeedCondition)
            fast = frozenset(e for e in body.triggering_entities if e.startswith("fast"))
            ok = (
                fast == frozenset(body.triggering_entities)
                if body.rule.value == "all"
                else bool(fast)
            )
            return ok, fast
        cond = body.condition
        if isinstance(cond, model.SimulationTimeCondition):
            return self.now > cond.value, frozenset()
        assert isinstance(cond, model.StoryboardElementStateCondition)
        return self.board.is_in(cond.element_type, cond.element_ref, cond.state), frozenset()

    def start(self, action: model.Action, actors: tuple[str, ...]) -> Sequence[FakeRun]:
        self.started.append((self.now, action.name, actors))
        run = FakeRun(self.durations.get(action.name, 0))
        self.runs.append(run)
        return [run]

    def step(self, n: int = 1) -> None:
        for _ in range(n):
            self.now = round(self.now + 1.0, 6)
            self.board.update(self.now)
            for run in self.runs:
                run.tick()
            self.board.settle(self.now)

    def names(self) -> list[str]:
        return [name for _, name, _ in self.started]


def test_act_start_trigger_and_event_without_trigger() -> None:
    h = Harness(b.storyboard(b.event("E"), act_start=b.trigger((b.sim_time(2.5),))))
    h.step(2)
    assert h.started == []
    h.step()
    assert h.started == [(3.0, "E-action", ("Car",))]
    assert h.board.is_in(
        model.StoryboardElementType.EVENT, "E", model.StoryboardElementState.COMPLETE_STATE
    )


def test_transition_chain_one_step_per_link() -> None:
    first = b.event("First", b.action("a1"))
    second = b.event(
        "Second", b.action("a2"), start=b.trigger((b.state("event", "First", "endTransition"),))
    )
    h = Harness(b.storyboard(first, second), durations={"a1": 2})
    h.step(5)
    times = {name: t for t, name, _ in h.started}
    assert times == {"a1": 1.0, "a2": 3.0}  # a1 ends in step 2, its endTransition seen in 3


def test_transition_of_an_element_named_with_its_parents() -> None:
    # two events each with an action called "Action": "Slow::Action" is the second one only
    fast = b.event("Fast", b.action("Action"))
    slow = b.event("Slow", b.action("Action"), start=b.trigger((b.sim_time(2.5),)))
    then = b.event(
        "Then",
        b.action("a3"),
        start=b.trigger((b.state("action", "Slow::Action", "endTransition"),)),
    )
    h = Harness(b.storyboard(fast, slow, then), durations={"Action": 1})
    h.step(6)
    assert [(t, name) for t, name, _ in h.started] == [
        (1.0, "Action"),
        (3.0, "Action"),
        (4.0, "a3"),  # Slow's action ends in step 3, its endTransition seen in 4
    ]


def test_priority_override_stops_running_event() -> None:
    slow = b.event("Slow", b.action("slow"))
    over = b.event(
        "Over", b.action("over"), start=b.trigger((b.sim_time(1.5),)), priority="override"
    )
    h = Harness(b.storyboard(slow, over), durations={"slow": 10, "over": 1})
    h.step(2)
    assert h.runs[0].stopped and h.names() == ["slow", "over"]
    slow_state = model.StoryboardElementState.COMPLETE_STATE
    assert h.board.is_in(model.StoryboardElementType.EVENT, "Slow", slow_state)


def test_priority_skip_and_parallel() -> None:
    slow = b.event("Slow", b.action("slow"))
    skip = b.event("Skip", b.action("skip"), start=b.trigger((b.sim_time(1.5),)), priority="skip")
    par = b.event("Par", b.action("par"), start=b.trigger((b.sim_time(1.5),)), priority="parallel")
    h = Harness(b.storyboard(slow, skip, par), durations={"slow": 3})
    h.step(2)
    assert h.names() == ["slow", "par"]
    h.step(3)  # slow done; skip's condition (edge none) still true -> starts now
    assert h.names() == ["slow", "par", "skip"]


def test_maximum_execution_count_of_event_and_group() -> None:
    h = Harness(b.storyboard(b.event("E", start=b.trigger((b.sim_time(0.5),)), max_count=3)))
    h.step(10)
    assert h.names() == ["E-action"] * 3
    h2 = Harness(b.storyboard(b.event("E"), group_max=2))
    h2.step(10)
    assert h2.names() == ["E-action"] * 2


def test_triggering_entities_any_all_and_actor_selection() -> None:
    def speed_trigger(rule: str, *names: str) -> model.Trigger:
        cond = model.Condition(
            name="s",
            delay=0.0,
            edge=model.ConditionEdge.NONE,
            body=model.ByEntity(
                triggering_entities=names,
                rule=model.TriggeringEntitiesRule(rule),
                condition=model.SpeedCondition(value=1.0, rule=model.Rule.GREATER_THAN),
            ),
        )
        return model.Trigger(condition_groups=(model.ConditionGroup(conditions=(cond,)),))

    any_h = Harness(
        b.storyboard(
            b.event("E", start=speed_trigger("any", "fastA", "slowB")),
            actors=(),
            select_triggering=True,
        )
    )
    any_h.step()
    assert any_h.started == [(1.0, "E-action", ("fastA",))]
    all_h = Harness(b.storyboard(b.event("E", start=speed_trigger("all", "fastA", "slowB"))))
    all_h.step(3)
    assert all_h.started == []


def test_act_stop_trigger_and_storyboard_stop() -> None:
    h = Harness(
        b.storyboard(
            b.event("E", b.action("long")),
            act_stop=b.trigger((b.sim_time(2.5),)),
            stop=b.trigger((b.state("act", "A", "endTransition"),)),
        ),
        durations={"long": 100},
    )
    h.step(2)
    assert not h.runs[0].stopped and not h.board.complete
    # the act's stop trigger fires at t=3: the act ends (endTransition, as in esmini, so acts
    # waiting for its end start), the action still running under it is stopped, and the
    # storyboard's stop trigger sees the act's endTransition in that step
    h.step()
    assert h.runs[0].stopped and h.board.complete
    assert not h.board.is_in(
        model.StoryboardElementType.ACT, "A", model.StoryboardElementState.STOP_TRANSITION
    )


def test_completes_without_stop_trigger_only_when_stories_end() -> None:
    h = Harness(b.storyboard(b.event("E", b.action("x"))), durations={"x": 2})
    h.step()
    assert not h.board.complete
    h.step(2)
    assert h.board.complete
    blocked = Harness(b.storyboard(b.event("E"), stop=b.trigger((b.sim_time(100),))))
    blocked.step(5)
    assert not blocked.board.complete


def test_without_stories_or_stop_trigger_the_storyboard_runs_on() -> None:
    """A static scene (Init only, esmini's geo_pos/stationary_objects) never ends by itself
    under esmini's rules: esmini runs it to its time limit. ScenarioRunner ends it at once."""
    scene = model.Storyboard(init=model.Init(), stories=(), stop_trigger=None)
    h = Harness(scene)
    h.step(5)
    assert not h.board.complete
    carla = Storyboard(scene, raw=h.raw, start_action=h.start, scenario_runner=True)
    carla.update(0.05)
    carla.settle(0.05)
    assert carla.complete


def test_init_teleports_relative_to_later_entities_run_after_them() -> None:
    # esmini's ScenarioReader::parseInit: car0 placed relative to car1, car1 relative to car2,
    # car2 on a lane: the teleports run car2, car1, car0 (a chain resolved), the rest in order.
    def teleport(position: model.Position) -> model.TeleportAction:
        return model.TeleportAction(position=position)

    step = model.TransitionDynamics(
        shape=model.DynamicsShape.STEP, dimension=model.DynamicsDimension.TIME, value=0.0
    )
    speed = model.SpeedAction(dynamics=step, target=model.AbsoluteTargetSpeed(value=5.0))
    init = model.Init(
        private=(
            model.PrivateInit(
                entity_ref="car0",
                actions=(teleport(model.RelativeObjectPosition(entity_ref="car1", dx=-10, dy=0)),),
            ),
            model.PrivateInit(
                entity_ref="car1",
                actions=(
                    teleport(model.RelativeObjectPosition(entity_ref="car2", dx=-10, dy=0)),
                    speed,
                ),
            ),
            model.PrivateInit(
                entity_ref="car2",
                actions=(teleport(model.LanePosition(road_id="1", lane_id=-1, s=100)), speed),
            ),
        )
    )
    teleports = [e for e, a in init_order(init) if isinstance(a, model.TeleportAction)]
    assert teleports == ["car2", "car1", "car0"]
    assert [e for e, a in init_order(init) if isinstance(a, model.SpeedAction)] == ["car1", "car2"]
