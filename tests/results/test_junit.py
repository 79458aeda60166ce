"""JUnit XML of a campaign run.

Covers: the document validates against the JUnit schema CI readers apply (testdata/junit.xsd);
one suite per run with correct tests/failures/errors/skipped counts; each verdict maps to the
right element with the reason as message and the verdict as type; classname is the category;
only the final attempt of a retried scenario counts; never-run scenarios appear as skipped;
SUT/simulator versions are suite properties; artifacts become GitLab attachments; characters XML
cannot carry are replaced; the file is written atomically.
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from pathlib import Path

import lxml.etree
import pytest

from simtest_operator.results import junit
from simtest_operator.verdicts import Verdict
from tests.results.resultdata import sample_run

SCHEMA = Path(__file__).parent / "testdata" / "junit.xsd"


@pytest.fixture(scope="module")
def schema() -> lxml.etree.XMLSchema:
    return lxml.etree.XMLSchema(lxml.etree.parse(str(SCHEMA)))


def _render(*, finished: bool = True) -> str:
    record, stored, listed = sample_run(finished=finished)
    return junit.render(record, stored, scenarios=listed, hostname="ci-runner-1")


def test_document_is_valid_junit(schema: lxml.etree.XMLSchema) -> None:
    for finished in (True, False):
        document = lxml.etree.fromstring(_render(finished=finished).encode())
        assert schema.validate(document), schema.error_log


def test_counts_elements_and_reasons() -> None:
    root = ET.fromstring(_render())
    (suite,) = root.findall("testsuite")
    assert suite.attrib | {"timestamp": "-"} == {
        "name": "smoke",
        "tests": "8",
        "failures": "2",
        "errors": "1",
        "skipped": "2",
        "time": "42.500",
        "timestamp": "-",
        "id": "smoke-20250301T120000Z-0badcafe",
        "package": "team-a",
        "hostname": "ci-runner-1",
    }
    assert root.attrib["tests"] == "8"
    cases = {case.attrib["name"]: case for case in suite.iter("testcase")}
    assert cases["cut-in/close.xosc"].attrib["classname"] == "cut-in"
    failure = cases["cut-in/close.xosc"].find("failure")
    assert failure is not None
    assert failure.attrib == {"type": "Failed", "message": "collision with 'cutter' at t=7.2 s"}
    timeout = cases["ped/night.xosc"].find("failure")
    assert timeout is not None
    assert timeout.attrib["type"] == "Timeout"
    error = cases["broken/bad.xosc"].find("error")
    assert error is not None
    assert error.attrib["type"] == "Invalid"
    assert "missing.xodr" in error.attrib["message"]
    # Retried after an infrastructure error: only the passing second attempt counts.
    assert [child.tag for child in cases["follow/stop.xosc"]] == ["system-out"]
    skipped = cases["never/ran.xosc"].find("skipped")
    assert skipped is not None
    assert skipped.attrib["message"] == junit.NOT_RUN
    assert cases["ped/crossing.xosc"].attrib["classname"] == "pedestrian"


def test_properties_and_attachments() -> None:
    suite = ET.fromstring(_render()).find("testsuite")
    assert suite is not None
    properties = {p.attrib["name"]: p.attrib["value"] for p in suite.iter("property")}
    assert properties["sut.name"] == "idm-driver"
    assert properties["sut.version"] == "1.4.0"
    assert properties["simulator.version"] == "sumo-1.20"
    assert properties["simtest.phase"] == "Failed"
    out = suite.find("testcase[@name='cut-in/close.xosc']/system-out")
    assert out is not None
    assert out.text is not None
    assert "[[ATTACHMENT|cut-in/close.xosc/recording.mcap]]" in out.text
    assert "minTTC: 0.4" in out.text


def test_unfinished_run_is_marked(schema: lxml.etree.XMLSchema) -> None:
    suite = ET.fromstring(_render(finished=False)).find("testsuite")
    assert suite is not None
    properties = {p.attrib["name"]: p.attrib["value"] for p in suite.iter("property")}
    assert properties["simtest.phase"] == "Unfinished"
    assert suite.attrib["time"] == "1.750"  # sum of the seven final attempts' wall times


def test_control_characters_are_replaced(schema: lxml.etree.XMLSchema, tmp_path: Path) -> None:
    record, stored, _ = sample_run()
    broken = dataclasses.replace(
        stored[0],
        outcome=dataclasses.replace(stored[0].outcome, reason="segfault \x00\x1b[31m in net"),
    )
    assert broken.outcome.verdict is Verdict.FAILED
    path = junit.write(tmp_path / "out" / "junit.xml", junit.render(record, [broken]))
    assert not list(path.parent.glob(".*partial"))
    document = lxml.etree.parse(str(path))
    assert schema.validate(document), schema.error_log
    assert "segfault \ufffd\ufffd[31m in net" in path.read_text(encoding="utf-8")
