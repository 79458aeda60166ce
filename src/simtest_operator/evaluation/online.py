"""Online evaluation: criteria checked on every world snapshot while the simulation runs.

The evaluator is fed snapshots one by one (by the runner, which also feeds the recorder), keeps
running minima/maxima and the first violation of each criterion, and at the end turns them plus the
engine's facts (storyboard complete? unsupported element?) into a verdict with a one-line reason.
It never looks at the simulator: off-road knowledge comes in as a callable from the engine.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

from simtest_operator import geometry
from simtest_operator.evaluation.carla_criteria import Outcome, ScenarioCriteria
from simtest_operator.evaluation.criteria import Criteria
from simtest_operator.snapshots import BoundingBox, EntityState, WorldSnapshot

OffRoadCheck = Callable[[EntityState], bool]
CoupledCheck = Callable[[str, str], bool]
"""Whether two entities are hitched together (a trailer and its tow vehicle)."""
"""True when the entity's reference point is off the drivable road."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Violation:
    """The first time one criterion was violated."""

    criterion: str
    time: float
    message: str


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Collision:
    """Two entities whose boxes touched; ``time`` is the first instant."""

    first: str
    second: str
    time: float


def _centre_radius(state: EntityState) -> float:
    """Radius around the box centre that contains the whole box."""
    return math.hypot(state.box.length, state.box.width) / 2.0


