"""``simtest run`` with a ``search`` section: proposals on the worker processes.

Covers: the first wave fills every worker and later proposals follow the results; every
proposal enters ``frozen.json`` with its proposal record before it runs; ``--frozen`` reruns
exactly the proposed list without searching; an interrupted search resumes by replaying the
searcher and ends with the budget spent and the first proposals unchanged; the summary is
written (``search.json``), kept in the store with the campaign and shown in the report and the
results UI; ``simtest search export`` writes the most critical ones as concrete scenarios.
"""

from __future__ import annotations

import json
import re
import shutil
import threading
from pathlib import Path

import pytest

from simtest_operator import results
from simtest_operator.errors import ScenarioError
from simtest_operator.results.querying import ReadOnlyDatabase
from simtest_operator.runner import campaigns, preparing, scheduling, searchresults
from simtest_operator.scenarios.resolving import FetchContext
from simtest_operator.settings import Settings
from simtest_operator.ui import views
from tests.runner import search_engine

pytestmark = pytest.mark.timeout(180)

CUT_IN = Path(__file__).parents[2] / "scenarios/library/cut-in/cut-in_highway_v25_gap15_dv10.xosc"
MANIFEST = """apiVersion: simtest.dev/v1alpha1
kind: TestCampaign
metadata:
  name: search
spec:
  scenarios:
    sources:
      - path: suite
  search:
    scenario: cut-in.xosc
    parameters:
      - {name: EgoSpeed, min: 15, max: 35}
      - {name: CutInGap, min: 5, max: 40}
    strategy: random
    budget: 12
    seed: 5
  execution:
    timeoutSeconds: 30
    retries: 0
"""


def _manifest(folder: Path) -> Path:
    (folder / "suite").mkdir(parents=True)
    shutil.copy(CUT_IN, folder / "suite" / "cut-in.xosc")
    manifest = folder / "campaign.yaml"
    manifest.write_text(MANIFEST)
    return manifest


def _request(
    tmp_path: Path, manifest: Path, out: str = "out", **kw: object
) -> preparing.LocalRunRequest:
    return preparing.LocalRunRequest(
        manifest=manifest, output=tmp_path / out,
        settings=Settings.from_env({"HOME": str(tmp_path / "home")}),
        execute=search_engine.execute, parallel=3, **kw,  # type: ignore[arg-type]
    )  # fmt: skip


def _proposals(out: Path) -> list[dict[str, object]]:
    frozen = json.loads((out / "frozen.json").read_text())
    return [
        {"id": s["id"], "overrides": s["overrides"], **s["proposal"]} for s in frozen["scenarios"]
    ]


def test_a_local_search_runs_its_proposals_in_waves_and_records_them(tmp_path: Path) -> None:
    manifest = _manifest(tmp_path)
    result = campaigns.run(_request(tmp_path, manifest))
    out = tmp_path / "out"
    assert result.summary.total == 12 and not result.interrupted
    proposals = _proposals(out)
    assert [p["index"] for p in proposals] == list(range(12))
    assert [p["id"] for p in proposals] == [f"cut-in.xosc#search-{i}" for i in range(12)]
    assert [p["basis"] for p in proposals[:3]] == [0, 0, 0]  # the first wave fills the workers
    for p in proposals:
        told = [t for q in proposals[: int(p["index"]) + 1] for t in q.get("told", [])]  # type: ignore[attr-defined]
        assert p["basis"] == len(told)
    assert proposals[-1]["basis"] >= 6  # later ones learnt from the results before them
    assert result.search is not None and result.search.waves[0] == 3
    verdicts = [json.loads(r.read_text())["verdict"] for r in out.glob("scenarios/*/result.json")]
    assert sorted(set(verdicts)) == ["Failed", "Passed"], verdicts
    summary = json.loads((out / "search.json").read_text())
    assert len(summary["proposals"]) == 12
    assert summary["summary"]["failures"] == verdicts.count("Failed")
    with results.open_store(out) as store:
        (campaign,) = store.campaigns()
        assert campaign.info.settings["search"]["spec"]["budget"] == 12
        assert len(store.outcomes(campaign.run_key)) == 12
    assert 'id="search"' in (out / "report.html").read_text()
    assert "data:image/png;base64," in (out / "report.html").read_text()

    db = ReadOnlyDatabase(str(out))
    try:
        page = views.run(db, {}, views.Context(search=searchresults.section_of))
    finally:
        db.close()
    assert page["search"] is not None and len(page["search"].plots) == 1  # one parameter pair
    assert ("Failures (Failed or Timeout)", str(verdicts.count("Failed"))) in page["search"].facts

    fetch = FetchContext(base_dir=tmp_path, cache_dir=tmp_path / "cache")
    exported = searchresults.export(out, tmp_path / "regression", fetch=fetch, top=2)
    critical = json.loads((out / "search.json").read_text())["summary"]["critical"][:2]
    assert [
        re.search(rf"search-{c['index']}[_-]", p.name) is not None
        for c, p in zip(critical, exported, strict=True)
    ] == [
        True,
        True,
    ]
    values = {p["index"]: p["overrides"] for p in proposals}
    for run, path in zip(critical, exported, strict=True):
        text = path.read_text()
        for name, value in values[run["index"]].items():  # type: ignore[attr-defined]
            assert f'"{name}"' in text and f'"{value}"' in text

    again = campaigns.run(_request(tmp_path, manifest, "again", frozen=out / "frozen.json"))
    assert again.search is None and again.summary.total == 12
    rerun = json.loads((tmp_path / "again" / "frozen.json").read_text())["scenarios"]
    assert [s["overrides"] for s in rerun] == [p["overrides"] for p in proposals]


