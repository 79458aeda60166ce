"""``simtest run``: exit codes with one-line reasons, plain progress, and Ctrl-C in a real process.

Covers: exit 0 (all passed), 1 (some failed, naming the first), 2 (an Error verdict; an invalid
manifest with the field path; a missing manifest; conflicting options) via the fake engine;
plain progress lines and the summary; a secret read from ``SIMTEST_SECRET_*``; SIGINT or SIGTERM
(issue 12: SIGTERM used to kill it, leaving the campaign ``running``) sent to a running
``simtest run`` process stops it with exit 2, kills its workers, leaves consistent outputs (every
scenario has a result, unfinished ones Skipped, the campaign ``interrupted``, no traceback), and
running the same command again resumes and finishes.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator.cli.main import cli
from simtest_operator.cli.run import env_secrets, secret_variable
from simtest_operator.errors import SourceError
from simtest_operator.scenarios import SecretRef
from tests.runner.support import alive, write_campaign

pytestmark = pytest.mark.timeout(120)


def invoke(tmp_path: Path, *args: str) -> tuple[int, str]:
    env = {"SIMTEST_CACHE_DIR": str(tmp_path / "cache")}
    result = CliRunner().invoke(cli, ["run", *args, "--engine", "fake", "--plain"], env=env)
    return result.exit_code, result.output


@pytest.mark.parametrize(
    ("behaviours", "code", "reason"),
    [
        ({"a": "pass", "b": "pass"}, 0, "all 2 scenarios passed"),
        ({"a": "pass", "b": "fail"}, 1, "1 of 2 scenarios failed (first: b.xosc: Failed: minTTC"),
        ({"a": "fail", "b": "error"}, 2, "1 of 2 scenarios could not be judged (first: b.xosc: "
                                         "Error: simulator backend lost"),
    ],
)  # fmt: skip
def test_exit_codes(tmp_path: Path, behaviours: dict[str, str], code: int, reason: str) -> None:
    manifest = write_campaign(tmp_path, behaviours, retries=0)
    exit_code, output = invoke(tmp_path, str(manifest), "-o", str(tmp_path / "out"), "-j", "2")
    assert exit_code == code, output
    assert output.rstrip().splitlines()[-1].startswith(reason)
    assert "running campaign demo: 2 of 2 scenarios on 2 worker process(es)" in output
    assert "[2/2]" in output and "report " in output and "junit " in output


def test_invalid_input_exits_2_with_a_reason(tmp_path: Path) -> None:
    manifest = write_campaign(tmp_path, {"a": "pass"})
    bad = tmp_path / "bad.yaml"
    bad.write_text(manifest.read_text().replace("timeoutSeconds: 20", "timeoutSecs: 20"))
    code, output = invoke(tmp_path, str(bad))
    assert code == 2
    assert "error: invalid manifest: spec.execution.timeoutSecs: unknown field" in output
    code, output = invoke(tmp_path)
    assert (code, "give a MANIFEST" in output) == (2, True)
    code, output = invoke(tmp_path, str(tmp_path / "missing.yaml"))
    assert code == 2 and "cannot read manifest" in output
    code, output = invoke(tmp_path, str(manifest), "--frozen", str(manifest),
                          "--rerun-failed", str(tmp_path))  # fmt: skip
    assert code == 2 and "exclude each other" in output


def test_env_secrets() -> None:
    ref = SecretRef(name="scenario-db", key="token")
    assert secret_variable(ref) == "SIMTEST_SECRET_SCENARIO_DB_TOKEN"
    assert env_secrets({"SIMTEST_SECRET_SCENARIO_DB_TOKEN": "t"})(ref) == "t"
    with pytest.raises(SourceError, match="set SIMTEST_SECRET_SCENARIO_DB_TOKEN"):
        env_secrets({})(ref)


@pytest.mark.parametrize(
    "signals",
    [
        (signal.SIGINT,),
        (signal.SIGTERM,),
        # Issue 29: a second SIGTERM 50 ms later aborted (exit 1 "Aborted!", campaign.json stayed
        # "running"); SIGHUP (a closed terminal, a CI runner's hangup) killed the run (exit 129).
        (signal.SIGTERM, signal.SIGTERM),
        (signal.SIGHUP,),
        (signal.SIGHUP, signal.SIGTERM),
    ],
    ids=lambda signals: "-".join(s.name for s in signals),
)
def test_stop_signal_stops_cleanly_and_the_same_command_resumes(
    tmp_path: Path, signals: tuple[signal.Signals, ...]
) -> None:
    behaviours = {"a": "pass", **{f"slow{i}": "sleep:1.5" for i in range(5)}}
    manifest = write_campaign(tmp_path, behaviours, batch_size=3)
    out = tmp_path / "out"
    args = [sys.executable, "-c", "from simtest_operator.cli.main import main; main()", "run",
            str(manifest), "-o", str(out), "-j", "2", "--engine", "fake", "--plain"]  # fmt: skip
    env = {**os.environ, "SIMTEST_CACHE_DIR": str(tmp_path / "cache")}
    process = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env,
                               text=True)  # fmt: skip
    assert process.stdout is not None
    lines = []
    for line in process.stdout:
        lines.append(line)
        if line.startswith("[1/6]"):
            break
    time.sleep(0.5)
    for stop_signal in signals:
        process.send_signal(stop_signal)
        time.sleep(0.05)
    rest, _ = process.communicate(timeout=60)
    output = "".join(lines) + rest
    assert process.returncode == 2, output
    assert f"stopping ({signals[0].name}): killing workers" in output
    assert "Traceback" not in output and "Aborted" not in output
    assert "interrupted after" in output.rstrip().splitlines()[-1]
    state = json.loads((out / "campaign.json").read_text())
    assert state["state"] == "interrupted"
    results = [json.loads(p.read_text()) for p in (out / "scenarios").glob("*/result.json")]
    assert len(results) == 6, "every scenario has a result file"
    assert any(r["verdict"] == "Skipped" for r in results)
    pids = [int(r["metrics"]["pid"]) for r in results if "pid" in r.get("metrics", {})]
    assert not any(alive(pid) for pid in pids), "no worker outlives the run"
    again = subprocess.run(args, capture_output=True, text=True, env=env, timeout=120, check=False)
    assert again.returncode == 0, again.stdout + again.stderr
    assert "resuming campaign demo:" in again.stdout
    assert again.stdout.rstrip().splitlines()[-1] == "all 6 scenarios passed"


def test_a_second_ctrl_c_aborts_with_exit_2(tmp_path: Path) -> None:
    """A person's second Ctrl-C aborts at once, but never with exit 1 ("the SUT failed")."""
    manifest = write_campaign(tmp_path, {f"slow{i}": "sleep:1.5" for i in range(4)})
    args = [sys.executable, "-c", "from simtest_operator.cli.main import main; main()", "run",
            str(manifest), "-o", str(tmp_path / "out"), "-j", "2", "--engine", "fake",
            "--plain"]  # fmt: skip
    env = {**os.environ, "SIMTEST_CACHE_DIR": str(tmp_path / "cache")}
    process = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env,
                               text=True)  # fmt: skip
    assert process.stdout is not None
    for line in process.stdout:
        if line.startswith("  results"):
            break
    time.sleep(0.3)
    process.send_signal(signal.SIGINT)
    time.sleep(0.02)
    process.send_signal(signal.SIGINT)
    output, _ = process.communicate(timeout=60)
    assert process.returncode == 2, output
    assert "Traceback" not in output and "Aborted!" not in output


