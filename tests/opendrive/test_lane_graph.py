"""Lane graph and moving along lanes: lane links across lane sections (ids change), road links
end-to-end (direction flips, lanes swap sides), junction connections with lane links, fork choice
by preferred roads, dead ends reporting the distance left, backwards moves, successors and
predecessors by driving direction (RHT and LHT), and the esmini junction maps."""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.opendrive import ContactPoint, LaneEntry, RoadNetwork

LANE = '<lane id="{id}" type="driving"><link>{link}</link><width sOffset="0" a="3.5"/></lane>'


def lane(lane_id: int, link: str = "") -> str:
    return LANE.format(id=lane_id, link=link)


def road(road_id: str, x: float, y: float, hdg: float, length: float, links: str, sections: str,
         junction: str = "-1", rule: str = "") -> str:  # fmt: skip
    return (
        f'<road id="{road_id}" length="{length}" junction="{junction}" {rule}><link>{links}</link>'
        f'<planView><geometry s="0" x="{x}" y="{y}" hdg="{hdg}" length="{length}"><line/>'
        f"</geometry></planView><lanes>{sections}</lanes></road>"
    )


def section(s: float, left: str = "", right: str = "") -> str:
    return (
        f'<laneSection s="{s}"><left>{left}</left><center><lane id="0" type="none"/></center>'
        f"<right>{right}</right></laneSection>"
    )


def network() -> RoadNetwork:
    """A (0..100 along +x, two sections) -> B (drawn backwards: its end meets A's end) -> junction
    J at B's start with connecting roads C1 (straight on) and C2 (to the left)."""
    road_a = road(
        "A", 0, 0, 0, 100,
        '<successor elementType="road" elementId="B" contactPoint="end"/>',
        section(0, lane(1), lane(-1, '<successor id="-2"/>') + lane(-2))
        + section(50, lane(1), lane(-1) + lane(-2, '<predecessor id="-1"/>')),
    )  # fmt: skip
    road_b = road(
        "B", 200, 0, 3.141592653589793, 100,
        '<predecessor elementType="junction" elementId="J"/>'
        '<successor elementType="road" elementId="A" contactPoint="end"/>',
        section(0, lane(1) + lane(2), lane(-1)),
    )  # fmt: skip
    from_b = '<predecessor elementType="road" elementId="B" contactPoint="start"/>'
    c1 = road("C1", 200, 0, 0, 20, from_b, section(0, "", lane(-1)), junction="J")
    c2 = road("C2", 200, 0, 0.5, 20, from_b, section(0, "", lane(-1)), junction="J")
    junction = (
        '<junction id="J" name="">'
        '<connection id="0" incomingRoad="B" connectingRoad="C1" contactPoint="start">'
        '<laneLink from="1" to="-1"/></connection>'
        '<connection id="1" incomingRoad="B" connectingRoad="C2" contactPoint="start">'
        '<laneLink from="2" to="-1"/><laneLink from="1" to="-1"/></connection></junction>'
    )
    document = (
        '<?xml version="1.0"?><OpenDRIVE><header revMajor="1" revMinor="6"/>'
        f"{road_a}{road_b}{c1}{c2}{junction}</OpenDRIVE>"
    )
    return RoadNetwork.from_bytes(document.encode())


def test_next_lanes_across_road_link_and_junction() -> None:
    net = network()
    assert net.next_lanes("A", -2, ContactPoint.END) == (
        LaneEntry(road_id="B", lane_id=2, contact_point=ContactPoint.END),
    )
    assert net.next_lanes("B", 1, ContactPoint.START) == (
        LaneEntry(road_id="C1", lane_id=-1, contact_point=ContactPoint.START),
        LaneEntry(road_id="C2", lane_id=-1, contact_point=ContactPoint.START),
    )
    # The graph is symmetric: leaving C2 backwards enters B at its start in both lanes.
    back = net.next_lanes("C2", -1, ContactPoint.START)
    assert {(entry.road_id, entry.lane_id) for entry in back} == {("B", 1), ("B", 2)}


def test_a_declared_lane_link_beats_the_id_guess_of_the_other_road() -> None:
    # P's end meets Q's end (lanes swap sides). Q's lane -1 declares P's lane 2 as successor;
    # P's lane 1 (0 m wide there, opening towards P's start) declares nothing, so the id guess
    # would link it to Q's -1 too, and P comes first in the file: the walk took the 0 m lane.
    narrow = (
        '<lane id="1" type="driving"><link/><width sOffset="0" a="3.5"/>'
        '<width sOffset="50" a="0"/></lane>'
    )
    road_p = road(
        "P", 200, 0, 3.141592653589793, 100,
        '<successor elementType="road" elementId="Q" contactPoint="end"/>',
        section(0, narrow + lane(2, '<successor id="-1"/>'), lane(-1)),
    )  # fmt: skip
    road_q = road(
        "Q", 0, 0, 0, 100,
        '<successor elementType="road" elementId="P" contactPoint="end"/>',
        section(0, lane(1), lane(-1, '<successor id="2"/>')),
    )  # fmt: skip
    net = RoadNetwork.from_bytes(
        (
            '<?xml version="1.0"?><OpenDRIVE><header revMajor="1" revMinor="6"/>'
            f"{road_p}{road_q}</OpenDRIVE>"
        ).encode()
    )
    assert net.next_lanes("Q", -1, ContactPoint.END) == (
        LaneEntry(road_id="P", lane_id=2, contact_point=ContactPoint.END),
    )
    assert net.advance("Q", 99.0, -1, 2.0).lane_id == 2
    # a lane that declares nothing still links by id where the other side is free
    assert net.next_lanes("Q", 1, ContactPoint.END) == (
        LaneEntry(road_id="P", lane_id=-1, contact_point=ContactPoint.END),
    )


