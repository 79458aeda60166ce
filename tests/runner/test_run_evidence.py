"""``simtest run`` (and every simulator pod) holds its own recording to the evidence rule of
``simtest evaluate``: a recording that is incomplete or inconsistent cannot make a run Passed.

Covers: a sound recording leaves the pass and the log says so; a recording below omega-prime's
10 Hz minimum turns the pass into ``Error`` with the same ``evidence incomplete: …`` reason
``simtest evaluate`` gives (result file too); a failure stays a failure (a violation seen in
partial evidence is still one); a run that keeps no recording (``scenario check``) records to a
scratch file and is held to the same rule.
"""

from __future__ import annotations

import dataclasses
import json
import re
import shutil
from pathlib import Path

import pytest

from simtest_operator.evaluation import quality
from simtest_operator.recording import objects
from simtest_operator.runner import scenario_execution
from simtest_operator.settings import SimulationSettings
from simtest_operator.snapshots import JumpCause
from simtest_operator.verdicts import Verdict

SMOKE = Path(__file__).resolve().parents[2] / "scenarios" / "smoke"
PASSING = SMOKE / "following_highway_v25_thw2_drop5_d2.xosc"
FAILING = SMOKE / "cut-in_highway_v30_gap8_dv12.xosc"


def _run(
    tmp_path: Path, scenario: Path, *, record_hz: float = 10.0, record: bool = True
) -> tuple[scenario_execution.RunReport, Path]:
    out = tmp_path / f"{scenario.stem}-{record_hz:g}-{record}"
    report = scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=scenario,
            nets_dir=tmp_path / "nets",
            simulation=SimulationSettings(record_hz=record_hz),
            output_dir=out,
            record=record,
        )
    )
    return report, out


@pytest.mark.slow
def test_a_sound_recording_keeps_the_pass(tmp_path: Path) -> None:
    report, out = _run(tmp_path, PASSING)
    assert report.outcome.verdict is Verdict.PASSED, report.outcome.reason
    assert "evidence: complete" in (out / "run.log").read_text(encoding="utf-8")


@pytest.mark.slow
def test_an_incomplete_recording_cannot_pass(tmp_path: Path) -> None:
    report, out = _run(tmp_path, PASSING, record_hz=5.0)
    outcome = report.outcome
    assert outcome.verdict is Verdict.ERROR
    assert outcome.reason.startswith("evidence incomplete: frame rate 5"), outcome.reason
    written = json.loads((out / "result.json").read_text(encoding="utf-8"))
    assert (written["verdict"], written["reason"]) == ("Error", outcome.reason)


@pytest.mark.slow
def test_a_failure_stays_a_failure(tmp_path: Path) -> None:
    failed, _ = _run(tmp_path, FAILING, record_hz=5.0)
    assert failed.outcome.verdict is Verdict.FAILED


@pytest.mark.slow
def test_a_run_that_keeps_no_recording_is_checked_alike(tmp_path: Path) -> None:
    # ``scenario check`` keeps no recording: the run records to a scratch file anyway, so its
    # pass meets the same evidence rule, and nothing is left behind.
    unrecorded, out = _run(tmp_path, PASSING, record=False)
    assert unrecorded.outcome.verdict is Verdict.PASSED
    assert "evidence: complete" in (out / "run.log").read_text(encoding="utf-8")
    assert not (out / "recording.mcap").exists() and "recording" not in unrecorded.outcome.artifacts
    thin, _ = _run(tmp_path, PASSING, record_hz=5.0, record=False)
    assert thin.outcome.verdict is Verdict.ERROR
    assert thin.outcome.reason.startswith("evidence incomplete: frame rate 5"), thin.outcome.reason


_HOP = """
        <Maneuver name="LeadHops">
          <Event name="Hop" priority="parallel" maximumExecutionCount="1">
            <Action name="HopAction">
              <PrivateAction>
                <TeleportAction>
                  <Position><RelativeLanePosition entityRef="Lead" ds="20" dLane="0"/></Position>
                </TeleportAction>
              </PrivateAction>
            </Action>
            <StartTrigger><ConditionGroup>
              <Condition name="HopStart" delay="0" conditionEdge="none"><ByValueCondition>
                <SimulationTimeCondition value="5" rule="greaterThan"/>
              </ByValueCondition></Condition>
            </ConditionGroup></StartTrigger>
          </Event>
        </Maneuver>
        </ManeuverGroup>"""


@pytest.mark.slow
def test_a_commanded_teleport_is_declared_and_judged_alike_by_run_check_and_evaluate(
    tmp_path: Path,
) -> None:
    # The lead vehicle is teleported 20 m ahead mid-run: the jump is the scenario's, so the
    # run passes whether it keeps its recording (run) or not (check), and the recording
    # carries the declaration that makes it complete evidence when judged again. Without the
    # declaration the same recording is incomplete: the gate excuses exactly what was declared.
    (tmp_path / "roads").mkdir()
    shutil.copy(SMOKE.parent / "roads" / "highway_straight.xodr", tmp_path / "roads")
    (tmp_path / "smoke").mkdir()
    text = PASSING.read_text(encoding="utf-8")
    assert text.count("</ManeuverGroup>") == 1
    scenario = tmp_path / "smoke" / "hop.xosc"
    scenario.write_text(text.replace("</ManeuverGroup>", _HOP), encoding="utf-8")
    kept, out = _run(tmp_path, scenario)
    unkept, _ = _run(tmp_path, scenario, record=False)
    assert kept.outcome.verdict is unkept.outcome.verdict is Verdict.PASSED, (
        kept.outcome.reason,
        unkept.outcome.reason,
    )
    decoded = objects.read_objects(out / "recording.mcap")
    lead = decoded.objects[1]
    (jump,) = decoded.discontinuities
    assert (jump.cause, jump.entity, jump.object_id) == (JumpCause.TELEPORT, 1, 1)
    hop = lead.t.index(jump.time)
    assert lead.x[hop] - lead.x[hop - 1] > 20.0
    judged = quality.assess(decoded, simulated_seconds=kept.outcome.simulated_seconds)
    assert judged.complete, judged.issues
    blind = dataclasses.replace(decoded, discontinuities=())
    issues = quality.assess(blind, simulated_seconds=kept.outcome.simulated_seconds).issues
    assert len(issues) == 1 and re.fullmatch(
        rf"object 1 jumps 1\d\.\d\d m against its velocity at t={jump.time:.2f} s", issues[0]
    ), issues
