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
