"""The whole local pipeline (``runner.campaigns.run``) with the fake engine in real workers.

Covers: outputs of a finished run (frozen list, state, per-scenario result with relative artifact
paths, results database rows for every attempt, JUnit and report), exit code and reason; a run
stopped mid-way leaves Skipped results and an ``interrupted`` state, and the same request resumes
it (only unfinished scenarios run, same run key, final summary over all); ``--frozen`` reproduces
the list exactly and detects a changed file; ``--rerun-failed`` runs only what did not pass;
refusals before anything runs (another manifest's output folder, a foreign non-empty folder, an
empty selection, an invalid manifest).
"""

from __future__ import annotations

import json
import threading
from pathlib import Path

import pytest

from simtest_operator import results
from simtest_operator.api.v1alpha1 import ManifestError
from simtest_operator.errors import ScenarioError
from simtest_operator.runner import campaigns, fakes, preparing, scheduling
from simtest_operator.settings import Settings
from simtest_operator.verdicts import Verdict
from tests.runner.support import write_campaign

pytestmark = pytest.mark.timeout(120)

BEHAVIOURS = {"a": "pass", "b": "fail", "cut-in/c": "sleep:0.2", "cut-in/d": "error-until:2",
              "e": "pass"}  # fmt: skip


def request(
    tmp_path: Path, manifest: Path | None, out: str = "out", **kw: object
) -> preparing.LocalRunRequest:
    return preparing.LocalRunRequest(
        manifest=manifest, output=tmp_path / out,
        settings=Settings.from_env({"HOME": str(tmp_path / "home")}), execute=fakes.execute,
        parallel=2, **kw,  # type: ignore[arg-type]
    )  # fmt: skip


def test_finished_run_outputs(tmp_path: Path) -> None:
    manifest = write_campaign(tmp_path, BEHAVIOURS)
    events: list[campaigns.Event] = []
    result = campaigns.run(request(tmp_path, manifest), on_event=events.append)
    assert result.summary.exit_code == 1
    assert result.summary.reason.startswith("1 of 5 scenarios failed (first: b.xosc: Failed")
    assert result.summary.counts[Verdict.PASSED] == 4
    assert [o.scenario_id for o in result.not_passed] == ["b.xosc"]
    assert result.scenarios_run == 6, "five scenarios, one retried once"
    prepared = events[0]
    assert isinstance(prepared, campaigns.Prepared) and prepared.total == 5
    out = tmp_path / "out"
    frozen = json.loads((out / "frozen.json").read_text())
    assert [s["id"] for s in frozen["scenarios"]] == [
        "a.xosc", "b.xosc", "cut-in/c.xosc", "cut-in/d.xosc", "e.xosc"]  # fmt: skip
    state = json.loads((out / "campaign.json").read_text())
    assert (state["state"], state["exitCode"], state["counts"]["Failed"]) == ("finished", 1, 1)
    folders = {p.name: p for p in (out / "scenarios").iterdir()}
    d_folder = next(p for n, p in folders.items() if n.startswith("cut-in__d.xosc"))
    document = json.loads((d_folder / "result.json").read_text())
    assert (document["verdict"], document["attempts"], document["batch"]) == ("Passed", 2, 1)
    assert document["artifacts"]["recording"] == f"scenarios/{d_folder.name}/recording.mcap"
    assert (out / document["artifacts"]["log"]).read_text().count("--- attempt") == 2
    with results.open_store(out) as store:
        rows = store.outcomes(results.RunKey(result.run_key), final_only=False)
        scenarios = store.scenarios(results.RunKey(result.run_key))
        campaign = store.campaign(results.RunKey(result.run_key))
    assert len(rows) == 6
    assert {s.scenario_id: s.category for s in scenarios}["cut-in/c.xosc"] == "cut-in"
    assert campaign is not None and campaign.phase == "Failed"
    assert result.junit is not None and "b.xosc" in result.junit.read_text()
    assert result.report is not None and result.report.stat().st_size > 1000


