"""``simtest report`` end to end on output folders with real recordings.

Covers: the report and JUnit files are written and the summary names the run and its counts;
trajectories come from the omega-prime recordings through the recording reader (entity names,
ego first); ``--compare`` prints the change counts and adds the comparison section; a run kept
in PostgreSQL is reported with ``--database`` while artifacts come from the folder; an empty
folder or an unknown run key exits 2 with a one-line reason.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator import results
from simtest_operator.cli.main import cli
from simtest_operator.runner.campaigns import read_recording
from tests.results.sampleoutdir import make_outdir, write_recording


def test_report_with_comparison_and_junit(tmp_path: Path) -> None:
    now = make_outdir(tmp_path / "now")
    before = make_outdir(tmp_path / "before", previous=True)
    result = CliRunner().invoke(
        cli, ["report", str(now), "--compare", str(before), "--junit", str(tmp_path / "j.xml")]
    )
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    assert lines[0] == (
        f"run smoke-20250301T120000Z-0badcafe ({now}): 3 passed, 1 failed, 1 timeout, "
        "1 invalid, 1 skipped, 1 not run"
    )
    assert lines[1] == (
        f"compared with {before}: 1 removed, 1 fixed, 1 regressed, 2 still failing, 3 unchanged"
    )
    assert lines[2:] == [f"report: {now / 'report.html'}", f"junit: {tmp_path / 'j.xml'}"]
    page = (now / "report.html").read_text(encoding="utf-8")
    assert 'data-change="regressed">1<' in page
    assert 'id="comparison"' in page
    close = page[page.index('id="s-cut-in-close-xosc"') :]
    close = close[: close.index("</details>")]
    assert 'data-entity="ego"' in close
    assert 'data-entity="object 1"' in close
    assert "ttc [s]" in close
    assert "<testsuite " in (tmp_path / "j.xml").read_text(encoding="utf-8")


def test_recording_reader_names_the_ego(tmp_path: Path) -> None:
    path = write_recording(tmp_path / "rec.mcap", "x.xosc", crossing=True)
    paths = read_recording(path)
    assert [(p.entity, p.is_ego) for p in paths] == [("ego", True), ("object 1", False)]
    ego = paths[0].points
    assert len(ego) == 101
    assert ego[0][0] == 0.0
    assert ego[-1][0] == 10.0
    assert ego[-1][1] == pytest.approx(100.0)


@pytest.mark.postgres
def test_report_from_postgres(tmp_path: Path, postgres_dsn: str) -> None:
    outdir = make_outdir(tmp_path / "out", database=postgres_dsn)
    assert not (outdir / "results.sqlite").exists()
    result = CliRunner().invoke(
        cli, ["report", str(outdir), "--database", postgres_dsn, "--out", str(tmp_path / "r.html")]
    )
    assert result.exit_code == 0, result.output
    assert "1 failed" in result.output
    assert "postgresql://127.0.0.1:" in result.output
    page = (tmp_path / "r.html").read_text(encoding="utf-8")
    assert 'data-entity="ego"' in page


def test_empty_folder_and_unknown_run_exit_2(tmp_path: Path) -> None:
    result = CliRunner().invoke(cli, ["report", str(tmp_path)])
    assert result.exit_code == 2
    assert result.output.strip() == (
        f"simtest report: no results database at {tmp_path / 'results.sqlite'}"
    )
    assert list(tmp_path.iterdir()) == []
    results.open_store(tmp_path / "empty.sqlite").close()
    result = CliRunner().invoke(cli, ["report", str(tmp_path), "--compare", str(tmp_path / "x")])
    assert result.exit_code == 2
    make_outdir(tmp_path / "out")
    result = CliRunner().invoke(
        cli, ["report", str(tmp_path / "out"), "--database", str(tmp_path / "empty.sqlite")]
    )
    assert result.output.strip() == "simtest report: the results store holds no campaign run yet"
    result = CliRunner().invoke(cli, ["report", str(tmp_path / "out"), "--run", "nope"])
    assert result.exit_code == 2
    assert "no campaign run 'nope'" in result.output
