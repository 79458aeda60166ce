"""Actions of the scenario model (a tagged union of frozen dataclasses).

Private actions apply to the actors of a maneuver group (or to the entity of an Init ``Private``);
global actions apply to the world. Actions the stand-in accepts but does not simulate (environment,
light state, visibility, appearance, animation) are :class:`IgnoredAction` so the engine can list
them in the result; actions it cannot run at all are :class:`~.common.Unsupported`.
"""

from __future__ import annotations

import dataclasses
import enum

from simtest_operator.openscenario.model import monitors
from simtest_operator.openscenario.model.common import (
    CoordinateSystem,
    ReferenceContext,
    Unsupported,
)
from simtest_operator.openscenario.model.controls import (
    ActivateControllerAction,
    AddEntityAction,
    AssignControllerAction,
    DeleteEntityAction,
    EnvironmentAction,
    IgnoredAction,
    ModifyValueAction,
    SetValueAction,
    TrafficSignalControllerAction,
    TrafficSignalStateAction,
)
from simtest_operator.openscenario.model.positions import Position, Route, Trajectory
from simtest_operator.openscenario.model.traffic import TrafficAction


class DynamicsShape(enum.StrEnum):
    """Shape of a transition over time/distance."""

    LINEAR = "linear"
    CUBIC = "cubic"
    SINUSOIDAL = "sinusoidal"
    STEP = "step"


class DynamicsDimension(enum.StrEnum):
    """What a transition's ``value`` measures: duration (s), distance (m) or rate (per s)."""

    TIME = "time"
    DISTANCE = "distance"
    RATE = "rate"


class FollowingMode(enum.StrEnum):
    """Trajectory/speed-profile following: exact position, or followed by a controller."""

    POSITION = "position"
    FOLLOW = "follow"


class SpeedTargetValueType(enum.StrEnum):
    """How a relative target speed combines with the reference entity's speed."""

    DELTA = "delta"
    FACTOR = "factor"


class LongitudinalDisplacement(enum.StrEnum):
    """Which side of the reference entity a distance action keeps (1.1+)."""

    ANY = "any"
    TRAILING = "trailingReferencedEntity"
    LEADING = "leadingReferencedEntity"


class LateralDisplacement(enum.StrEnum):
    """Which side of the reference entity a lateral distance action keeps (1.1+)."""

    ANY = "any"
    LEFT = "leftToReferencedEntity"
    RIGHT = "rightToReferencedEntity"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TransitionDynamics:
    """How a speed or lane change unfolds."""

    shape: DynamicsShape
    dimension: DynamicsDimension
    value: float
    following_mode: FollowingMode | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class DynamicConstraints:
    """Limits for distance-keeping and speed-profile actions."""

    max_acceleration: float | None = None
    max_deceleration: float | None = None
    max_speed: float | None = None
    max_acceleration_rate: float | None = None
    max_deceleration_rate: float | None = None
    line: int | None = None


# --- longitudinal -----------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class AbsoluteTargetSpeed:
    """Target speed in m/s."""

    value: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RelativeTargetSpeed:
    """Target speed relative to ``entity_ref``; ``continuous`` keeps tracking it afterwards."""

    entity_ref: str
    value: float
    value_type: SpeedTargetValueType
    continuous: bool
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SpeedAction:
    """Change speed to a target with a transition."""

    dynamics: TransitionDynamics
    target: AbsoluteTargetSpeed | RelativeTargetSpeed
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SpeedProfileEntry:
    """One speed-profile step: reach ``speed`` within ``time`` s (None: as fast as allowed)."""

    speed: float
    time: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SpeedProfileAction:
    """Follow a sequence of speeds (1.2); relative to ``entity_ref`` when given."""

    following_mode: FollowingMode
    entries: tuple[SpeedProfileEntry, ...]
    entity_ref: str | None = None
    constraints: DynamicConstraints | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LongitudinalDistanceAction:
    """Reach/keep a distance (m) or time gap (s) to ``entity_ref``."""

    entity_ref: str
    freespace: bool
    continuous: bool
    distance: float | None = None
    time_gap: float | None = None
    coordinate_system: CoordinateSystem = CoordinateSystem.ENTITY
    displacement: LongitudinalDisplacement = LongitudinalDisplacement.TRAILING
    constraints: DynamicConstraints | None = None
    line: int | None = None


