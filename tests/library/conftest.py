"""Fixtures for the scenario library tests: where the library and the schemas are."""

from __future__ import annotations

from pathlib import Path

import pytest
from lxml import etree

LIBRARY_ROOT = Path(__file__).resolve().parents[2] / "scenarios"
"""The committed library: generate.py, roads/, library/, smoke/."""

SCHEMAS = Path(__file__).resolve().parent / "schemas"
"""ASAM schemas copied from the esmini distribution (see schemas/README.md)."""


@pytest.fixture(scope="session")
def library_root() -> Path:
    return LIBRARY_ROOT


@pytest.fixture(scope="session")
def openscenario_schema() -> etree.XMLSchema:
    return etree.XMLSchema(etree.parse(str(SCHEMAS / "OpenSCENARIOv1.2.xsd")))


@pytest.fixture(scope="session")
def opendrive_schema() -> etree.XMLSchema:
    return etree.XMLSchema(etree.parse(str(SCHEMAS / "OpenDRIVE_1.6" / "opendrive_16_core.xsd")))
