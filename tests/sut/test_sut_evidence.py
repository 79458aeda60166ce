"""What a SUT's developer gets when a run goes wrong: the SUT's own output as the scenario's
``sut.log`` (bounded), its tail in every SUT error (also when it never became ready), the
configured SUT's identity on start-up errors, and by how much a step deadline was missed."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

from simtest_operator.sim import SutConfig
from simtest_operator.sut.output import BoundedOutput
from simtest_operator.verdicts import Verdict
from tests.sut.test_lockstep import AEB, FAULTY, external, run


def faulty(mode: str, step: int = 5, **options: float) -> SutConfig:
    return dataclasses.replace(
        AEB, external=external((sys.executable, str(FAULTY), mode, str(step)), **options)
    )


def test_a_crashed_sut_leaves_its_log_and_its_last_words_in_the_reason(tmp_path: Path) -> None:
    outcome = run(faulty("kill"), tmp_path).outcome
    assert outcome.verdict is Verdict.ERROR
    assert "killed by signal 9: faulty SUT: mode kill at step 5 faulty SUT: run " in (
        outcome.reason
    ), outcome.reason
    assert outcome.reason.endswith("faulty SUT: crashing at step 5"), outcome.reason
    log = Path(outcome.artifacts["sutLog"])
    assert log == tmp_path / "sut.log"
    assert log.read_text().splitlines() == [
        "faulty SUT: mode kill at step 5",
        "faulty SUT: run hard_braking_lead.xosc",
        "faulty SUT: crashing at step 5",
    ]


def test_a_sut_that_never_listens_says_what_it_said(tmp_path: Path) -> None:
    # A shell, not Python: it has printed long before the start-up timeout, even under load.
    script = "echo 'planner 2.1 starting'; echo 'waiting for the licence server' >&2; sleep 60"
    deaf = dataclasses.replace(AEB, external=external(("sh", "-c", script), startup_timeout=2.0))
    outcome = run(deaf, tmp_path).outcome
    assert outcome.verdict is Verdict.ERROR
    assert "did not become ready" in outcome.reason, outcome.reason
    assert "said last: planner 2.1 starting waiting for the licence server" in (outcome.reason), (
        outcome.reason
    )
    # Which SUT failed to start, though it never answered READY.
    assert outcome.versions["sut.configHash"].startswith("sha256:")
    assert outcome.versions["sut.launch"] == "local"
    assert "sut.reported" not in outcome.versions
    assert "waiting for the licence" in (tmp_path / "sut.log").read_text()


def test_a_missed_step_deadline_says_by_how_much() -> None:
    outcome = run(faulty("slow"), None).outcome
    assert outcome.verdict is Verdict.ERROR
    reason = outcome.reason
    assert "missed the 500 ms deadline for step 5 (t=0.200 s): the answer came" in reason, reason
    late = float(reason.split("the answer came ")[1].split(" ms late")[0])
    assert 300 <= late <= 4000, reason  # answered after 1 s: about 500 ms past the deadline
    assert "the SUT process is running; it said last: faulty SUT: mode slow" in reason


def test_a_passing_run_keeps_the_sut_log_too(tmp_path: Path) -> None:
    outcome = run(faulty("kill", step=100_000), tmp_path).outcome
    assert outcome.verdict is Verdict.PASSED, outcome.reason
    assert (tmp_path / "sut.log").read_text().splitlines() == [
        "faulty SUT: mode kill at step 100000",
        "faulty SUT: run hard_braking_lead.xosc",
    ]
    assert outcome.artifacts["sutLog"] == str(tmp_path / "sut.log")


def test_output_is_bounded_to_its_head_and_tail() -> None:
    kept = BoundedOutput(head=10, tail=20)
    for index in range(1000):
        kept.feed(f"line {index:04d}\n".encode())
    text = kept.text()
    assert text.startswith("line 0000\n\n[... 9970 bytes of SUT output not kept ...]\nline 0998")
    assert text.endswith("line 0998\nline 0999\n")
    assert "[... 9970 bytes of SUT output not kept ...]" in text
    assert len(text.encode()) < 100
    assert kept.last(9) == "line 0999"