# --- lateral ----------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class AbsoluteTargetLane:
    """Target lane by OpenDRIVE lane id."""

    lane_id: int
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RelativeTargetLane:
    """Target lane ``value`` lanes from ``entity_ref``'s lane (positive: left)."""

    entity_ref: str
    value: int
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LaneChangeAction:
    """Change lane with a lateral transition; end ``target_lane_offset`` from the lane centre."""

    dynamics: TransitionDynamics
    target: AbsoluteTargetLane | RelativeTargetLane
    target_lane_offset: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class AbsoluteTargetLaneOffset:
    """Target offset (m) from the current lane centre."""

    value: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RelativeTargetLaneOffset:
    """Target offset relative to ``entity_ref``'s lane offset."""

    entity_ref: str
    value: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LaneOffsetAction:
    """Move to a lateral offset within the lane."""

    continuous: bool
    shape: DynamicsShape
    target: AbsoluteTargetLaneOffset | RelativeTargetLaneOffset
    max_lateral_acc: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LateralDistanceAction:
    """Reach/keep a lateral distance to ``entity_ref``."""

    entity_ref: str
    freespace: bool
    continuous: bool
    distance: float | None = None
    coordinate_system: CoordinateSystem = CoordinateSystem.ENTITY
    displacement: LateralDisplacement = LateralDisplacement.ANY
    constraints: DynamicConstraints | None = None
    line: int | None = None


# --- position, routing, synchronisation -------------------------------------------------------


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TeleportAction:
    """Place the entity at ``position`` instantly."""

    position: Position
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TrailerAction:
    """1.3 ConnectTrailerAction (``trailer_ref`` set: hitch that entity) or
    DisconnectTrailerAction (``trailer_ref`` None: unhitch the current trailer)."""

    trailer_ref: str | None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class AssignRouteAction:
    """Give the entity a route to follow."""

    route: Route | Unsupported
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class AcquirePositionAction:
    """Route the entity to ``position`` from where it is."""

    position: Position
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Timing:
    """Trajectory time mapping, as the reference player reads it: the trajectory clock runs
    ``scale`` times as fast as simulation time (from the action start when relative) and the
    position is taken at clock + ``offset``."""

    domain: ReferenceContext
    scale: float
    offset: float
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class FollowTrajectoryAction:
    """Follow a trajectory; ``timing`` None means ignore the vertex times (TimeReference/None)."""

    trajectory: Trajectory | Unsupported
    following_mode: FollowingMode
    timing: Timing | None = None
    initial_distance_offset: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SteadyState:
    """Synchronize steady state: keep the final speed for a ``distance`` or ``time`` before."""

    distance: float | None = None
    time: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class AbsoluteFinalSpeed:
    """Synchronize final speed in m/s."""

    value: float
    steady_state: SteadyState | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RelativeFinalSpeed:
    """Synchronize final speed relative to the master entity."""

    value: float
    value_type: SpeedTargetValueType
    steady_state: SteadyState | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SynchronizeAction:
    """Arrive at ``target_position`` when the master arrives at ``target_position_master``."""

    master_entity_ref: str
    target_position_master: Position
    target_position: Position
    final_speed: AbsoluteFinalSpeed | RelativeFinalSpeed | None = None
    target_tolerance_master: float | None = None
    target_tolerance: float | None = None
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class RandomRouteAction:
    """Follow a random route from where the entity is (1.3, no attributes)."""

    line: int | None = None


PrivateAction = (
    TeleportAction
    | SpeedAction
    | SpeedProfileAction
    | LongitudinalDistanceAction
    | LaneChangeAction
    | LaneOffsetAction
    | LateralDistanceAction
    | AssignRouteAction
    | RandomRouteAction
    | AcquirePositionAction
    | FollowTrajectoryAction
    | SynchronizeAction
    | ActivateControllerAction
    | AssignControllerAction
    | TrailerAction
    | IgnoredAction
    | Unsupported
)
"""Private actions; an OverrideControllerValueAction alone is an IgnoredAction."""

GlobalAction = (
    SetValueAction
    | ModifyValueAction
    | TrafficSignalStateAction
    | TrafficSignalControllerAction
    | TrafficAction
    | AddEntityAction
    | DeleteEntityAction
    | EnvironmentAction
    | monitors.SetMonitorAction
    | IgnoredAction
    | Unsupported
)
"""Global actions; TrafficArea actions are Unsupported, UserDefined ones IgnoredActions."""

AnyAction = PrivateAction | GlobalAction


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Action:
    """A named storyboard action wrapping one private or global action."""

    name: str
    body: AnyAction
    is_private: bool
    """True for a PrivateAction (applies to each actor), False for a global/user-defined one."""
    line: int | None = None