def test_an_interrupted_search_resumes_by_replaying_the_searcher(tmp_path: Path) -> None:
    manifest = _manifest(tmp_path)
    stop = threading.Event()
    finished: list[str] = []

    def stop_after_five(event: campaigns.Event) -> None:
        if isinstance(event, scheduling.Finished):
            finished.append(event.pinned.id)
            if len(finished) >= 5:
                stop.set()

    first = campaigns.run(_request(tmp_path, manifest), on_event=stop_after_five, stop=stop)
    assert first.interrupted
    before = _proposals(tmp_path / "out")
    assert 5 <= len(before) < 12
    second = campaigns.run(_request(tmp_path, manifest))
    assert not second.interrupted and second.summary.total == 12
    after = _proposals(tmp_path / "out")
    assert [p["index"] for p in after] == list(range(12))
    assert after[: len(before)] == before  # replayed, not proposed again
    uninterrupted = tmp_path / "whole"
    uninterrupted.mkdir()
    campaigns.run(_request(uninterrupted, _manifest(uninterrupted)))
    assert [p["values"] for p in _proposals(uninterrupted / "out")][:3] == [
        p["values"] for p in before[:3]
    ]  # the same seed gives the same first wave


DISTRIBUTION = """<?xml version="1.0"?>
<OpenSCENARIO>
  <FileHeader revMajor="1" revMinor="2" date="2026-01-01T00:00:00" description="d" author="a"/>
  <ParameterValueDistribution>
    <ScenarioFile filepath="cut-in.xosc"/>
    <Deterministic>
      <DeterministicSingleParameterDistribution parameterName="EgoSpeed">
        <DistributionRange stepWidth="0.5">
          <Range lowerLimit="15" upperLimit="35"/>
        </DistributionRange>
      </DeterministicSingleParameterDistribution>
    </Deterministic>
    <Stochastic numberOfTestRuns="4" randomSeed="1">
      <StochasticDistribution parameterName="CutInGap">
        <UniformDistribution><Range lowerLimit="5" upperLimit="40"/></UniformDistribution>
      </StochasticDistribution>
    </Stochastic>
  </ParameterValueDistribution>
</OpenSCENARIO>
"""


def test_a_search_over_a_distribution_runs_the_scenario_it_names(tmp_path: Path) -> None:
    """The distribution is the logical scenario (its ranges are the dimensions); the
    proposals run the scenario file it names, pinned from the same source; a resumed run
    pins the distribution again and replays."""
    manifest = _manifest(tmp_path)
    (tmp_path / "suite" / "cut-in-pvd.xosc").write_text(DISTRIBUTION)
    text = MANIFEST.replace("scenario: cut-in.xosc", "scenario: cut-in-pvd.xosc")
    text = text.replace(
        "      - {name: EgoSpeed, min: 15, max: 35}\n      - {name: CutInGap, min: 5, max: 40}\n",
        "      - {name: CutInGap, min: 10, max: 30}  # narrows the distribution's range\n",
    )
    manifest.write_text(text)
    stop = threading.Event()
    finished: list[str] = []

    def stop_after_five(event: campaigns.Event) -> None:
        if isinstance(event, scheduling.Finished):
            finished.append(event.pinned.id)
            if len(finished) >= 5:
                stop.set()

    first = campaigns.run(_request(tmp_path, manifest), on_event=stop_after_five, stop=stop)
    assert first.interrupted
    before = _proposals(tmp_path / "out")
    second = campaigns.run(_request(tmp_path, manifest))
    assert not second.interrupted and second.summary.total == 12
    after = _proposals(tmp_path / "out")
    assert after[: len(before)] == before  # replayed from the distribution, not proposed again
    assert [p["id"] for p in after] == [f"cut-in-pvd.xosc#search-{i}" for i in range(12)]
    frozen = json.loads((tmp_path / "out" / "frozen.json").read_text())["scenarios"]
    scenario = (tmp_path / "suite" / "cut-in.xosc").absolute().as_uri()
    assert {s["source"] for s in frozen} == {scenario}
    for p in after:
        values = {k: json.loads(v) for k, v in p["values"].items()}  # type: ignore[attr-defined]
        assert set(values) == {"EgoSpeed", "CutInGap"}
        assert 15 <= values["EgoSpeed"] <= 35 and (values["EgoSpeed"] * 2) % 1 == 0
        assert 10 <= values["CutInGap"] <= 30
    summary = json.loads((tmp_path / "out" / "search.json").read_text())
    assert [d["name"] for d in summary["dimensions"]] == ["EgoSpeed", "CutInGap"]
    fetch = FetchContext(base_dir=tmp_path, cache_dir=tmp_path / "cache")
    exported = searchresults.export(tmp_path / "out", tmp_path / "regression", fetch=fetch, top=1)
    assert len(exported) == 1 and "ScenarioObject" in exported[0].read_text()
    other = (tmp_path / "suite" / "cut-in.xosc").read_text() + "<!-- another file -->\n"
    (tmp_path / "suite" / "other.xosc").write_text(other)
    pvd = tmp_path / "suite" / "cut-in-pvd.xosc"
    pvd.write_text(DISTRIBUTION.replace('filepath="cut-in.xosc"', 'filepath="other.xosc"'))
    with pytest.raises(ScenarioError, match="no longer leads to the file this search ran"):
        campaigns.run(_request(tmp_path, manifest))  # resuming: the distribution changed
