"""The HTML report: its view model and the rendered page.

Covers: verdict totals including never-run scenarios; per-category bars; coverage by scenario
type, road network and tag with pass rates; scenario order (failing first) with retry history;
comparison changes attached to scenarios; the page is self-contained (no external resource is
loaded), escapes scenario text, shows an unfinished-run warning, links local artifacts, and
draws trajectory and timeline SVGs; the plot limit leaves a note.
"""

from __future__ import annotations

import datetime
import re
from pathlib import Path

import pytest

from simtest_operator.results import comparing, details, publishing, reporting, reportmodel
from tests.results.resultdata import T0, sample_run

NOW = T0 + datetime.timedelta(hours=1)


def _run(*, finished: bool = True) -> reportmodel.Run:
    record, stored, listed = sample_run(finished=finished)
    return reportmodel.Run(campaign=record, outcomes=tuple(stored), scenarios=tuple(listed))


def test_totals_and_coverage() -> None:
    report = reportmodel.build(_run(), generated_at=NOW)
    assert report.total == 8
    assert dict(report.totals) == {"Passed": 3, "Failed": 1, "Timeout": 1, "Error": 0,
                                   "Invalid": 1, "Skipped": 1, "Not run": 1}  # fmt: skip
    coverage = dict(report.coverage)
    by_type = {row.label: row for row in coverage["Scenario type"]}
    assert {k: (r.total, r.passed, r.failing) for k, r in by_type.items()} == {
        "car-following": (3, 1, 1), "cut-in": (3, 1, 1), "pedestrian": (2, 1, 1),
    }  # fmt: skip
    assert by_type["cut-in"].pass_rate == 0.5  # never/ran does not count against it
    by_road = {row.label: row.total for row in coverage["Road network"]}
    assert by_road == {"(unknown)": 2, "A9.xodr": 3, "missing.xodr": 1, "town.xodr": 2}
    by_tag = {row.label: row.total for row in coverage["Tag"]}
    assert by_tag == {"(untagged)": 4, "cut-in": 1, "highway": 2, "night": 1, "urban": 2}
    assert report.duration_seconds == 42.5


def test_scenarios_failing_first_with_history() -> None:
    report = reportmodel.build(_run(), generated_at=NOW)
    order = [(s.scenario.scenario_id, s.verdict) for s in report.scenarios]
    assert order[:3] == [("broken/bad.xosc", "Invalid"), ("cut-in/close.xosc", "Failed"),
                         ("ped/night.xosc", "Timeout")]  # fmt: skip
    assert order[-1] == ("never/ran.xosc", "Not run")
    retried = next(s for s in report.scenarios if s.scenario.scenario_id == "follow/stop.xosc")
    assert (retried.verdict, retried.attempts) == ("Passed", 2)
    assert retried.history == ((1, "Error", "simulator exited with code -9"),)
    assert ("minTTC", "3.2") in retried.metrics


def test_comparison_marks_scenarios() -> None:
    run = _run()
    earlier = [s for s in run.outcomes if s.scenario.scenario_id != "cut-in/far.xosc"]
    comparison = comparing.compare(earlier, run.outcomes, base_label="yesterday")
    report = reportmodel.build(run, generated_at=NOW, comparison=comparison)
    changes = {s.scenario.scenario_id: s.change for s in report.scenarios}
    assert changes["cut-in/far.xosc"] == "new"
    assert changes["cut-in/close.xosc"] == "still failing"


@pytest.fixture
def page() -> str:
    run = _run(finished=False)
    close = next(s for s in run.outcomes if s.scenario.scenario_id == "cut-in/close.xosc")
    extra = {
        "cut-in/close.xosc": details.ScenarioDetails(
            trajectories=(
                details.Trajectory(entity="ego", points=((0, 0, 0), (5, 100, 0)), is_ego=True),
                details.Trajectory(entity="<cutter>", points=((0, 20, 3.5), (5, 90, 0))),
            ),
            timelines=(details.Timeline(name="ttc", unit="s", points=((0, 4.0), (5, 0.4))),),
        )
    }
    assert close.outcome.reason
    report = reportmodel.build(run, generated_at=NOW, details_of=extra)
    return reporting.render(report, source="/tmp/out")


def test_page_is_self_contained(page: str) -> None:
    assert page.startswith("<!DOCTYPE html>")
    assert not re.search(r"<(script|img|iframe|link)[^>]*\b(src|href)=", page)
    assert "@import" not in page
    assert not re.search(r"url\(", page)
    assert "<style>" in page
    assert "<script>" in page


def test_page_shows_counts_reasons_and_plots(page: str) -> None:
    assert 'data-count="Total">8<' in page
    assert 'data-count="Failed">1<' in page
    assert 'data-count="Not run">1<' in page
    assert "collision with &#39;cutter&#39; at t=7.2 s" in page
    assert "road network missing.xodr not found &lt;LogicFile&gt;" in page
    assert "<LogicFile>" not in page
    assert 'id="unfinished"' in page
    section = page[page.index('id="s-cut-in-close-xosc"') :]
    section = section[: section.index("</details>")]
    assert section.count("<polyline") == 3  # two trajectories and one timeline
    assert 'data-entity="&lt;cutter&gt;"' in section
    assert 'href="cut-in/close.xosc/recording.mcap"' in section
    assert "Comparison" not in page


def test_plot_limit_leaves_a_note(tmp_path: Path) -> None:
    loaded = publishing.load_details(_run(), tmp_path, limit=2)
    noted = [key for key, value in loaded.items() if value.notes]
    assert len(loaded) == 7
    assert len(noted) == 5
    assert "cut-in/close.xosc" not in noted  # failing scenarios are detailed first


def test_local_links() -> None:
    assert reporting.local_link("a b/rec.mcap") == "a%20b/rec.mcap"
    assert reporting.local_link("/data/rec.mcap") == "file:///data/rec.mcap"
    assert reporting.local_link("https://minio/x") == "https://minio/x"
    assert reporting.local_link("s3://bucket/x") == ""
