"""Fixtures for OpenDRIVE tests: the esmini road files and a builder for synthetic roads."""

from __future__ import annotations

from pathlib import Path

import pytest

XODR_DIR = (
    Path(__file__).resolve().parents[3]
    / "shared"
    / "scenarios-dev"
    / "esmini"
    / "resources"
    / "xodr"
)


@pytest.fixture(scope="session")
def xodr_dir() -> Path:
    if not XODR_DIR.is_dir():
        pytest.fail(f"development corpus missing: {XODR_DIR}")
    return XODR_DIR


def single_road(
    geometry: str, *, length: float, lanes: str | None = None, extra: str = ""
) -> bytes:
    """A one-road OpenDRIVE document with the given planView geometry body."""
    lanes = lanes or (
        '<laneSection s="0"><left><lane id="1" type="driving"><width sOffset="0" a="3.5"/></lane>'
        '</left><center><lane id="0" type="none"/></center><right>'
        '<lane id="-1" type="driving"><width sOffset="0" a="3.5"/></lane>'
        '<lane id="-2" type="sidewalk"><width sOffset="0" a="2.0"/></lane></right></laneSection>'
    )
    return (
        '<?xml version="1.0"?><OpenDRIVE><header revMajor="1" revMinor="6"/>'
        f'<road id="r" length="{length}" junction="-1"><planView>{geometry}</planView>'
        f"<lanes>{extra}{lanes}</lanes></road></OpenDRIVE>"
    ).encode()


def road_grid(count: int, *, lanes: int = 2, length: float = 20.0, shape: str = "<line/>") -> bytes:
    """``count`` separate roads on a grid, each with ``lanes`` driving lanes per side: a large
    road network, generated (21,000 roads of 2 x 2 lanes are 32 MB)."""
    lane = (
        '<lane id="{id}" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/>'
        '<roadMark sOffset="0" type="solid" weight="standard" color="standard" width="0.15"/>'
        "</lane>"
    )
    left = "".join(lane.format(id=k) for k in range(lanes, 0, -1))
    right = "".join(lane.format(id=-k) for k in range(1, lanes + 1))
    spacing = length + 30.0
    parts = ['<?xml version="1.0"?><OpenDRIVE><header revMajor="1" revMinor="6"/>\n']
    for i in range(count):
        x, y = (i % 100) * spacing, (i // 100) * spacing
        parts.append(
            f'<road id="{i}" length="{length}" junction="-1"><planView><geometry s="0" x="{x}" '
            f'y="{y}" hdg="0" length="{length}">{shape}</geometry></planView><lanes>'
            f'<laneSection s="0"><left>{left}</left><center><lane id="0" type="none"/></center>'
            f"<right>{right}</right></laneSection></lanes></road>\n"
        )
    parts.append("</OpenDRIVE>\n")
    return "".join(parts).encode()
