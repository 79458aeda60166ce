"""An external SUT in lockstep with the simulation, end to end through the runner: the reference
SUT as a separate process gives the in-process model's verdicts and the same recording; two SUT
configurations give different verdicts and the result names the SUT; a SUT that does not start,
crashes, is too slow, answers garbage or gives up ends the run ``Error`` with a reason saying
so (retried per spec, never ``Failed``); in a pod, the endpoint the template names (a composed
stack's Service) wins over the campaign's."""

from __future__ import annotations

import dataclasses
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from mcap.reader import make_reader

from simtest_operator.drivermodel import ExternalSut, Launch
from simtest_operator.runner import scenario_execution, suts
from simtest_operator.settings import SUT_ENDPOINT, Settings, SimulationSettings
from simtest_operator.sim import BackendChoice, SutConfig
from simtest_operator.sut.launching import free_port, reference_command
from simtest_operator.sut.processes import SutProcesses
from simtest_operator.verdicts import Verdict

SCENARIO = Path(__file__).parents[1] / "sim" / "data" / "hard_braking_lead.xosc"
FAULTY = Path(__file__).parent / "faulty_sut.py"
NO_AEB = SutConfig(acc=False, aeb=False)
AEB = SutConfig(acc=False, aeb=True, aeb_ttc_threshold=2.5, aeb_deceleration=9.0)


def external(command: tuple[str, ...], **extra: float) -> ExternalSut:
    options: dict[str, float] = {"step_deadline": 0.5, "startup_timeout": 20.0, **extra}
    return ExternalSut(launch=Launch.LOCAL, command=command, **options)  # type: ignore[arg-type]


def run(
    sut: SutConfig,
    out: Path | None,
    *,
    processes: SutProcesses | None = None,
    **simulation: float,
) -> scenario_execution.RunReport:
    return scenario_execution.run_scenario(
        scenario_execution.RunRequest(
            scenario=SCENARIO,
            nets_dir=out or Path(),
            sut=sut,
            output_dir=out,
            record=out is not None,
            backend=BackendChoice.MEMORY,
            simulation=SimulationSettings(**simulation),  # type: ignore[arg-type]
        ),
        processes=processes,
    )


def frames(path: Path) -> list[tuple[str, int, bytes]]:
    with path.open("rb") as stream:
        return [(c.topic, m.log_time, m.data) for _, c, m in make_reader(stream).iter_messages()]


@pytest.mark.parametrize("config", [NO_AEB, AEB], ids=["no-aeb", "aeb"])
def test_reference_sut_out_of_process_matches_the_in_process_model(
    config: SutConfig, tmp_path: Path
) -> None:
    inside = run(config, tmp_path / "inside")
    outside = run(
        dataclasses.replace(config, external=external(reference_command())), tmp_path / "outside"
    )
    assert outside.outcome.verdict is inside.outcome.verdict
    assert outside.outcome.reason == inside.outcome.reason
    recorded = frames(tmp_path / "outside" / "recording.mcap")
    assert len(recorded) > 50
    assert recorded == frames(tmp_path / "inside" / "recording.mcap")  # bit for bit
    metrics = outside.outcome.metrics
    assert metrics["sutSteps"] > 100
    assert 0.0 < metrics["sutRoundTripP50Ms"] <= metrics["sutRoundTripP99Ms"]
    versions = outside.outcome.versions
    assert versions["sut.reported"] == "simtest-reference-sut 1.0.0"
    assert versions["sut.configHash"].startswith("sha256:")
    assert "sutSteps" not in inside.outcome.metrics


def test_two_external_sut_versions_give_different_verdicts_and_say_which(
    tmp_path: Path,
) -> None:
    old = run(
        dataclasses.replace(NO_AEB, version="1.0", external=external(reference_command())), None
    )
    new = run(dataclasses.replace(AEB, version="2.0", external=external(reference_command())), None)
    assert (old.outcome.verdict, new.outcome.verdict) == (Verdict.FAILED, Verdict.PASSED)
    assert old.outcome.reason.startswith("Ego collided with Lead")
    assert old.outcome.versions["sut"] == "idm-driver 1.0"
    assert new.outcome.versions["sut"] == "idm-driver 2.0"
    assert old.outcome.versions["sut.configHash"] != new.outcome.versions["sut.configHash"]