@pytest.mark.slow
def test_smoke_campaign_end_to_end(tmp_path: Path) -> None:
    """The README's main command on the real engine: 5 of the 6 smoke scenarios pass and the
    close cut-in fails (scenarios/README.md), with every artifact in place."""
    repo = Path(__file__).resolve().parents[2]
    out = tmp_path / "out"
    args = [sys.executable, "-c", "from simtest_operator.cli.main import main; main()", "run",
            str(repo / "scenarios/smoke-campaign.yaml"), "-o", str(out), "--plain"]  # fmt: skip
    done = subprocess.run(args, capture_output=True, text=True, timeout=600, check=False)
    output = done.stdout + done.stderr
    assert done.returncode == 1, output
    last = done.stdout.rstrip().splitlines()[-1]
    assert last.startswith("1 of 6 scenarios failed (first: cut-in_highway_v30_gap8_dv12.xosc"), (
        last
    )
    results = {
        json.loads(p.read_text())["scenarioId"]: json.loads(p.read_text())
        for p in (out / "scenarios").glob("*/result.json")
    }
    assert len(results) == 6
    for document in results.values():
        assert document["verdict"] in ("Passed", "Failed")
        assert (out / document["artifacts"]["recording"]).stat().st_size > 1000
        assert (out / document["artifacts"]["log"]).read_text().startswith("--- attempt 1")
    junit = (out / "junit.xml").read_text()
    assert 'tests="6"' in junit and 'failures="1"' in junit
    assert (out / "report.html").stat().st_size > 10_000
