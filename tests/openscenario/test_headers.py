"""openscenario.headers, the cheap header reader selection relies on.

Covers: description/author/revision and Properties (last one wins), the document kind (scenario,
catalog, distribution), the road file, namespaced files and a UTF-8 BOM, and refusal of
DOCTYPE/ENTITY declarations, oversize files, malformed XML, other root elements and a missing
FileHeader — all as ScenarioError naming the file.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import headers

HEAD = (
    '<FileHeader revMajor="1" revMinor="3" date="2024-01-01T00:00:00" description="Cut in" '
    'author="me"><License name="MPL"/><Properties><Property name="simtest:tags" value="a,b"/>'
    '<Property name="simtest:category" value="x"/>'
    '<Property name="simtest:category" value="cut-in"/>'
    "</Properties></FileHeader>"
)


def test_scenario_header_and_road() -> None:
    data = (
        f"\ufeff<?xml version='1.0' encoding='utf-8'?><OpenSCENARIO>{HEAD}"
        "<ParameterDeclarations/><CatalogLocations/><RoadNetwork><LogicFile "
        "filepath='../xodr/straight.xodr'/></RoadNetwork><Entities/><Storyboard/></OpenSCENARIO>"
    ).encode()
    header = headers.parse_header(data, source="a.xosc")
    assert header.kind is headers.FileKind.SCENARIO
    assert (header.description, header.author, header.rev_major, header.rev_minor) == (
        "Cut in", "me", 1, 3,
    )  # fmt: skip
    assert header.properties == {"simtest:tags": "a,b", "simtest:category": "cut-in"}
    assert header.road_file == "../xodr/straight.xodr"


@pytest.mark.parametrize(
    ("body", "kind"),
    [
        ("<Catalog name='c'/>", headers.FileKind.CATALOG),
        ("<ParameterValueDistribution/>", headers.FileKind.DISTRIBUTION),
        ("<Storyboard/>", headers.FileKind.SCENARIO),
        ("", headers.FileKind.UNKNOWN),
    ],
)
def test_kinds(body: str, kind: headers.FileKind) -> None:
    data = f'<OpenSCENARIO xmlns="urn:x">{HEAD}{body}</OpenSCENARIO>'.encode()
    assert headers.parse_header(data, source="k.xosc").kind is kind


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b'<!DOCTYPE x [<!ENTITY a "b">]><OpenSCENARIO/>', "DOCTYPE declarations"),
        ("<OpenSCENARIO><!ENTITY a 'x'></OpenSCENARIO>".encode("utf-16"), "ENTITY declarations"),
        (b"<OpenSCENARIO><FileHeader", "malformed XML"),
        (b"<OpenDRIVE><header/></OpenDRIVE>", "not <OpenSCENARIO>"),
        (b"<OpenSCENARIO><Storyboard/></OpenSCENARIO>", "no <FileHeader>"),
        (b"<OpenSCENARIO>" + b" " * 2000 + b"</OpenSCENARIO>", "larger than"),
    ],
)
def test_refusals(data: bytes, message: str) -> None:
    with pytest.raises(ScenarioError, match=message) as caught:
        headers.parse_header(data, source="bad.xosc", max_bytes=1000)
    assert "bad.xosc" in str(caught.value)


def test_read_header_file_errors(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match="cannot read file"):
        headers.read_header(tmp_path / "missing.xosc")
    path = tmp_path / "ok.xosc"
    path.write_text(f"<OpenSCENARIO>{HEAD}<Storyboard/></OpenSCENARIO>")
    assert headers.read_header(path).properties["simtest:tags"] == "a,b"
