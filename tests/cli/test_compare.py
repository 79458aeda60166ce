"""``simtest compare``: two SUT versions (time headway 1.5 s vs 0.8 s) on the smoke scenarios,
recorded for real and evaluated, compared by metric values per base scenario.

Covers: the shorter headway shows up as minTHW on approaching worse, with distributions; a
``--fail-on`` rule over that change exits 1, a looser one exits 0; ``--original`` compares the
runs' own metrics; the JSON output; two evaluations of one run (default vs a strict criteria set)
differ in verdicts but not in metric values; bad rules and sources are exit 2 with one line.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from simtest_operator import results
from simtest_operator.cli.main import cli
from tests.evaluation import recorded_runs

pytestmark = pytest.mark.timeout(300)


@pytest.fixture(scope="module")
def versions(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    folder = tmp_path_factory.mktemp("versions")
    outs = []
    for version, headway in (("1.0.0", 1.5), ("1.1.0", 0.8)):
        manifest = recorded_runs.write_manifest(
            folder / version, name="smoke", source=recorded_runs.SCENARIOS / "smoke",
            include=["following_*.xosc", "hard-braking_*.xosc", "cut-in_highway_v25_*.xosc"],
            sut_version=version, time_headway=headway,
        )  # fmt: skip
        out = recorded_runs.run_campaign(manifest, folder / version / "out")
        result = CliRunner().invoke(cli, ["evaluate", str(out), "-q"])
        assert result.exit_code in (0, 1), result.output
        outs.append(out)
    return outs[0], outs[1]


def compare(*args: str) -> tuple[int, str]:
    result = CliRunner().invoke(cli, ["compare", *args])
    return result.exit_code, result.output


def test_a_shorter_headway_is_an_approaching_regression(
    versions: tuple[Path, Path], tmp_path: Path
) -> None:
    base, other = versions
    report = tmp_path / "kpis.json"
    code, output = compare(
        str(base),
        str(other),
        "--fail-on",
        "minTHW.p50@approaching:worse>0.2",
        "--json",
        str(report),
    )
    assert code == 1, output
    assert "(evaluation default-" in output.splitlines()[0]
    line = next(x for x in output.splitlines() if x.strip().startswith("minTHW on approaching"))
    assert "worse in 2 of 2" in line
    assert "rule minTHW.p50@approaching:worse>0.2: VIOLATED" in output
    assert output.strip().endswith("1 of 1 --fail-on rules violated")
    data = json.loads(report.read_text())
    (change,) = [
        c for c in data["changes"] if (c["group"], c["metric"]) == ("approaching", "minTHW")
    ]
    assert change["items"] == 2 and len(change["worse"]) == 2
    assert change["base"]["p50"] - change["other"]["p50"] == pytest.approx(change["p50WorseBy"])
    assert change["p50WorseBy"] > 0.2
    assert data["rules"] == [
        {
            "rule": "minTHW.p50@approaching:worse>0.2",
            "value": change["p50WorseBy"],
            "violated": True,
        }
    ]


def test_a_looser_gate_passes_and_the_reverse_direction_is_better(
    versions: tuple[Path, Path],
) -> None:
    base, other = versions
    code, output = compare(str(base), str(other), "--fail-on", "minTHW.p50@approaching:worse>5")
    assert code == 0, output
    code, output = compare(str(other), str(base), "--fail-on", "minTHW@approaching:worsened>0")
    assert code == 0, output
    assert "rule minTHW@approaching:worsened>0: ok (0;" in output


def test_original_metrics_are_compared_when_asked(versions: tuple[Path, Path]) -> None:
    base, other = versions
    code, output = compare(
        str(base), str(other), "--original", "--fail-on", "minTHW.p50@run:worse>0.2"
    )
    assert code == 1, output
    assert "(original verdicts)" in output.splitlines()[0]
    assert any(x.strip().startswith("minTHW on run") for x in output.splitlines())


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--fail-on", "minTHW>1"], "simtest compare: bad --fail-on rule 'minTHW>1': expected"),
        (["--run", "nope"], "simtest compare: no run nope in the store"),
        (["--evaluation", "nope"], "simtest compare: no evaluation nope of run "),
    ],
)
def test_bad_input_is_exit_2_with_one_line(
    versions: tuple[Path, Path], args: list[str], message: str
) -> None:
    base, other = versions
    code, output = compare(str(base), str(other), *args)
    assert code == 2
    (line,) = output.strip().splitlines()
    assert line.startswith(message)


def test_an_unknown_source_is_exit_2(tmp_path: Path) -> None:
    code, output = compare(str(tmp_path / "a"), str(tmp_path / "b"))
    assert code == 2 and "no such output folder, database file or DSN" in output


def test_two_evaluations_of_one_run_differ_in_verdicts_not_values(
    versions: tuple[Path, Path], tmp_path: Path
) -> None:
    base = Path(shutil.copytree(versions[0], tmp_path / "base"))
    strict = tmp_path / "strict.yaml"
    strict.write_text("name: strict\nbaseScenarios:\n  following: {minTHW: 5}\n", "utf-8")
    result = CliRunner().invoke(cli, ["evaluate", str(base), "--criteria", str(strict), "-q"])
    assert result.exit_code == 1, result.output
    with results.open_store(base) as store:
        (run,) = store.campaigns()
        evaluations = store.evaluations(run.run_key)
    by_name = {e.info.criteria_name: e.evaluation_id for e in evaluations}
    code, output = compare(
        str(base), "--base-evaluation", by_name["default"], "--evaluation", by_name["strict"],
        "--fail-on", "verdict:regressed>0,minTHW@following:worsened>0",
    )  # fmt: skip
    assert code == 1, output
    assert "rule minTHW@following:worsened>0: ok (0;" in output
    assert "rule verdict:regressed>0: VIOLATED" in output