def test_interrupt_then_resume(tmp_path: Path) -> None:
    behaviours = {f"s{i}": "sleep:0.3" for i in range(6)}
    manifest = write_campaign(tmp_path, behaviours)
    stop = threading.Event()

    def stop_after_two(event: campaigns.Event) -> None:
        if isinstance(event, scheduling.Finished) and event.outcome.verdict is Verdict.PASSED:
            stop_after_two.done += 1  # type: ignore[attr-defined]
            if stop_after_two.done >= 2:  # type: ignore[attr-defined]
                stop.set()

    stop_after_two.done = 0  # type: ignore[attr-defined]
    first = campaigns.run(request(tmp_path, manifest), on_event=stop_after_two, stop=stop)
    assert first.interrupted and first.summary.exit_code == 2
    assert first.summary.reason.startswith("interrupted after")
    out = tmp_path / "out"
    assert json.loads((out / "campaign.json").read_text())["state"] == "interrupted"
    verdicts = [json.loads(p.read_text())["verdict"] for p in out.glob("scenarios/*/result.json")]
    assert len(verdicts) == 6 and "Skipped" in verdicts
    done_before = verdicts.count("Passed")
    second = campaigns.run(request(tmp_path, manifest))
    assert not second.interrupted and second.summary.exit_code == 0
    assert second.scenarios_run == 6 - done_before
    assert second.run_key == first.run_key
    with results.open_store(out) as store:
        final = store.outcomes(results.RunKey(second.run_key))
    assert sorted(o.outcome.verdict for o in final) == [Verdict.PASSED] * 6
    third = campaigns.run(request(tmp_path, manifest))
    assert third.scenarios_run == 0 and third.summary.exit_code == 0


def test_frozen_list_reproduces_and_detects_changes(tmp_path: Path) -> None:
    manifest = write_campaign(tmp_path, {"a": "pass", "b": "pass"})
    campaigns.run(request(tmp_path, manifest))
    (tmp_path / "suite/new.xosc").write_text((tmp_path / "suite/a.xosc").read_text())
    frozen = tmp_path / "out/frozen.json"
    again = campaigns.run(request(tmp_path, manifest, "again", frozen=frozen))
    assert again.summary.total == 2, "the new file is not in the frozen list"
    (tmp_path / "suite/b.xosc").write_text((tmp_path / "suite/b.xosc").read_text() + "\n")
    changed = campaigns.run(request(tmp_path, manifest, "changed", frozen=frozen))
    assert changed.summary.exit_code == 2
    (problem,) = changed.not_passed
    assert problem.verdict is Verdict.ERROR and "content changed" in problem.reason


def test_rerun_failed(tmp_path: Path) -> None:
    manifest = write_campaign(tmp_path, {"a": "pass", "b": "fail", "c": "invalid"})
    campaigns.run(request(tmp_path, manifest))
    rerun = campaigns.run(request(tmp_path, None, "rerun", rerun_failed=tmp_path / "out"))
    assert rerun.summary.total == 2
    assert sorted(o.scenario_id for o in rerun.not_passed) == ["b.xosc", "c.xosc"]
    manifest2 = write_campaign(tmp_path / "all-pass", {"a": "pass"})
    campaigns.run(request(tmp_path, manifest2, "ok"))
    with pytest.raises(ScenarioError, match="nothing to rerun"):
        campaigns.run(request(tmp_path, None, "rerun2", rerun_failed=tmp_path / "ok"))


def test_refusals_before_anything_runs(tmp_path: Path) -> None:
    manifest = write_campaign(tmp_path, {"a": "pass"})
    campaigns.run(request(tmp_path, manifest))
    other = write_campaign(tmp_path / "other", {"a": "pass"}, name="other")
    with pytest.raises(ScenarioError, match="holds a run of a different manifest"):
        campaigns.run(request(tmp_path, other))
    (tmp_path / "foreign").mkdir()
    (tmp_path / "foreign/x.txt").write_text("x")
    with pytest.raises(ScenarioError, match="holds no simtest run"):
        campaigns.run(request(tmp_path, manifest, "foreign"))
    empty = write_campaign(tmp_path / "empty", {}, extra="")
    with pytest.raises(ScenarioError, match="no scenarios selected"):
        campaigns.run(request(tmp_path, empty, "empty-out"))
    bad = tmp_path / "bad.yaml"
    bad.write_text(manifest.read_text().replace("batchSize: 2", "batchSize: 0"))
    with pytest.raises(ManifestError, match=r"spec.execution.batchSize"):
        campaigns.run(request(tmp_path, bad, "bad-out"))
    assert not (tmp_path / "bad-out").exists()