def test_successors_follow_driving_direction() -> None:
    net = network()
    assert [e.road_id for e in net.successors("B", 1)] == ["C1", "C2"]
    assert [(e.road_id, e.lane_id) for e in net.predecessors("B", 1)] == [("A", -1)]
    assert net.successors("C1", -1) == ()


def test_advance_through_sections_roads_and_junction() -> None:
    net = network()
    # Lane -1 of A's first section continues as -2 in the second; A's end meets B's end, so the
    # walk continues on B's lane 2 towards decreasing s.
    mid = net.advance("A", 10.0, -1, 60.0)
    assert (mid.road_id, mid.lane_id, mid.direction) == ("A", -2, 1)
    assert mid.s == pytest.approx(70.0)
    onto_b = net.advance("A", 10.0, -1, 120.0)
    assert (onto_b.road_id, onto_b.lane_id, onto_b.direction) == ("B", 2, -1)
    assert onto_b.s == pytest.approx(70.0)
    # Continue through the junction; the preferred road wins at the fork.
    through = net.advance("A", 90.0, -1, 115.0, prefer_roads={"C2"})
    assert (through.road_id, through.lane_id, through.direction) == ("C2", -1, 1)
    assert through.s == pytest.approx(5.0)
    default = net.advance("B", 10.0, 1, -15.0)
    assert (default.road_id, default.s) == ("C1", pytest.approx(5.0))


def test_advance_stops_at_dead_end() -> None:
    net = network()
    end = net.advance("C1", 5.0, -1, 40.0)
    assert (end.road_id, end.s, end.remaining) == ("C1", 20.0, pytest.approx(25.0))
    back = net.advance("A", 30.0, 1, -50.0)
    assert (back.road_id, back.s, back.direction, back.remaining) == (
        "A",
        0.0,
        -1,
        pytest.approx(20.0),
    )


def test_driving_direction_respects_rule() -> None:
    lht = road("L", 0, 0, 0, 50, "", section(0, lane(1), lane(-1)), rule='rule="LHT"')
    net = RoadNetwork.from_bytes(
        f'<OpenDRIVE><header revMajor="1" revMinor="5"/>{lht}</OpenDRIVE>'.encode()
    )
    assert net.driving_direction("L", 1) == 1
    assert net.driving_direction("L", -1) == -1


@pytest.mark.parametrize(
    "name", ["fabriksgatan.xodr", "multi_intersections.xodr", "soderleden.xodr"]
)
def test_every_junction_connection_is_in_the_graph(name: str, xodr_dir: Path) -> None:
    net = RoadNetwork.from_file(xodr_dir / name)
    for junction in net.document.junctions:
        for connection in junction.connections:
            incoming = net.road(connection.incoming_road)
            ends = [
                end
                for end, link in ((ContactPoint.START, incoming.predecessor),
                                  (ContactPoint.END, incoming.successor))
                if link is not None and link.element_id == junction.id
            ]  # fmt: skip
            assert ends, f"road {incoming.id} does not link to junction {junction.id}"
            reached = {
                (entry.road_id, entry.lane_id)
                for end in ends
                for link in connection.lane_links
                for entry in net.next_lanes(incoming.id, link.from_lane, end)
            }
            for link in connection.lane_links:
                assert (connection.connecting_road, link.to_lane) in reached


def test_a_route_leads_on_through_another_connector_joining_the_same_roads(
    xodr_dir: Path,
) -> None:
    # esmini's route_lane_change: a car planned from road 0 onto road 2 through connector 9
    # changed onto road 0's oncoming lane -1 and drives it back into the junction. Connector 9
    # does not continue that lane; connector 14 (road 2 -> road 0) does, and it joins road 2,
    # so the route takes it (esmini too), not the first declared connector 5 (to road 1).
    net = RoadNetwork.from_file(xodr_dir / "fabriksgatan.xodr")
    into = net.advance("0", 2.0, -1, -4.0, prefer_roads=("9", "2"))
    assert (into.road_id, into.lane_id) == ("14", -1)
    assert net.advance("0", 2.0, -1, -4.0).road_id == "5"  # no route: the first declared one
