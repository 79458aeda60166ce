"""Safe parsing of untrusted OpenDRIVE: DOCTYPE/entities and external entities refused, size limit,
malformed XML, missing or invalid attributes reported with element and line, unsupported
geometries, namespaced root, every esmini road file parses into the model (roads, lane sections,
junction connections including direct junctions' linkedRoad), and signal stripping."""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.opendrive import models, parse, without_signals
from tests.opendrive.conftest import single_road

LINE = '<geometry s="0" x="0" y="0" hdg="0" length="10"><line/></geometry>'


def test_entities_and_doctype_are_refused(tmp_path: Path) -> None:
    secret = tmp_path / "secret.txt"
    secret.write_text("TOPSECRET")
    external = (
        f'<?xml version="1.0"?><!DOCTYPE r [<!ENTITY x SYSTEM "file://{secret}">]>'
        "<OpenDRIVE><header revMajor='1' revMinor='4' name='&x;'/></OpenDRIVE>"
    ).encode()
    with pytest.raises(ScenarioError, match="DOCTYPE"):
        parse(external)
    laughs = (
        b'<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa">'
        b'<!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">]><OpenDRIVE>&b;</OpenDRIVE>'
    )
    with pytest.raises(ScenarioError):
        parse(laughs)


def test_size_limit() -> None:
    data = single_road(LINE, length=10)
    with pytest.raises(ScenarioError, match="limit"):
        parse(data, max_bytes=100)


def test_malformed_and_wrong_root() -> None:
    with pytest.raises(ScenarioError, match="malformed") as caught:
        parse(b"<OpenDRIVE><road>", source="bad.xodr")
    assert caught.value.file == "bad.xodr"
    with pytest.raises(ScenarioError, match="expected <OpenDRIVE>"):
        parse(b"<OpenSCENARIO/>")


def test_missing_attribute_names_element_and_line() -> None:
    data = single_road('<geometry s="0" x="0" y="0" hdg="0"><line/></geometry>', length=10)
    with pytest.raises(ScenarioError) as caught:
        parse(data, source="r.xodr")
    assert caught.value.element == "geometry"
    assert caught.value.line == 1
    assert "length" in str(caught.value)


def test_invalid_number_and_unknown_geometry() -> None:
    with pytest.raises(ScenarioError, match="hdg='north'"):
        parse(single_road(LINE.replace('hdg="0"', 'hdg="north"'), length=10))
    with pytest.raises(ScenarioError, match="unsupported planView geometry <nurbs>"):
        parse(single_road(LINE.replace("<line/>", "<nurbs/>"), length=10))


def test_namespaced_document_parses() -> None:
    data = single_road(LINE, length=10).replace(
        b"<OpenDRIVE>",
        b'<OpenDRIVE xmlns="http://code.asam.net/simulation/standard/opendrive_schema">',
    )
    document = parse(data)
    assert document.roads[0].geometries[0].kind is models.GeometryKind.LINE
    assert document.roads[0].lane_sections[0].lane_ids == (1, -1, -2)


@pytest.mark.parametrize(
    "name",
    sorted(p.name for p in (Path(__file__).resolve().parents[3] / "shared" / "scenarios-dev"
                            / "esmini" / "resources" / "xodr").glob("*.xodr")),
)  # fmt: skip
def test_esmini_maps_parse(name: str, xodr_dir: Path) -> None:
    document = parse((xodr_dir / name).read_bytes(), source=name)
    assert document.rev_major == 1
    for road in document.roads:
        assert road.geometries and road.lane_sections
        assert abs(sum(g.length for g in road.geometries) - road.length) < 1e-3 * max(
            1.0, road.length
        )


def test_direct_junction_uses_linked_road(xodr_dir: Path) -> None:
    document = parse((xodr_dir / "soderleden.xodr").read_bytes())
    (junction,) = document.junctions
    assert {(c.incoming_road, c.connecting_road) for c in junction.connections} == {
        ("2", "0"),
        ("5", "0"),
    }


def test_without_signals(xodr_dir: Path) -> None:
    original = (xodr_dir / "straight_500m_signs.xodr").read_bytes()
    assert b"<signal " in original
    stripped = without_signals(original)
    assert b"<signal" not in stripped
    assert len(parse(stripped).roads) == len(parse(original).roads)


def test_road_type_speed_limits() -> None:
    types = (
        '<type s="0" type="town"><speed max="25" unit="mph"/></type>'
        '<type s="4" type="rural"><speed max="no limit"/></type>'
        '<type s="5" type="motorway"><speed max="nan" unit="km/h"/></type>'
        '<type s="6" type="motorway"><speed max="90" unit="km/h"/></type>'
        '<type s="8" type="town"><speed max="12"/></type>'
    )
    data = single_road(LINE, length=10).replace(b"<planView>", types.encode() + b"<planView>")
    road = parse(data).roads[0]
    # A limit nobody can drive at (no limit, NaN) is left out: the previous one stays in force.
    assert [(limit.s, round(limit.max_speed, 3)) for limit in road.speed_limits] == [
        (0.0, 11.176),
        (6.0, 25.0),
        (8.0, 12.0),
    ]
    assert road.speed_limit(5.0) == pytest.approx(11.176)
    assert road.speed_limit(9.0) == 12.0
    assert parse(single_road(LINE, length=10)).roads[0].speed_limit(0.0) is None


def _with_header_offset(offset: str) -> bytes:
    data = single_road(LINE, length=10)
    return data.replace(b'revMinor="6"/>', b'revMinor="6">' + offset.encode() + b"</header>")


def test_header_offset_translates_then_rotates() -> None:
    # OpenDRIVE 1.5+: the dataset is translated by (x, y), then rotated by hdg about the new
    # origin; esmini reports geo_pos's (908.13, 593.99, 5.4978) at (-129.69, -21.34, 0.175)
    offset = parse(_with_header_offset('<offset x="-1000" y="-500" z="0" hdg="0.959931"/>')).offset
    assert offset is not None
    x, y, heading = offset.apply(908.1317271, 593.9895912, 5.497787)
    assert (x, y, heading) == pytest.approx((-129.685, -21.344, 0.17453), abs=1e-3)


def test_identity_or_absent_header_offset_is_none() -> None:
    assert parse(single_road(LINE, length=10)).offset is None
    assert parse(_with_header_offset('<offset x="0" y="0" z="0" hdg="0"/>')).offset is None


@pytest.mark.parametrize(
    "offset",
    [
        '<offset x="nan" y="0" z="0" hdg="0"/>',
        '<offset x="0" y="1e300" z="0" hdg="0"/>',
        '<offset x="0" y="0" z="0" hdg="inf"/>',
        '<offset x="0" y="0" z="0"/>',
    ],
)
def test_hostile_header_offset_is_refused(offset: str) -> None:
    with pytest.raises(ScenarioError, match="offset"):
        parse(_with_header_offset(offset))