@pytest.mark.parametrize(
    ("mode", "reason"),
    [
        ("kill", r"closed the connection .* during step 5 .*; the SUT process killed by signal 9"),
        ("slow", r"missed the 500 ms deadline for step 5 \(t=0\.200 s\)"),
        ("garbage", r"MOTION_REQUEST at step 5 is malformed: field 4 claims 64 bytes"),
        ("refuse", r"reported an error during step 5 .*: planner diverged"),
        ("exit", r"did not start: the SUT process exited with code 3: .*licence server"),
        ("version", r"speaks protocol 2, the simulator 1"),
    ],
)
def test_a_faulty_sut_ends_the_run_error_saying_why(mode: str, reason: str) -> None:
    sut = dataclasses.replace(AEB, external=external((sys.executable, str(FAULTY), mode, "5")))
    outcome = run(sut, None).outcome
    assert outcome.verdict is Verdict.ERROR
    assert re.search(reason, outcome.reason), outcome.reason


def test_a_sut_that_never_answers_the_handshake_times_out_at_start_up() -> None:
    sut = dataclasses.replace(
        AEB,
        # 5 s: the Python SUT must be listening before then, even on a loaded machine.
        external=external((sys.executable, str(FAULTY), "silent"), startup_timeout=5.0),
    )
    outcome = run(sut, None).outcome
    assert outcome.verdict is Verdict.ERROR
    assert "missed the 5000 ms deadline for the handshake (READY)" in outcome.reason


def test_a_paced_run_records_the_achieved_factor_and_flags_falling_behind() -> None:
    # Pace 5: the 8.2 s run takes 1.64 s of wall time while its own work takes ~0.15 s (about
    # 60x real time unpaced), so even a loaded machine keeps up; pacing must hold it back.
    sut = dataclasses.replace(AEB, external=external(reference_command()))
    kept = run(sut, None, real_time_factor=5.0).outcome.metrics
    assert kept["realTimeFactorTarget"] == 5.0
    assert kept["realTimeBehind"] == 0.0
    assert 5.0 * suts.KEEP_UP_TOLERANCE <= kept["loopRealTimeFactor"] <= 5.25
    slow = dataclasses.replace(
        AEB, external=external((sys.executable, str(FAULTY), "slow", "3"), step_deadline=2.0)
    )
    behind = run(slow, None, real_time_factor=20.0).outcome.metrics  # a 1 s stall in 0.41 s
    assert behind["realTimeBehind"] == 1.0
    assert behind["loopRealTimeFactor"] < 19.0


def test_in_a_pod_the_templates_endpoint_wins_over_the_campaigns() -> None:
    """A composed stack (template ``composed-sut``): the SUT already runs behind a Service the
    pod is told about in SIMTEST_SUT_ENDPOINT (read into the settings, applied to the request);
    the campaign's endpoint is where ``simtest run`` would look, and nothing listens there."""
    live, dead = free_port(), free_port()
    stack = subprocess.Popen(
        reference_command(),
        env={**os.environ, "SIMTEST_SUT_HOST": "127.0.0.1", "SIMTEST_SUT_PORT": str(live)},
        stdin=subprocess.DEVNULL,
    )
    try:
        endpoint = ExternalSut(
            launch=Launch.ENDPOINT, endpoint=f"127.0.0.1:{dead}", step_deadline=0.5,
            startup_timeout=20.0,
        )  # fmt: skip
        sut = dataclasses.replace(AEB, external=endpoint)
        in_pod = Settings.from_env({"HOME": "/h", SUT_ENDPOINT: f"127.0.0.1:{live}"})
        inside = run(AEB, None).outcome
        # the readiness wait polls until the stack accepts
        outside = run(suts.reached_here(sut, in_pod), None).outcome
        assert (outside.verdict, outside.reason) == (inside.verdict, inside.reason)
        assert outside.versions["sut.launch"] == "endpoint"
        quick = dataclasses.replace(endpoint, startup_timeout=0.3)
        elsewhere = dataclasses.replace(AEB, external=quick)
        missed = run(suts.reached_here(elsewhere, Settings.from_env({"HOME": "/h"})), None).outcome
        assert missed.verdict is Verdict.ERROR
        assert f"did not become ready at 127.0.0.1:{dead}" in missed.reason
    finally:
        stack.terminate()
        stack.wait(timeout=10)
