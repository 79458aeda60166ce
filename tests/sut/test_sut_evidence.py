"""What a SUT's developer gets when a run goes wrong: the SUT's own output as the scenario's
``sut.log`` (bounded), its tail in every SUT error (also when it never became ready), the
configured SUT's identity on start-up errors, and by how much a step deadline was missed."""

from __future__ import annotations

import contextlib
import dataclasses
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

from simtest_operator import render
from simtest_operator.drivermodel import ExternalSut, Launch
from simtest_operator.runner import suts
from simtest_operator.settings import SUT_ENDPOINT, SUT_OUTPUT_DIR, Settings
from simtest_operator.sim import SutConfig
from simtest_operator.sut import launching
from simtest_operator.sut.output import BoundedOutput, take_files
from simtest_operator.verdicts import Verdict
from tests.render.cases import CASES
from tests.sut.test_lockstep import AEB, FAULTY, external, run

REPO = Path(__file__).resolve().parents[2]


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


def _wrap_script() -> str:
    """The shell line the pod template starts a captured sidecar with (default/pod.yaml.j2)."""
    pod = render.render_environment(
        CASES["ros2-stack-in-pod"], render.TemplateLibrary(REPO / "helm-templates")
    ).pod
    (bridge,) = [c for c in pod["spec"]["initContainers"] if c["name"] == "sut"]
    assert bridge["command"][:2] == ["/bin/sh", "-c"]
    return str(bridge["command"][2])


@contextlib.contextmanager
def sidecar(tmp_path: Path, *command: str) -> Iterator[SutConfig]:
    """``command`` started as the pod template starts a captured sidecar (sh, tee into the
    shared folder), and the SUT config a pod's runner reaches it with."""
    folder = tmp_path / "var/run/simtest/sut-output"
    folder.mkdir(parents=True)
    script = _wrap_script().replace("/var/run/simtest/sut-output", str(folder))
    port = launching.free_port()
    env = {**os.environ, "SIMTEST_SUT_PORT": str(port)}
    with subprocess.Popen(["/bin/sh", "-c", script, "sut", *command], env=env) as process:
        try:
            sut = dataclasses.replace(
                AEB,
                external=ExternalSut(
                    launch=Launch.SIDECAR,
                    endpoint="127.0.0.1:7460",
                    image="ghcr.io/simtest-dev/simtest-runner:0.1.0",
                    step_deadline=0.5,
                    startup_timeout=20.0,
                ),
            )
            pod = Settings.from_env(
                {
                    "HOME": str(tmp_path),
                    SUT_ENDPOINT: f"127.0.0.1:{port}",
                    SUT_OUTPUT_DIR: str(folder),
                }
            )
            sut = suts.reached_here(sut, pod)
            assert sut.external is not None and sut.external.output_dir == folder
            yield sut
        finally:
            process.terminate()


def test_a_sidecar_s_output_is_each_run_s_sut_log(tmp_path: Path) -> None:
    """What a captured sidecar printed during each run is that run's sut.log, and only that: a
    pod's runs follow each other, and the next run's log starts where the last one ended."""
    logs = []
    with sidecar(tmp_path, *launching.reference_command()) as sut:
        for name in ("first", "second"):
            outcome = run(sut, tmp_path / name).outcome
            assert outcome.verdict is Verdict.PASSED, outcome.reason
            logs.append(Path(outcome.artifacts["sutLog"]).read_text())
    first, second = (log.splitlines() for log in logs)
    run_line = "reference SUT: run hard_braking_lead.xosc: ego "
    assert first[0] == "==> sut <==", first
    assert first[1].startswith("reference SUT: simtest-reference-sut 1.0.0 listening on"), first
    assert [line[: len(run_line)] for line in first[2:]] == [run_line], first
    assert second[0] == "==> sut <==", second
    assert [line[: len(run_line)] for line in second[1:]] == [run_line], second


def test_a_failing_sidecar_s_last_words_are_in_the_reason(tmp_path: Path) -> None:
    with sidecar(tmp_path, sys.executable, str(FAULTY), "refuse", "5") as sut:
        outcome = run(sut, tmp_path / "out").outcome
    assert outcome.verdict is Verdict.ERROR
    assert "the SUT's sidecars said last: sut: faulty SUT: mode refuse at step 5" in (
        outcome.reason
    ), outcome.reason
    log = Path(outcome.artifacts["sutLog"]).read_text()
    assert log.startswith("==> sut <==\nfaulty SUT: mode refuse at step 5\n"), log


def test_sidecar_files_are_kept_to_their_head_and_tail_and_emptied(tmp_path: Path) -> None:
    folder, log = tmp_path / "out", tmp_path / "sut.log"
    folder.mkdir()
    assert not take_files(folder, log) and not log.exists()  # nothing captured: no sut.log
    big = b"".join(f"line {i:06d}\n".encode() for i in range(20_000))  # 240 kB
    (folder / "stack-control.log").write_bytes(big)
    (folder / "sut.log").write_bytes(b"bridge: up\n")
    (folder / ".sut.fifo").write_bytes(b"not a log")
    assert take_files(folder, log)
    text = log.read_text()
    assert text.startswith("==> stack-control <==\nline 000000\n"), text[:80]
    assert f"[... {len(big) - 128 * 1024} bytes of SUT output not kept ...]" in text
    assert text.endswith("line 019999\n\n==> sut <==\nbridge: up\n"), text[-80:]
    assert (folder / "stack-control.log").stat().st_size == 0
    assert (folder / "sut.log").stat().st_size == 0
