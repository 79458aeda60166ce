"""Lane connectivity: which lane continues where, across lane sections, road links and junctions.

Movement along a lane past the end of a road (RelativeLanePosition ``ds``, routes, lane-following
drivers) needs the lane graph. OpenDRIVE spreads it over road links, lane links and junction
connections, and real files often declare a link on one side only, so the graph is built from every
declaration and made symmetric: if leaving road A at its end in lane -1 enters road B at its start
in lane -1, then leaving B at its start in lane -1 enters A at its end in lane -1.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from simtest_operator.opendrive import models


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LaneEntry:
    """Entering road ``road_id`` through its ``contact_point`` end, in lane ``lane_id``.

    Entering at ``START`` means travelling towards increasing s on that road; at ``END``, towards
    decreasing s.
    """

    road_id: str
    lane_id: int
    contact_point: models.ContactPoint


_EndKey = tuple[str, int, models.ContactPoint]


def _end_section(road: models.Road, end: models.ContactPoint) -> models.LaneSection:
    return road.lane_sections[0] if end is models.ContactPoint.START else road.lane_sections[-1]


def _default_lane(lane_id: int, end: models.ContactPoint, contact: models.ContactPoint) -> int:
    """Lane id continuing ``lane_id`` when no lane link says so: roads joined end-to-start keep
    their ids; roads joined end-to-end or start-to-start face each other and swap sides."""
    return lane_id if end is not contact else -lane_id


class LaneGraph:
    """Undirected lane connectivity between road ends."""

    __slots__ = ("_edges", "_neighbours", "_roads")

    def __init__(self, document: models.OpenDrive) -> None:
        self._roads: dict[str, models.Road] = {road.id: road for road in document.roads}
        self._edges: dict[_EndKey, list[LaneEntry]] = {}
        junctions = {junction.id: junction for junction in document.junctions}
        # Declared lane links first: a lane without one is linked by its id only where the
        # other road's lane does not declare a different partner (a lane that opens from 0 m
        # wide beside the declared one must not take its traffic).
        for guessing in (False, True):
            for road in document.roads:
                for end in models.ContactPoint:
                    link = road.predecessor if end is models.ContactPoint.START else road.successor
                    if link is None:
                        continue
                    if link.element_type is models.ElementType.ROAD:
                        self._link_roads(road, end, link, guessing=guessing)
                    elif link.element_id in junctions and not guessing:
                        self._link_junction(road, end, junctions[link.element_id])
        neighbours: dict[str, set[str]] = {}
        for (road_id, _, _), entries in self._edges.items():
            neighbours.setdefault(road_id, set()).update(entry.road_id for entry in entries)
        self._neighbours = {key: frozenset(value) for key, value in neighbours.items()}

    @property
    def roads(self) -> Mapping[str, models.Road]:
        return self._roads

    def _add(self, key: _EndKey, entry: LaneEntry) -> None:
        """Record both directions of one lane-to-lane connection (once each)."""
        forward = self._edges.setdefault(key, [])
        if entry not in forward:
            forward.append(entry)
        back_key = (entry.road_id, entry.lane_id, entry.contact_point)
        back = LaneEntry(road_id=key[0], lane_id=key[1], contact_point=key[2])
        backward = self._edges.setdefault(back_key, [])
        if back not in backward:
            backward.append(back)

    def _has_lane(self, road_id: str, lane_id: int, end: models.ContactPoint) -> bool:
        road = self._roads.get(road_id)
        return road is not None and _end_section(road, end).lane(lane_id) is not None

    def _linked_to(self, key: _EndKey, road_id: str) -> bool:
        return any(entry.road_id == road_id for entry in self._edges.get(key, ()))

    def _link_roads(
        self,
        road: models.Road,
        end: models.ContactPoint,
        link: models.RoadLink,
        *,
        guessing: bool,
    ) -> None:
        """Declared lane links (``guessing`` False), or the id-based default for lanes that
        declare none and whose partner end is not linked to this road yet (True)."""
        other = self._roads.get(link.element_id)
        if other is None:
            return
        contact = link.contact_point or self._guess_contact(road, other)
        for lane in _lanes(_end_section(road, end)):
            declared = lane.predecessors if end is models.ContactPoint.START else lane.successors
            if bool(declared) == guessing:
                continue
            targets = declared or (_default_lane(lane.id, end, contact),)
            for target in targets:
                if target == 0 or not self._has_lane(other.id, target, contact):
                    continue
                if guessing and (
                    self._linked_to((road.id, lane.id, end), other.id)
                    or self._linked_to((other.id, target, contact), road.id)
                ):
                    continue
                self._add(
                    (road.id, lane.id, end),
                    LaneEntry(road_id=other.id, lane_id=target, contact_point=contact),
                )

    def _guess_contact(self, road: models.Road, other: models.Road) -> models.ContactPoint:
        """Contact point missing in the file: the end of ``other`` that links back to ``road``."""
        if other.successor is not None and other.successor.element_id == road.id:
            return models.ContactPoint.END
        return models.ContactPoint.START

    def _link_junction(
        self, road: models.Road, end: models.ContactPoint, junction: models.Junction
    ) -> None:
        for connection in junction.connections:
            if connection.incoming_road != road.id:
                continue
            connecting = self._roads.get(connection.connecting_road)
            if connecting is None or not self._links_back(connecting, connection, road, end):
                continue
            contact = connection.contact_point
            if connection.lane_links:
                pairs = [(link.from_lane, link.to_lane) for link in connection.lane_links]
            else:
                pairs = [
                    (lane.id, _default_lane(lane.id, end, contact))
                    for lane in _lanes(_end_section(road, end))
                ]
            for from_lane, to_lane in pairs:
                if self._has_lane(road.id, from_lane, end) and self._has_lane(
                    connecting.id, to_lane, contact
                ):
                    self._add(
                        (road.id, from_lane, end),
                        LaneEntry(road_id=connecting.id, lane_id=to_lane, contact_point=contact),
                    )

    @staticmethod
    def _links_back(
        connecting: models.Road,
        connection: models.Connection,
        road: models.Road,
        end: models.ContactPoint,
    ) -> bool:
        """Whether the connection belongs to this end of ``road`` (a road may meet the same
        junction at both ends); when the connecting road does not say, accept it."""
        back = (
            connecting.predecessor
            if connection.contact_point is models.ContactPoint.START
            else connecting.successor
        )
        if back is None or back.element_type is not models.ElementType.ROAD:
            return True
        if back.element_id != road.id:
            return False
        return back.contact_point is None or back.contact_point is end

    def connected_roads(self, road_id: str) -> frozenset[str]:
        """Roads sharing a lane connection with ``road_id`` at either end."""
        return self._neighbours.get(road_id, frozenset())

    def next_lanes(
        self, road_id: str, lane_id: int, end: models.ContactPoint
    ) -> tuple[LaneEntry, ...]:
        """Lanes entered when leaving road ``road_id`` through ``end`` in lane ``lane_id``."""
        return tuple(self._edges.get((road_id, lane_id, end), ()))

    def next_section_lane(
        self, road: models.Road, section_index: int, lane_id: int, forward: bool
    ) -> int | None:
        """Lane id continuing ``lane_id`` in the neighbouring lane section of the same road."""
        sections = road.lane_sections
        target_index = section_index + (1 if forward else -1)
        if not 0 <= target_index < len(sections):
            return None
        lane = sections[section_index].lane(lane_id)
        target = sections[target_index]
        if lane is not None:
            declared = lane.successors if forward else lane.predecessors
            for candidate in declared:
                if candidate != 0 and target.lane(candidate) is not None:
                    return candidate
        for candidate_lane in _lanes(target):
            back = candidate_lane.predecessors if forward else candidate_lane.successors
            if lane_id in back:
                return candidate_lane.id
        return lane_id if target.lane(lane_id) is not None else None


def _lanes(section: models.LaneSection) -> tuple[models.Lane, ...]:
    return section.left + section.right
