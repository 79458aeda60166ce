"""The world: actors, the road network, simulated time, parameters and variables.

Actions, conditions and positions all read the world through this one object, so they agree on
what "the current lane of X" or "the state of X" means. Frozen per-step entity states are cached
(:meth:`World.refresh`) because conditions read them many times per step.
"""

from __future__ import annotations

import math
import random
from collections.abc import Iterable, Sequence

from simtest_operator.errors import ScenarioError
from simtest_operator.opendrive import RoadCoord, RoadNetwork, SignalIndex, traffic_controls
from simtest_operator.openscenario import model
from simtest_operator.sim.actors import Actor, Mode
from simtest_operator.sim.lanecache import LaneCache
from simtest_operator.sim.signal_controllers import SignalControllers
from simtest_operator.sim.trailers import Hitches
from simtest_operator.snapshots import Discontinuity, EntityState, JumpCause


class World:
    """Everything that changes during a run, plus the static road network."""

    __slots__ = (
        "_lanes",
        "_signal_index",
        "_states",
        "_undated",
        "actors",
        "discontinuities",
        "dt",
        "environments",
        "ghosts",
        "hitches",
        "ignored",
        "monitors",
        "parameters",
        "rng",
        "roads",
        "signal_controllers",
        "signals",
        "time",
        "traffic",
        "variables",
    )

    def __init__(
        self,
        *,
        roads: RoadNetwork | None,
        actors: Iterable[Actor],
        dt: float,
        seed: int,
        parameters: dict[str, model.ParameterValue],
        variables: dict[str, model.ParameterValue],
        controllers: Sequence[model.TrafficSignalController] = (),
    ) -> None:
        self.roads = roads
        self._lanes = LaneCache(roads) if roads is not None else None
        self.actors = {actor.name: actor for actor in actors}
        self.ghosts: frozenset[str] = frozenset()
        """esmini's ghost entities (:mod:`esmini_ghost`): recorded, but phantoms to everyone."""
        self.hitches = Hitches(actor.obj for actor in self.actors.values())
        """Which entity tows which (TrailerActions change it)."""
        self.dt = dt
        self.time = 0.0
        self.rng = random.Random(seed)
        self.parameters = parameters
        self.variables = variables
        self.ignored: list[str] = []
        self.signals: dict[str, str] = {}
        """Traffic signal states by signal name (as TrafficSignalStateActions and the
        controllers' phases set them)."""
        self.signal_controllers = SignalControllers(controllers, self.signals)
        self._signal_index: SignalIndex | None = None
        self.monitors: dict[str, bool] = {}
        """1.3 monitors by name: declared values, then as SetMonitorActions set them."""
        self.environments: list[tuple[float, model.Environment]] = []
        """Environments set by EnvironmentActions, with the time they were set (not rendered:
        recorded for the result)."""
        self.discontinuities: list[Discontinuity] = []
        """Jumps the scenario commanded, dated by the snapshot that first shows them (for the
        evidence checks, which excuse exactly these)."""
        self._undated: list[tuple[int, JumpCause]] = []
        self._states: dict[str, EntityState] = {}
        self.traffic: tuple[EntityState, ...] = ()
        """Vehicles the backend drives (anonymous traffic) as of the last step."""

    def declare(self, actor: Actor, cause: JumpCause) -> None:
        """Note that ``actor`` moves discontinuously on purpose; dated by :meth:`date_jumps`
        when the next snapshot is built (an action may start before or after time advances)."""
        self._undated.append((actor.id, cause))

    def date_jumps(self) -> None:
        """Date the jumps declared since the last snapshot with the time of the one being
        built."""
        self.discontinuities.extend(
            Discontinuity(time=self.time, entity=entity, cause=cause)
            for entity, cause in self._undated
        )
        self._undated.clear()

    def actor(self, name: str) -> Actor:
        try:
            return self.actors[name]
        except KeyError:
            raise ScenarioError(f"entity {name!r} is not declared", element="EntityRef") from None

    def state(self, name: str) -> EntityState:
        """Frozen state of ``name``: as of the last :meth:`freeze`, or as of its first read
        after the last :meth:`refresh`."""
        state = self._states.get(name)
        if state is None:
            state = self.actor(name).state()
            self._states[name] = state
        return state

    def states(self) -> tuple[EntityState, ...]:
        return tuple(self.state(name) for name, actor in self.actors.items() if actor.placed)

    def refresh(self) -> None:
        """Forget cached states after actors moved (cheap: an actor that did not change
        hands back the state it built last, see :meth:`Actor.state`)."""
        self._states.clear()

    def freeze(self) -> None:
        """Cache every placed actor's state as it is now: until the next refresh, whatever
        reads states sees this one instant, whichever actor has moved on meanwhile."""
        self._states.clear()
        self.states()

    # --- roads --------------------------------------------------------------------------------

    @property
    def signal_index(self) -> SignalIndex:
        """The map's traffic lights and stop signs by the lanes their stop lines cross (built
        on first use: only drivers that obey signals need it)."""
        if self._signal_index is None:
            controls = traffic_controls(self.roads) if self.roads is not None else ()
            self._signal_index = SignalIndex(controls)
        return self._signal_index

    def road_coord(self, x: float, y: float, heading: float | None = None) -> RoadCoord | None:
        if self.roads is None:
            return None
        return self.roads.to_road(x, y, heading=heading)

    def attach(self, actor: Actor) -> None:
        """Put ``actor`` into ROAD mode on the lane under it (whatever its heading, like esmini:
        it then moves along the lane in the direction its heading points to, keeping its angle);
        FREE mode off the road or without a road network."""
        coord = self.road_coord(actor.x, actor.y, actor.heading)
        if coord is None or not coord.on_road or coord.lane_id == 0:
            actor.mode = Mode.FREE
            return
        diff = math.remainder(actor.heading - coord.heading_of_road, 2.0 * math.pi)
        self.set_lane(
            actor,
            coord.road_id,
            coord.lane_id,
            coord.s,
            self.offset_in_lane(coord.road_id, coord.s, coord.lane_id, coord.t),
            direction=1 if abs(diff) <= math.pi / 2 else -1,
        )

    def offset_in_lane(self, road_id: str, s: float, lane_id: int, t: float) -> float:
        assert self.roads is not None
        bounds = self.roads.lane_bounds(road_id, s, lane_id)
        return t - bounds.t_center if bounds is not None else 0.0

    def set_lane(
        self, actor: Actor, road_id: str, lane_id: int, s: float, offset: float, *, direction: int
    ) -> None:
        """Put ``actor`` on a lane (ROAD mode) without moving it; its current heading becomes
        its heading relative to the lane."""
        assert self._lanes is not None
        actor.mode = Mode.ROAD
        actor.road_id = road_id
        actor.lane_id = lane_id
        actor.s = s
        actor.offset = offset
        actor.direction = direction
        actor.stuck = False
        frame = self._lanes.frame(road_id, s, lane_id, offset)
        lane_heading = frame[3]
        actor.stretch = frame[4]
        base = lane_heading if direction > 0 else lane_heading + math.pi
        actor.heading_offset = math.remainder(actor.heading - base, 2.0 * math.pi)

    def lane_t(self, road_id: str, s: float, lane_id: int) -> float:
        """t of a lane's centre at s (0 for the centre lane or a lane that does not exist)."""
        assert self._lanes is not None
        return self._lanes.lane_t(road_id, s, lane_id)

    def current_lane(self, actor: Actor) -> int:
        """The lane containing the actor's reference point (its logical lane while changing)."""
        if actor.mode is not Mode.ROAD or actor.road_id is None or self.roads is None:
            coord = self.road_coord(actor.x, actor.y, actor.heading)
            return coord.lane_id if coord is not None else 0
        t = self.lane_t(actor.road_id, actor.s, actor.lane_id) + actor.offset
        for bounds in self.roads.lanes_at(actor.road_id, actor.s):
            if bounds.lane_id != 0 and bounds.t_min <= t <= bounds.t_max and bounds.width > 0:
                return bounds.lane_id
        return actor.lane_id

    def pose_on_road(self, actor: Actor, lateral_angle: float = 0.0) -> None:
        """Recompute a ROAD-mode actor's pose from its lane coordinates."""
        assert self._lanes is not None and actor.road_id is not None
        x, y, z, heading, stretch = self._lanes.frame(
            actor.road_id, actor.s, actor.lane_id, actor.offset
        )
        actor.x, actor.y, actor.z = x, y, z
        actor.stretch = stretch
        base = heading if actor.direction > 0 else heading + math.pi
        actor.heading = math.remainder(base + actor.heading_offset + lateral_angle, 2.0 * math.pi)

    def neighbour_lane(
        self, road_id: str, s: float, lane_id: int, steps: int, direction: int
    ) -> int:
        """The lane ``steps`` lanes to the left (positive) of ``lane_id`` for a vehicle travelling
        in ``direction``, skipping the centre lane; clamped to existing lanes."""
        assert self.roads is not None
        ids = sorted(i for i in self.roads.lane_ids(road_id, s) if i != 0)
        if not ids:
            return lane_id
        # Left of travel is +t when moving along +s, so the lane list walks upwards.
        ordered = ids if direction > 0 else ids[::-1]
        try:
            index = ordered.index(lane_id)
        except ValueError:
            return lane_id
        return ordered[max(0, min(len(ordered) - 1, index + steps))]
