"""``simtest evaluate`` on a real recorded run (the smoke campaign on the SUMO stand-in).

Covers: exit 1 with the failing cut-in named, the evaluation stored as a new evaluation of the
same run with base scenarios while the original verdicts stay; a lenient criteria set gives exit
0; a run whose recording ends before its simulated time has incomplete evidence and cannot pass;
a missing recording is missing evidence; recordings fetched from S3 (moto's server) by their
``s3://`` artifact URIs; runs in PostgreSQL evaluated in place; bad criteria files and sources
are exit 2 with one line naming the problem.
"""

from __future__ import annotations

import json
import shutil
import sqlite3
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator import results
from simtest_operator.cli.main import cli
from tests.evaluation import recorded_runs
from tests.results.s3server import BUCKET, CREDENTIALS, S3Server, s3

__all__ = ["s3"]  # the fixture, used by name

pytestmark = pytest.mark.timeout(300)

CUT_IN = "cut-in_highway_v30_gap8_dv12.xosc"
FOLLOWING = "following_highway_v25_thw2_drop5_d2.xosc"


@pytest.fixture(scope="module")
def smoke_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("smoke")
    manifest = recorded_runs.write_manifest(
        folder, name="smoke", source=recorded_runs.SCENARIOS / "smoke", include=["*.xosc"]
    )
    return recorded_runs.run_campaign(manifest, folder / "out")


@pytest.fixture
def run_copy(smoke_run: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(smoke_run, tmp_path / "run"))


def evaluate(*args: str, env: dict[str, str] | None = None) -> tuple[int, str]:
    result = CliRunner().invoke(cli, ["evaluate", *args], env=env)
    return result.exit_code, result.output


def _set(run: Path, sql: str, *params: object) -> None:
    with sqlite3.connect(run / "results.sqlite") as connection:
        connection.execute(sql, params)


def test_a_run_is_scored_again_and_stored_beside_its_original(run_copy: Path) -> None:
    with results.open_store(run_copy) as store:
        (record,) = store.campaigns()
        original = store.outcomes(record.run_key)
    code, output = evaluate(str(run_copy))
    assert code == 1, output
    lines = output.strip().splitlines()
    assert lines[-1].startswith(f"1 of 6 scenarios not passed (first: {CUT_IN}: Failed: cut-in")
    assert "with criteria 'default': 1 failed, 5 passed" in lines[-2]
    with results.open_store(run_copy) as store:
        assert store.outcomes(record.run_key) == original
        (evaluation,) = store.evaluations(record.run_key)
        assert evaluation.finished_at is not None
        assert evaluation.info.criteria["name"] == "default"
        runs = {r.scenario_id: r for r in store.evaluated_runs(evaluation.evaluation_id)}
    assert set(runs) == {o.scenario.scenario_id for o in original}
    assert all(r.evidence == "complete" for r in runs.values())
    cut_in = [b for b in runs[CUT_IN].base_scenarios if b.kind == "cut-in"]
    assert cut_in and cut_in[0].metrics["collision"].value == 1.0
    assert cut_in[0].metrics["minTTC"].threshold == 1.0
    assert {b.kind for b in runs[FOLLOWING].base_scenarios} >= {"following"}
    assert runs[FOLLOWING].recording.endswith("recording.mcap")


def test_a_lenient_criteria_set_passes_everything(run_copy: Path, tmp_path: Path) -> None:
    lenient = tmp_path / "lenient.yaml"
    kinds = ["free-driving", "following", "approaching", "cut-in", "cut-out", "lane-change",
             "crossing", "vru"]  # fmt: skip
    lenient.write_text(
        "name: lenient\ncollision: false\nbaseScenarios:\n"
        + "".join(f"  {kind}: {{}}\n" for kind in kinds),
        encoding="utf-8",
    )
    code, output = evaluate(str(run_copy), "--criteria", str(lenient), "-q")
    assert code == 0, output
    assert "with criteria 'lenient': 6 passed" in output
    with results.open_store(run_copy) as store:
        (record,) = store.campaigns()
        assert [e.info.criteria_name for e in store.evaluations(record.run_key)] == ["lenient"]


def test_a_recording_shorter_than_its_run_cannot_pass(run_copy: Path) -> None:
    _set(run_copy, "UPDATE runs SET simulated_seconds = 60 WHERE scenario_id = ?", FOLLOWING)
    shutil.rmtree(next((run_copy / "scenarios").glob("merge_*")))
    code, output = evaluate(str(run_copy), "-q")
    assert code == 1
    with results.open_store(run_copy) as store:
        (record,) = store.campaigns()
        (evaluation,) = store.evaluations(record.run_key)
        runs = {r.scenario_id: r for r in store.evaluated_runs(evaluation.evaluation_id)}
    following = runs[FOLLOWING]
    assert (following.verdict.value, following.evidence) == ("Error", "incomplete")
    assert following.reason.startswith("evidence incomplete: recording ends at t=10.00 s, ")
    merge = runs["merge_onramp_v25_vm20_gap35.xosc"]
    assert (merge.verdict.value, merge.evidence) == ("Error", "missing")
    assert (
        merge.reason.startswith("evidence missing: artifact ") and "does not exist" in merge.reason
    )
    assert "2 without complete evidence" in output


