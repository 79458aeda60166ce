"""Trailers: which entity tows which, and the towed entities' poses.

As in esmini, a trailer is an entity of its own (an inline ``Trailer`` is the entity
``<tractor>+``) whose pose its tow vehicle decides: its coupler point (``TrailerCoupler dx``
ahead of its reference point) sits on the tow vehicle's hitch point (``TrailerHitch dx``).
Each step, after the tow vehicle moved, the trailer is pulled: it turns about its coupler towards
the hitch, keeping the coupler distance, so it follows the tow vehicle's path with the off-tracking
of an articulated vehicle; it takes the tow vehicle's speed. A teleported tow vehicle lines its
trailers up straight behind it; a towed entity ignores its own teleports. Connecting a trailer at
run time does not move it: the next pull swings it onto the hitch.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import model
from simtest_operator.sim.actors import Actor

_MAX_CHAIN = 100
"""Trailers behind one tow vehicle at most (esmini's limit; a loop of references ends here)."""


class Hitches:
    """The tow vehicle -> trailer links of a run (changed by TrailerActions)."""

    __slots__ = ("_towed", "_towing")

    def __init__(self, objects: Iterable[model.ScenarioObject]) -> None:
        self._towed: dict[str, str] = {}
        """Tow vehicle name -> trailer name."""
        self._towing: dict[str, str] = {}
        """Trailer name -> tow vehicle name."""
        by_name = {obj.name: obj for obj in objects}
        for obj in by_name.values():
            if obj.trailer is not None:
                self.connect(obj, by_name[obj.trailer])

    def connect(self, tractor: model.ScenarioObject, trailer: model.ScenarioObject) -> None:
        """Hitch ``trailer`` to ``tractor`` (replacing its trailer and the trailer's tow)."""
        if tractor.trailer_hitch is None:
            raise ScenarioError(f"{tractor.name!r} has no TrailerHitch to tow {trailer.name!r}")
        if trailer.trailer_coupler is None:
            raise ScenarioError(f"{trailer.name!r} has no TrailerCoupler to be towed")
        if trailer.name == tractor.name:
            raise ScenarioError(f"{tractor.name!r} cannot tow itself")
        self.disconnect(tractor.name)
        former = self._towing.get(trailer.name)
        if former is not None:
            self.disconnect(former)
        self._towed[tractor.name] = trailer.name
        self._towing[trailer.name] = tractor.name

    def disconnect(self, tractor: str) -> None:
        """Unhitch ``tractor``'s trailer (nothing when it has none)."""
        trailer = self._towed.pop(tractor, None)
        if trailer is not None:
            del self._towing[trailer]

    def towed(self, name: str) -> bool:
        """Whether ``name`` is a trailer hitched to something."""
        return name in self._towing

    def coupled(self, first: str, second: str) -> bool:
        """Whether the two entities are hitched to each other (their boxes may overlap)."""
        return self._towed.get(first) == second or self._towed.get(second) == first

    def chain(self, tractor: str) -> list[str]:
        """The trailers behind ``tractor``, nearest first."""
        names: list[str] = []
        current = self._towed.get(tractor)
        while current is not None and current != tractor and len(names) < _MAX_CHAIN:
            names.append(current)
            current = self._towed.get(current)
        return names

    def leaders(self) -> list[str]:
        """Tow vehicles that are not towed themselves."""
        return [name for name in self._towed if name not in self._towing]


def hitch_point(tractor: Actor) -> tuple[float, float]:
    dx = tractor.obj.trailer_hitch or 0.0
    return tractor.x + dx * math.cos(tractor.heading), tractor.y + dx * math.sin(tractor.heading)


def align(actors: dict[str, Actor], hitches: Hitches, tractor: Actor) -> list[Actor]:
    """Line ``tractor``'s trailers up straight behind it (after it was teleported); returns
    them. esmini turns every trailer of the chain to the tow vehicle's heading."""
    placed: list[Actor] = []
    front = tractor
    for name in hitches.chain(tractor.name):
        trailer = actors[name]
        hx, hy = hitch_point(front)
        dx = trailer.obj.trailer_coupler or 0.0
        trailer.heading = tractor.heading
        trailer.x = hx - dx * math.cos(tractor.heading)
        trailer.y = hy - dx * math.sin(tractor.heading)
        trailer.z = tractor.z
        trailer.speed = tractor.speed
        trailer.placed = True
        placed.append(trailer)
        front = trailer
    return placed


def pull(actors: dict[str, Actor], hitches: Hitches) -> list[Actor]:
    """Pull every placed chain's trailers after their tow vehicles moved; returns them."""
    moved: list[Actor] = []
    for leader in hitches.leaders():
        front = actors[leader]
        if not front.placed:
            continue
        for name in hitches.chain(leader):
            trailer = actors[name]
            hx, hy = hitch_point(front)
            vx, vy = trailer.x - hx, trailer.y - hy
            length = math.hypot(vx, vy)
            if length > 0.0:
                scale = (trailer.obj.trailer_coupler or 0.0) / length
                vx, vy = vx * scale, vy * scale
                trailer.heading = math.remainder(math.atan2(vy, vx) + math.pi, 2.0 * math.pi)
            trailer.x, trailer.y, trailer.z = hx + vx, hy + vy, front.z
            trailer.speed = front.speed
            trailer.placed = True
            moved.append(trailer)
            front = trailer
    return moved
