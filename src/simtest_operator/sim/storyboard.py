"""The storyboard state machine (OpenSCENARIO 1.x, chapter "Storyboard and entities").

Every element (story, act, maneuver group, maneuver, event, action) is in ``standby``,
``running`` or ``complete`` and moves through ``startTransition``, ``endTransition``,
``stopTransition`` and ``skipTransition``. One :meth:`Storyboard.update` per step evaluates the
triggers that matter in the current states (storyboard stop trigger, act start/stop triggers, event
start triggers) and starts or stops elements; after the engine advanced the running actions,
:meth:`Storyboard.settle` propagates completions upwards (action -> event -> maneuver -> maneuver
group -> act -> story -> storyboard).

Transitions are events, not states: one that happens during step k is visible to the
StoryboardElementStateConditions evaluated after it in step k and in step k+1, then it is gone.
So an event waiting for its act's startTransition starts in the same step as the act, and an
event waiting for another's endTransition starts in the step after it ended -- the timing the
reference player (esmini) shows on the development corpus.

Event priorities apply within the event's maneuver: ``override`` (1.0 ``overwrite``) stops the
other running events, ``skip`` does not start while another event runs, ``parallel`` just starts.
Under ScenarioRunner's rules priorities are not applied: ScenarioRunner runs the events of a
maneuver side by side (a parallel composite) and never reads the attribute; and its
StoryboardElementStateCondition knows one end of an element, so ``endTransition`` and
``stopTransition`` both see an element end however it ended. Its storyboard StopTrigger stops
nothing (ScenarioRunner reads only the criteria out of it): the run ends with the stories; an
act's StopTrigger fires on any one of its conditions.
An event or maneuver group that ended with executions left goes back to standby (maneuver group:
restarts at once) until ``maximumExecutionCount`` is used up.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Collection, Iterator, Sequence
from typing import Protocol

from simtest_operator.openscenario import model
from simtest_operator.sim.triggers import RawCondition, TriggerState

Kind = model.StoryboardElementType
Transition = model.StoryboardElementState


_ENDINGS = (Transition.END_TRANSITION, Transition.STOP_TRANSITION)


class Phase(enum.StrEnum):
    """The three states of a storyboard element."""

    STANDBY = "standbyState"
    RUNNING = "runningState"
    COMPLETE = "completeState"


class ActionRun(Protocol):
    """One running instance of an action on one actor (or the world), owned by the engine."""

    @property
    def finished(self) -> bool:
        """True once the action reached its goal or was stopped."""

    @property
    def stopped(self) -> bool:
        """True when it ended by being stopped or overridden rather than by reaching its goal."""

    def cancel(self) -> None:
        """Stop the action now (its element takes a stopTransition)."""


ActionStarter = Callable[[model.Action, tuple[str, ...]], Sequence[ActionRun]]
"""Starts an action for the given actors (empty for global actions) and returns its runs."""


class Node:
    """Runtime state of one storyboard element."""

    __slots__ = (
        "actors",
        "children",
        "executions",
        "kind",
        "max_executions",
        "name",
        "phase",
        "runs",
        "source",
        "start",
        "stop",
    )

    def __init__(
        self,
        kind: Kind,
        name: str,
        source: object,
        *,
        children: Sequence[Node] = (),
        start: model.Trigger | None = None,
        stop: model.Trigger | None = None,
        max_executions: int = 1,
        level: bool = False,
    ) -> None:
        self.kind = kind
        self.name = name
        self.source = source
        self.children = tuple(children)
        self.phase = Phase.STANDBY
        # An empty <StartTrigger/> starts at once, as if it were absent (esmini does the same);
        # an empty stop trigger never fires.
        self.start = TriggerState(
            start if start is not None and start.condition_groups else None, level=level
        )
        self.stop = (
            TriggerState(stop, level=level, any_condition=level and kind is Kind.ACT)
            if stop is not None
            else None
        )
        self.executions = 0
        self.max_executions = max(1, max_executions)
        self.runs: tuple[ActionRun, ...] = ()
        self.actors: tuple[str, ...] = ()

    def walk(self) -> Iterator[Node]:
        yield self
        for child in self.children:
            yield from child.walk()


def _build_event(event: model.Event, level: bool) -> Node:
    actions = [Node(Kind.ACTION, a.name, a) for a in event.actions]
    return Node(
        Kind.EVENT,
        event.name,
        event,
        children=actions,
        start=event.start_trigger,
        max_executions=event.maximum_execution_count,
        level=level,
    )


def _build_story(story: model.Story, level: bool) -> Node:
    acts = []
    for act in story.acts:
        groups = []
        for group in act.maneuver_groups:
            maneuvers = [
                Node(Kind.MANEUVER, m.name, m, children=[_build_event(e, level) for e in m.events])
                for m in group.maneuvers
            ]
            groups.append(
                Node(
                    Kind.MANEUVER_GROUP,
                    group.name,
                    group,
                    children=maneuvers,
                    max_executions=group.maximum_execution_count,
                )
            )
        acts.append(
            Node(
                Kind.ACT,
                act.name,
                act,
                children=groups,
                start=act.start_trigger,
                stop=act.stop_trigger,
                level=level,
            )
        )
    return Node(Kind.STORY, story.name, story, children=acts)


class Storyboard:
    """Runs the storyboard's stories; the engine runs Init actions itself before the first step."""

    __slots__ = (
        "_by_name",
        "_complete",
        "_end_with_stories",
        "_fired",
        "_pending",
        "_raw",
        "_scenario_runner",
        "_start_action",
        "_stop",
        "_stop_defined",
        "_stories",
        "_visible",
    )

    def __init__(
        self,
        storyboard: model.Storyboard,
        *,
        raw: RawCondition,
        start_action: ActionStarter,
        scenario_runner: bool = False,
    ) -> None:
        self._raw = raw
        self._start_action = start_action
        self._scenario_runner = scenario_runner
        self._stories = tuple(_build_story(story, scenario_runner) for story in storyboard.stories)
        stop = storyboard.stop_trigger
        self._stop = TriggerState(stop, level=scenario_runner)
        # A stop trigger that held only ScenarioRunner criteria is no stop trigger; under
        # ScenarioRunner's rules none is: it reads only the criteria out of the storyboard's
        # StopTrigger (OpenScenario._create_test_criteria) and builds no stop from its conditions.
        self._stop_defined = (
            stop is not None
            and bool(stop.condition_groups or not stop.criteria)
            and not scenario_runner
        )
        # ScenarioRunner ends a scenario when its stories are done (or at its timeout).
        # Without a stop trigger esmini ends the storyboard when its stories are done, but one
        # with no story (a static scene) never ends by itself: it runs to the time limit.
        self._end_with_stories = scenario_runner or (not self._stop_defined and bool(self._stories))
        self._complete = False
        self._fired: list[tuple[Node, Node, Node, frozenset[str]]] = []
        self._visible: set[tuple[Node, Transition]] = set()
        self._pending: set[tuple[Node, Transition]] = set()
        self._by_name: dict[tuple[Kind, str], list[Node]] = {}
        for story in self._stories:
            self._index(story, ())
        for story in self._stories:
            story.phase = Phase.RUNNING
            self._pending.add((story, Transition.START_TRANSITION))

    def _index(self, node: Node, parents: tuple[str, ...]) -> None:
        """Register ``node`` by its name and by every ``Parent::...::Name`` suffix of its path
        (esmini's way to tell apart elements with the same name)."""
        path = (*parents, node.name)
        for k in range(len(path)):
            self._by_name.setdefault((node.kind, "::".join(path[k:])), []).append(node)
        for child in node.children:
            self._index(child, path)

    @property
    def complete(self) -> bool:
        """True once the stop trigger fired (or, without one or under ScenarioRunner's rules,
        every story completed; without stop trigger and stories, never under esmini's rules)."""
        return self._complete

    def nodes(self) -> Iterator[Node]:
        for story in self._stories:
            yield from story.walk()

    # --- queries for StoryboardElementStateCondition ------------------------------------------

    def is_in(self, kind: Kind, name: str, state: Transition) -> bool:
        """Whether an element called ``name`` is in ``state`` or just passed that transition."""
        nodes = self._by_name.get((kind, name), ())
        if state in (Transition.STANDBY_STATE, Transition.RUNNING_STATE, Transition.COMPLETE_STATE):
            return any(node.phase.value == state.value for node in nodes)
        # by node: a reference qualified with its parents (``Event::Action``) names one node of
        # several that share the plain name
        if self._scenario_runner and state in _ENDINGS:
            # ScenarioRunner knows one end of an element, however it came (its END rule).
            return any((node, ending) in self._visible for node in nodes for ending in _ENDINGS)
        return any((node, state) in self._visible for node in nodes)

    def known(self, kind: Kind, name: str) -> bool:
        return (kind, name) in self._by_name

    # --- stepping -----------------------------------------------------------------------------

    def update(self, now: float) -> None:
        """Evaluate triggers at ``now`` and start/stop elements accordingly."""
        self._visible = set(self._pending)
        self._pending = set()
        if self._complete:
            return
        for story in self._stories:
            if story.phase is not Phase.RUNNING:
                continue
            for act in story.children:
                self._update_act(now, act)
        self._start_fired()

    def rearm(self, events: Collection[str]) -> None:
        """Set the completed events of these names back to standby with no executions (esmini
        does so when its ghost restarts, for the events that teleported the ghost)."""
        for node in self.nodes():
            if node.kind is Kind.EVENT and node.name in events and node.phase is Phase.COMPLETE:
                node.phase = Phase.STANDBY
                node.executions = 0
                node.start.reset()

    def _update_act(self, now: float, act: Node) -> None:
        if act.phase is Phase.STANDBY:
            fired, _ = act.start.evaluate(now, self._raw)
            if fired:
                self._begin(act)
                for group in act.children:
                    self._begin_group(group)
        if act.phase is not Phase.RUNNING:
            return
        if act.stop is not None and act.stop.evaluate(now, self._raw)[0]:
            # The act's own stop trigger ends it (endTransition, as in esmini); what still runs
            # under it is stopped.
            self._halt(act, Transition.END_TRANSITION)
            return
        for group in act.children:
            if group.phase is not Phase.RUNNING:
                continue
            for maneuver in group.children:
                if maneuver.phase is Phase.RUNNING:
                    self._update_events(now, group, maneuver)

    def _update_events(self, now: float, group: Node, maneuver: Node) -> None:
        for event in maneuver.children:
            if event.phase is not Phase.STANDBY:
                continue
            fired, who = event.start.evaluate(now, self._raw)
            if fired:
                self._fired.append((group, maneuver, event, who))

    def _start_fired(self) -> None:
        """Start the events whose triggers fired this update, after all were evaluated (so one
        event's actions cannot hide another's trigger in the same step)."""
        fired, self._fired = self._fired, []
        for group, maneuver, event, who in fired:
            if event.phase is not Phase.STANDBY:
                continue
            source = event.source
            assert isinstance(source, model.Event)
            running = [e for e in maneuver.children if e is not event and e.phase is Phase.RUNNING]
            if not self._scenario_runner and source.priority is model.Priority.SKIP and running:
                self._transition(event, Transition.SKIP_TRANSITION)
                continue
            if not self._scenario_runner and source.priority is model.Priority.OVERRIDE:
                for other in running:
                    self._halt(other)
            self._start_event(event, self._actors(group, who))

    def _actors(self, group: Node, triggering: frozenset[str]) -> tuple[str, ...]:
        source = group.source
        assert isinstance(source, model.ManeuverGroup)
        actors = list(source.actors.entity_refs)
        if source.actors.select_triggering_entities:
            actors += sorted(name for name in triggering if name not in actors)
        return tuple(actors)

    def _start_event(self, event: Node, actors: tuple[str, ...]) -> None:
        self._begin(event)
        event.executions += 1
        for action in event.children:
            self._begin(action)
            source = action.source
            assert isinstance(source, model.Action)
            action.actors = actors if source.is_private else ()
            action.runs = tuple(self._start_action(source, action.actors))

    def _transition(self, node: Node, transition: Transition) -> None:
        key = (node, transition)
        self._pending.add(key)
        self._visible.add(key)

    def _begin(self, node: Node) -> None:
        node.phase = Phase.RUNNING
        self._transition(node, Transition.START_TRANSITION)

    def _begin_group(self, group: Node) -> None:
        self._begin(group)
        group.executions += 1
        for maneuver in group.children:
            self._begin(maneuver)
            for event in maneuver.children:
                event.phase = Phase.STANDBY
                event.executions = 0
                event.start.reset()

    def _halt(self, node: Node, transition: Transition = Transition.STOP_TRANSITION) -> None:
        """Stop ``node`` (with ``transition``) and everything under it that has not completed
        yet."""
        for child in node.children:
            if child.phase is not Phase.COMPLETE:
                self._halt(child)
        for run in node.runs:
            if not run.finished:
                run.cancel()
        node.phase = Phase.COMPLETE
        self._transition(node, transition)

    def _end(self, node: Node) -> None:
        node.phase = Phase.COMPLETE
        self._transition(node, Transition.END_TRANSITION)

    # --- completion ---------------------------------------------------------------------------

    def settle(self, now: float) -> None:
        """Propagate completions after the engine advanced the running actions to ``now``, then
        evaluate the storyboard stop trigger on that new state (so the run ends at the time the
        trigger fires, not one step later)."""
        if self._complete:
            return
        self._settle_stories()
        if self._stop_defined and self._stop.evaluate(now, self._raw)[0]:
            for story in self._stories:
                self._halt(story)
            self._complete = True

    def _settle_stories(self) -> None:
        for story in self._stories:
            if story.phase is not Phase.RUNNING:
                continue
            for act in story.children:
                if act.phase is Phase.RUNNING:
                    self._settle_act(act)
            if all(act.phase is Phase.COMPLETE for act in story.children):
                self._end(story)
        if self._end_with_stories and all(s.phase is Phase.COMPLETE for s in self._stories):
            self._complete = True

    def _settle_act(self, act: Node) -> None:
        for group in act.children:
            if group.phase is not Phase.RUNNING:
                continue
            for maneuver in group.children:
                if maneuver.phase is Phase.RUNNING:
                    self._settle_maneuver(maneuver)
            if all(m.phase is Phase.COMPLETE for m in group.children):
                self._end(group)
                if group.executions < group.max_executions:
                    self._begin_group(group)
        if all(group.phase is Phase.COMPLETE for group in act.children):
            self._end(act)

    def _settle_maneuver(self, maneuver: Node) -> None:
        for event in maneuver.children:
            if event.phase is not Phase.RUNNING:
                continue
            for action in event.children:
                if action.phase is Phase.RUNNING and all(run.finished for run in action.runs):
                    if any(run.stopped for run in action.runs):
                        action.phase = Phase.COMPLETE
                        self._transition(action, Transition.STOP_TRANSITION)
                    else:
                        self._end(action)
            if all(action.phase is Phase.COMPLETE for action in event.children):
                self._end(event)
                if event.executions < event.max_executions:
                    event.phase = Phase.STANDBY
                    event.start.reset()
        if all(event.phase is Phase.COMPLETE for event in maneuver.children):
            self._end(maneuver)