def test_recordings_are_fetched_from_s3(run_copy: Path, s3: S3Server) -> None:
    client = s3.client()
    with sqlite3.connect(run_copy / "results.sqlite") as connection:
        rows = connection.execute("SELECT scenario_id, artifacts FROM runs").fetchall()
        for scenario_id, artifacts in rows:
            data = json.loads(artifacts)
            key = f"nightly/{data['recording']}"
            client.upload_file(str(run_copy / data["recording"]), BUCKET, key)
            data["recording"] = f"s3://{BUCKET}/{key}"
            connection.execute(
                "UPDATE runs SET artifacts = ? WHERE scenario_id = ?",
                (json.dumps(data), scenario_id),
            )
    shutil.rmtree(run_copy / "scenarios")
    env = {
        "AWS_ENDPOINT_URL_S3": s3.endpoint,
        "AWS_ACCESS_KEY_ID": CREDENTIALS["access_key_id"],
        "AWS_SECRET_ACCESS_KEY": CREDENTIALS["secret_access_key"],
        "AWS_DEFAULT_REGION": "us-east-1",
    }
    code, output = evaluate(str(run_copy), "-q", env=env)
    assert code == 1, output
    assert "1 failed, 5 passed" in output and "0 without complete evidence" in output
    with results.open_store(run_copy) as store:
        (record,) = store.campaigns()
        (evaluation,) = store.evaluations(record.run_key)
        recordings = {r.recording for r in store.evaluated_runs(evaluation.evaluation_id)}
    assert all(uri.startswith(f"s3://{BUCKET}/nightly/") for uri in recordings)


@pytest.mark.postgres
def test_runs_in_postgresql_are_evaluated_in_place(postgres_dsn: str, tmp_path: Path) -> None:
    manifest = recorded_runs.write_manifest(
        tmp_path, name="shared", source=recorded_runs.SCENARIOS / "smoke", include=["*.xosc"]
    )
    out = recorded_runs.run_campaign(manifest, tmp_path / "out", "--db", postgres_dsn)
    assert not (out / "results.sqlite").exists()
    code, output = evaluate(postgres_dsn, "--artifacts", str(out), "-q")
    assert code == 1, output
    assert "1 failed, 5 passed" in output and "0 without complete evidence" in output
    with results.open_store(postgres_dsn) as store:
        (record,) = store.campaigns()
        (evaluation,) = store.evaluations(record.run_key)
        runs = store.evaluated_runs(evaluation.evaluation_id)
    assert len(runs) == 6 and sum(len(r.base_scenarios) for r in runs) >= 6


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("name: x\nbaseScenarios:\n  cut-in: {minTCC: 1}\n", "baseScenarios.cut-in.minTCC: "),
        ("name: x\nbaseScenarios:\n  overtaking: {}\n", "baseScenarios.overtaking: "),
        ("name: x\nlaneWidth: -1\n", "laneWidth: Input should be greater than 0"),
        ("- just a list\n", "a criteria set is a mapping"),
        ("name: [unclosed\n", "cannot read criteria"),
    ],
)
def test_bad_criteria_files_are_one_line_errors(
    run_copy: Path, tmp_path: Path, content: str, message: str
) -> None:
    criteria = tmp_path / "criteria.yaml"
    criteria.write_text(content, encoding="utf-8")
    code, output = evaluate(str(run_copy), "--criteria", str(criteria))
    assert code == 2
    (line,) = output.strip().splitlines()
    assert line.startswith("simtest evaluate: ") and message in line


def test_an_unknown_source_or_run_is_exit_2(run_copy: Path, tmp_path: Path) -> None:
    code, output = evaluate(str(tmp_path / "nowhere"))
    assert code == 2 and "no such output folder, database file or DSN" in output
    code, output = evaluate(str(run_copy), "--run", "nope-20250101T000000Z-00000000")
    assert code == 2 and output.strip() == (
        f"simtest evaluate: no run nope-20250101T000000Z-00000000 in {run_copy}"
    )


def test_the_summary_file_carries_the_outcome_for_the_operator(
    run_copy: Path, tmp_path: Path
) -> None:
    """What the evaluation Job's termination message holds; the source from the variable the
    Job's DSN arrives in."""
    summary = tmp_path / "termination-log"
    code, output = evaluate(
        "--summary-file", str(summary), "-q", env={"SIMTEST_RESULTS_DSN": str(run_copy)}
    )
    assert code == 1, output
    said = results.EvaluationMessage.from_text(summary.read_text(encoding="utf-8"))
    with results.open_store(run_copy) as store:
        (record,) = store.campaigns()
        (evaluation,) = store.evaluations(record.run_key)
    assert said.evaluation_id == evaluation.evaluation_id
    assert said.run_key == record.run_key
    first, second = output.strip().splitlines()[-2:]
    assert said.summary == f"{first}; {second}"
    code, output = evaluate(str(run_copy), "--run", "nope", "--summary-file", str(summary))
    assert code == 2
    said = results.EvaluationMessage.from_text(summary.read_text(encoding="utf-8"))
    assert said.summary == output.strip() and said.evaluation_id == ""


def test_a_long_summary_fits_the_termination_message() -> None:
    message = results.EvaluationMessage(summary="x" * 10_000, evaluation_id="e", run_key="k")
    text = message.to_text()
    assert len(text.encode()) <= 4096
    back = results.EvaluationMessage.from_text(text)
    assert back.evaluation_id == "e" and back.summary.startswith("xxx")
    crash = results.EvaluationMessage.from_text("Traceback\n  File x\nMemoryError\n")
    assert crash.summary == "Traceback | File x | MemoryError" and crash.evaluation_id == ""
