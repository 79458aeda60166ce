"""JUnit XML: how CI systems (GitLab, Jenkins, GitHub actions) read a campaign's verdicts.

One ``<testsuite>`` per campaign run inside ``<testsuites>``; one ``<testcase>`` per scenario with
``classname`` = category and ``name`` = scenario id. Verdicts map onto the three JUnit outcomes the
way the verdict vocabulary already splits them: ``Failed`` and ``Timeout`` are verdicts on the
system under test -> ``<failure>``; ``Error`` and ``Invalid`` mean the test itself could not run
-> ``<error>``; ``Skipped`` (and scenarios of the frozen list that never ran) -> ``<skipped>``.
The element's ``type`` is the verdict and ``message`` the one-line reason. SUT and simulator
versions go into suite ``<properties>``; artifact paths into ``<system-out>`` as GitLab
``[[ATTACHMENT|...]]`` lines. The output validates against the widely used JUnit schema
(Jenkins xunit's ``junit-10.xsd`` rules, which GitLab and GitHub readers accept).
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

from simtest_operator.results import comparing, records
from simtest_operator.verdicts import Verdict

NOT_RUN = "not run: the campaign stopped before this scenario finished"

_ELEMENT = {
    Verdict.FAILED: "failure",
    Verdict.TIMEOUT: "failure",
    Verdict.ERROR: "error",
    Verdict.INVALID: "error",
    Verdict.SKIPPED: "skipped",
}
_NOT_XML = re.compile("[^\u0009\u000a\u000d\u0020-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def render(
    campaign: records.CampaignRecord,
    outcomes: Sequence[records.StoredOutcome],
    *,
    scenarios: Sequence[records.ScenarioInfo] = (),
    hostname: str = "",
) -> str:
    """The JUnit document of one run (final attempts only); ``scenarios`` adds the never-run."""
    final = comparing.final_outcomes(outcomes)
    missing = [s for s in scenarios if s.scenario_id not in final]
    cases = [_testcase(final[key]) for key in sorted(final)]
    cases += [_not_run(s) for s in missing]
    counts = {"failure": 0, "error": 0, "skipped": 0}
    for case in cases:
        for child in case:
            if child.tag in counts:
                counts[child.tag] += 1
    total_time = _suite_seconds(campaign, final.values())
    suite = ET.Element(
        "testsuite",
        {
            "name": _text(campaign.info.name),
            "tests": str(len(cases)),
            "failures": str(counts["failure"]),
            "errors": str(counts["error"]),
            "skipped": str(counts["skipped"]),
            "time": _seconds(total_time),
            "timestamp": campaign.info.started_at.strftime("%Y-%m-%dT%H:%M:%S"),
            "id": _text(campaign.run_key),
            "package": _text(campaign.info.namespace or "local"),
            **({"hostname": _text(hostname)} if hostname else {}),
        },
    )
    properties = ET.SubElement(suite, "properties")
    for name, value in _properties(campaign).items():
        ET.SubElement(properties, "property", {"name": name, "value": _text(value)})
    suite.extend(cases)
    root = ET.Element(
        "testsuites",
        {
            "name": _text(campaign.info.name),
            "tests": suite.attrib["tests"],
            "failures": suite.attrib["failures"],
            "errors": suite.attrib["errors"],
            "time": suite.attrib["time"],
        },
    )
    root.append(suite)
    ET.indent(root)
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"


def write(path: Path, document: str) -> Path:
    """Write a rendered document atomically (a CI step never reads half a file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(f".{path.name}.partial")
    partial.write_text(document, encoding="utf-8")
    partial.replace(path)
    return path


def _testcase(stored: records.StoredOutcome) -> ET.Element:
    outcome = stored.outcome
    case = ET.Element(
        "testcase",
        {
            "name": _text(stored.scenario.scenario_id),
            "classname": _text(stored.scenario.category or records.UNCATEGORIZED),
            "time": _seconds(outcome.wall_seconds),
        },
    )
    element = _ELEMENT.get(outcome.verdict)
    if element is not None:
        reason = outcome.reason or outcome.verdict.value
        child = ET.SubElement(
            case, element, {"type": outcome.verdict.value, "message": _text(reason)}
        )
        child.text = _text(_details(stored))
    out = [f"verdict: {outcome.verdict.value} (attempt {outcome.attempts})"]
    out += [f"{name}: {_number(value)}" for name, value in sorted(outcome.metrics.items())]
    out += [f"[[ATTACHMENT|{uri}]]" for _, uri in sorted(outcome.artifacts.items())]
    ET.SubElement(case, "system-out").text = _text("\n".join(out))
    return case


def _not_run(scenario: records.ScenarioInfo) -> ET.Element:
    case = ET.Element(
        "testcase",
        {"name": _text(scenario.scenario_id), "classname": _text(scenario.category), "time": "0"},
    )
    ET.SubElement(case, "skipped", {"type": "NotRun", "message": NOT_RUN})
    return case


def _details(stored: records.StoredOutcome) -> str:
    outcome = stored.outcome
    lines = [outcome.reason] if outcome.reason else []
    lines += [f"scenario: {stored.scenario.source or stored.scenario.scenario_id}"]
    lines += [f"sha256: {stored.scenario.sha256}"]
    if outcome.ignored_elements:
        lines.append(f"ignored elements: {', '.join(outcome.ignored_elements)}")
    return "\n".join(lines)


def _properties(campaign: records.CampaignRecord) -> Mapping[str, str]:
    info = campaign.info
    props = {
        "simtest.runKey": campaign.run_key,
        "simtest.namespace": info.namespace,
        "simtest.manifestSha256": info.manifest_sha256,
        "sut.name": info.sut_name,
        "sut.version": info.sut_version,
        "simulator.version": info.simulator_version,
        "simtest.phase": campaign.phase or ("" if campaign.finished else "Unfinished"),
    }
    return {name: value for name, value in props.items() if value}


def _suite_seconds(
    campaign: records.CampaignRecord, final: Iterable[records.StoredOutcome]
) -> float:
    """Campaign wall time when finished; the sum of scenario times for an unfinished run."""
    if campaign.finished_at is not None:
        return max(0.0, (campaign.finished_at - campaign.info.started_at).total_seconds())
    return sum(s.outcome.wall_seconds for s in final)


def _seconds(value: float) -> str:
    return f"{value:.3f}" if math.isfinite(value) and value >= 0 else "0"


def _number(value: float) -> str:
    return f"{value:.6g}"


def _text(value: str) -> str:
    """Drop characters XML 1.0 cannot carry (control characters from a crashing simulator)."""
    return _NOT_XML.sub("\ufffd", value)