class OnlineEvaluator:
    """Accumulates metrics and violations over a run for one ego."""

    __slots__ = (
        "_collided",
        "_collisions",
        "_coupled",
        "_criteria",
        "_ego",
        "_max_decel",
        "_min_distance",
        "_min_thw",
        "_min_ttc",
        "_off_road",
        "_radii",
        "_scenario_criteria",
        "_steps",
        "_violations",
    )

    def __init__(
        self,
        criteria: Criteria,
        *,
        ego: str | None,
        off_road: OffRoadCheck | None = None,
        coupled: CoupledCheck | None = None,
        scenario_criteria: ScenarioCriteria | None = None,
    ) -> None:
        self._criteria = criteria
        self._scenario_criteria = scenario_criteria
        """The scenario's own tests (CARLA ScenarioRunner ``criteria_*``), judged alongside."""
        self._ego = ego
        self._off_road = off_road
        self._coupled = coupled
        """Hitched pairs touch by design: neither a collision nor a distance to keep."""
        self._violations: dict[str, Violation] = {}
        self._collisions: list[Collision] = []
        self._collided: set[tuple[str, str]] = set()
        self._min_ttc = math.inf
        self._min_thw = math.inf
        self._min_distance = math.inf
        self._max_decel = 0.0
        self._steps = 0
        self._radii: dict[str, tuple[BoundingBox, float]] = {}

    def _radius_of(self, state: EntityState) -> float:
        cached = self._radii.get(state.name)
        if cached is None or cached[0] is not state.box:
            cached = (state.box, _centre_radius(state))
            self._radii[state.name] = cached
        return cached[1]

    @property
    def criteria(self) -> Criteria:
        return self._criteria

    @property
    def violations(self) -> tuple[Violation, ...]:
        """First violation of each criterion, in the order they happened."""
        return tuple(sorted(self._violations.values(), key=lambda v: v.time))

    @property
    def collisions(self) -> tuple[Collision, ...]:
        """Every pair of entities that touched (not only the ego), first contact each."""
        return tuple(self._collisions)

    @property
    def scenario_criteria(self) -> ScenarioCriteria | None:
        return self._scenario_criteria

    def criterion_outcomes(self) -> tuple[Outcome, ...]:
        """Outcomes of the scenario's own criteria so far (empty without any)."""
        if self._scenario_criteria is None:
            return ()
        ego = self._ego
        hits = [
            (c.second if c.first == ego else c.first, c.time)
            for c in self._collisions
            if ego in (c.first, c.second)
        ]
        return self._scenario_criteria.outcomes(ego=ego, collided_with=hits)

    def observe(self, snapshot: WorldSnapshot) -> None:
        """Update metrics and violations with one snapshot."""
        self._steps += 1
        entities = snapshot.entities
        radii = [self._radius_of(state) for state in entities]
        centres = [state.box_center() for state in entities]
        self._check_collisions(snapshot.time, entities, radii, centres)
        ego = snapshot.entity(self._ego) if self._ego is not None else None
        if self._scenario_criteria is not None:
            self._scenario_criteria.observe(snapshot.time, ego, snapshot.signals)
        if ego is None:
            return
        ego_radius = self._radius_of(ego)
        cos_h, sin_h = math.cos(ego.heading), math.sin(ego.heading)
        ego_x, ego_y, _ = ego.box_center()
        half_width = ego.box.width / 2.0
        for other, radius, centre in zip(entities, radii, centres, strict=True):
            if other is ego or self._hitched(ego.name, other.name):
                continue
            other_x, other_y, _ = centre
            centre_gap = math.hypot(other_x - ego_x, other_y - ego_y) - ego_radius - radius
            if centre_gap < self._min_distance:
                self._min_distance = min(self._min_distance, geometry.box_distance(ego, other))
            # Cheap bounding-circle test in the ego frame before the exact in-path geometry.
            ahead = (other_x - ego_x) * cos_h + (other_y - ego_y) * sin_h
            across = -(other_x - ego_x) * sin_h + (other_y - ego_y) * cos_h
            if ahead + radius <= 0.0 or abs(across) >= half_width + radius:
                continue
            gap = geometry.gap_ahead(ego, other)
            if gap is None:
                continue
            if ego.speed > 0.0:
                self._min_thw = min(self._min_thw, gap / ego.speed)
            evx, evy = ego.velocity()
            ovx, ovy = other.velocity()
            closing = (evx - ovx) * cos_h + (evy - ovy) * sin_h
            if closing > 0.0:
                self._min_ttc = min(self._min_ttc, gap / closing)
        self._max_decel = max(self._max_decel, -ego.acceleration)
        self._check_thresholds(snapshot.time, ego)

    def _check_collisions(
        self,
        time: float,
        entities: tuple[EntityState, ...],
        radii: list[float],
        centres: list[tuple[float, float, float]],
    ) -> None:
        count = len(entities)
        for i in range(count):
            xi, yi, _ = centres[i]
            ri = radii[i]
            for j in range(i + 1, count):
                xj, yj, _ = centres[j]
                reach = ri + radii[j]
                dx, dy = xj - xi, yj - yi
                if dx * dx + dy * dy > reach * reach:
                    continue  # bounding circles apart: no contact possible
                first, second = entities[i], entities[j]
                pair = (first.name, second.name)
                if pair in self._collided or self._hitched(*pair):
                    continue
                if not geometry.boxes_overlap(first, second):
                    continue
                self._collided.add(pair)
                self._collisions.append(Collision(first=pair[0], second=pair[1], time=time))
                if self._criteria.collision and self._ego in pair:
                    other = pair[1] if pair[0] == self._ego else pair[0]
                    self._violate("collision", time, f"{self._ego} collided with {other}")

    def _hitched(self, first: str, second: str) -> bool:
        return self._coupled is not None and self._coupled(first, second)

    def _check_thresholds(self, time: float, ego: EntityState) -> None:
        criteria = self._criteria
        if criteria.min_ttc is not None and self._min_ttc < criteria.min_ttc:
            self._violate(
                "minTTC", time, f"time to collision {self._min_ttc:.2f} s < {criteria.min_ttc:g} s"
            )
        if criteria.min_thw is not None and self._min_thw < criteria.min_thw:
            self._violate(
                "minTHW", time, f"time headway {self._min_thw:.2f} s < {criteria.min_thw:g} s"
            )
        if criteria.max_decel is not None and self._max_decel > criteria.max_decel:
            self._violate(
                "maxDecel",
                time,
                f"deceleration {self._max_decel:.2f} m/s^2 > {criteria.max_decel:g} m/s^2",
            )
        if criteria.off_road and self._off_road is not None and self._off_road(ego):
            where = f"({ego.x:.1f}, {ego.y:.1f})"
            self._violate("offRoad", time, f"{ego.name} left the road at {where}")

    def _violate(self, criterion: str, time: float, message: str) -> None:
        if criterion not in self._violations:
            self._violations[criterion] = Violation(
                criterion=criterion, time=time, message=f"{message} at t={time:.2f} s"
            )

    def metrics(self) -> dict[str, float]:
        """Running metrics of the ego; a metric that never got a finite value is left out."""
        values = {
            "minTTC": self._min_ttc,
            "minTHW": self._min_thw,
            "minDistance": self._min_distance,
            "maxDecel": self._max_decel if self._steps else math.inf,
        }
        return {key: round(value, 4) for key, value in values.items() if math.isfinite(value)}
