"""The scenario root and its storyboard hierarchy.

Storyboard -> Story -> Act -> ManeuverGroup -> Maneuver -> Event -> Action, with the triggers of
each level, mirrors the standard one to one so the engine can implement its state machine without
reinterpreting the file. Catalog references (maneuvers, entities, controllers, routes,
trajectories) are already resolved; parameters are already substituted with their final values.
"""

from __future__ import annotations

import dataclasses
import enum
from pathlib import Path

from simtest_operator.openscenario.deviations import Deviation
from simtest_operator.openscenario.model.actions import Action, GlobalAction, PrivateAction
from simtest_operator.openscenario.model.common import ParameterDeclaration, Unsupported
from simtest_operator.openscenario.model.entities import ScenarioObject
from simtest_operator.openscenario.model.monitors import MonitorDeclaration
from simtest_operator.openscenario.model.trigger_conditions import Criterion, Trigger


class Priority(enum.StrEnum):
    """Event priority. The pre-1.2 ``overwrite`` is normalised to OVERRIDE (same meaning)."""

    OVERRIDE = "override"
    PARALLEL = "parallel"
    SKIP = "skip"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class FileHeader:
    """The FileHeader: OpenSCENARIO revision and descriptive fields."""

    rev_major: int
    rev_minor: int
    date: str = ""
    description: str = ""
    author: str = ""
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Phase:
    """One phase of a traffic signal controller: ``duration`` seconds of the signal states
    ``states`` (``(trafficSignalId, state)``)."""

    name: str
    duration: float
    states: tuple[tuple[str, str], ...] = ()


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrafficSignalController:
    """A RoadNetwork ``TrafficSignalController``: its phases in cycle order; with a
    ``reference``, its first phase starts ``delay`` seconds after the referenced one's."""

    name: str
    phases: tuple[Phase, ...]
    delay: float = 0.0
    reference: str | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RoadNetwork:
    """The road network; ``logic_file`` is the absolute .xodr path, None for open space."""

    logic_file: Path | None = None
    controllers: tuple[TrafficSignalController, ...] = ()
    """The ``TrafficSignals`` controllers, cycling from the start of the run."""
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class PrivateInit:
    """Init actions for one entity."""

    entity_ref: str
    actions: tuple[PrivateAction, ...]
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Init:
    """Init actions, executed at time 0 before any story starts."""

    global_actions: tuple[GlobalAction, ...] = ()
    private: tuple[PrivateInit, ...] = ()
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Event:
    """An event: actions started together when its start trigger fires."""

    name: str
    priority: Priority
    maximum_execution_count: int
    actions: tuple[Action, ...]
    start_trigger: Trigger | None = None
    """None: starts as soon as its maneuver runs."""
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Maneuver:
    """A maneuver (inline or from a Maneuver catalog)."""

    name: str
    events: tuple[Event, ...]
    parameters: tuple[ParameterDeclaration, ...] = ()
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Actors:
    """Entities a maneuver group acts on."""

    select_triggering_entities: bool
    entity_refs: tuple[str, ...]
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ManeuverGroup:
    """Maneuvers executed by the same actors, up to ``maximum_execution_count`` times."""

    name: str
    maximum_execution_count: int
    actors: Actors
    maneuvers: tuple[Maneuver, ...]
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Act:
    """An act with its maneuver groups and triggers (start trigger None: starts immediately)."""

    name: str
    maneuver_groups: tuple[ManeuverGroup, ...]
    start_trigger: Trigger | None = None
    stop_trigger: Trigger | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Story:
    """A story: a set of acts."""

    name: str
    acts: tuple[Act, ...]
    parameters: tuple[ParameterDeclaration, ...] = ()
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Storyboard:
    """Init, stories and the storyboard stop trigger (None: never stops by itself)."""

    init: Init
    stories: tuple[Story, ...]
    stop_trigger: Trigger | None = None
    line: int | None = None

    @property
    def criteria(self) -> tuple[Criterion, ...]:
        """ScenarioRunner's ``criteria_<Test>`` conditions of every StopTrigger, the storyboard's
        first, then the acts' in document order (ScenarioRunner collects them from every
        StopTrigger under the storyboard: ``OpenScenario._create_test_criteria``)."""
        triggers = [self.stop_trigger] + [
            act.stop_trigger for story in self.stories for act in story.acts
        ]
        return tuple(c for trigger in triggers if trigger is not None for c in trigger.criteria)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Scenario:
    """A loaded OpenSCENARIO scenario, fully resolved."""

    path: Path
    """Absolute path of the .xosc file."""
    header: FileHeader
    parameters: tuple[ParameterDeclaration, ...]
    """Global parameters with final values (declarations, then caller overrides)."""
    variables: tuple[ParameterDeclaration, ...]
    """1.2+ VariableDeclarations with initial values."""
    monitors: tuple[MonitorDeclaration, ...] = ()
    """1.3 MonitorDeclarations with initial values (see :mod:`.monitors`)."""
    road_network: RoadNetwork
    entities: tuple[ScenarioObject, ...]
    storyboard: Storyboard
    unsupported_nodes: tuple[Unsupported, ...] = ()
    """Every Unsupported node anywhere in the model, in document order."""
    ignored_kinds: tuple[str, ...] = ()
    """Distinct element kinds present that are accepted but not simulated (IgnoredAction kinds,
    scene graph, ...), sorted."""
    notes: tuple[str, ...] = ()
    """Non-fatal remarks about the input (e.g. a parameter value kept as text because it does
    not fit its declared type), each naming file and line."""
    deviations: tuple[Deviation, ...] = ()
    """Deviations from the schema that were accepted with their clear meaning (``int`` for
    ``integer``, a heading in degrees, ...), in reading order; empty under strict mode, which
    refuses them."""
    line: int | None = None

    def unsupported(self) -> tuple[Unsupported, ...]:
        """All unsupported elements of the scenario (the engine reports those it reaches)."""
        return self.unsupported_nodes

    @property
    def criteria(self) -> tuple[Criterion, ...]:
        """ScenarioRunner's test criteria (see :attr:`Storyboard.criteria`)."""
        return self.storyboard.criteria

    def entity(self, name: str) -> ScenarioObject | None:
        """The entity called ``name``, or None."""
        for obj in self.entities:
            if obj.name == name:
                return obj
        return None

    def parameter(self, name: str) -> ParameterDeclaration | None:
        """The global parameter called ``name``, or None."""
        for decl in self.parameters:
            if decl.name == name:
                return decl
        return None

    def variable(self, name: str) -> ParameterDeclaration | None:
        """The variable called ``name``, or None."""
        for decl in self.variables:
            if decl.name == name:
                return decl
        return None
