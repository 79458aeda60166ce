"""``lifetime: Worker``: one SUT process serves a worker's scenarios one after the other while it
resets between runs (READY ``"reset": true``), with the verdicts of a fresh start per scenario;
a SUT that does not reset, or that failed a run, is started anew for the next; each scenario
keeps a ``sut.log`` of its own run; a retired worker leaves no SUT behind."""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import yaml
from click.testing import CliRunner

from simtest_operator.cli.main import cli
from simtest_operator.drivermodel import Lifetime, SutConfig
from simtest_operator.sut.processes import SutProcesses
from simtest_operator.verdicts import Verdict
from tests.sut.test_lockstep import AEB, FAULTY, external, run

REPO = Path(__file__).resolve().parents[2]


def campaign(tmp_path: Path, lifetime: str) -> Path:
    manifest = yaml.safe_load((REPO / "scenarios" / "external-sut-campaign.yaml").read_text())
    manifest["spec"]["scenarios"]["sources"] = [{"path": str(REPO / "scenarios" / "smoke")}]
    manifest["spec"]["environment"]["sut"]["external"]["lifetime"] = lifetime
    path = tmp_path / f"{lifetime}.yaml"
    path.write_text(yaml.safe_dump(manifest))
    return path


def reference_suts() -> set[int]:
    """Running reference SUT processes started with this interpreter (the campaign's command)."""
    found = set()
    mine = f"{sys.executable}\0-m\0simtest_operator.sut.reference".encode()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if (entry / "cmdline").read_bytes().startswith(mine):
                    found.add(int(entry.name))
            except OSError:
                continue
    return found


def results(out: Path) -> dict[str, dict[str, object]]:
    return {
        (result := json.loads(p.read_text()))["scenarioId"]: result
        for p in out.glob("scenarios/*/result.json")
    }


def test_a_warm_sut_serves_the_workers_scenarios_with_the_fresh_verdicts(tmp_path: Path) -> None:
    found = {}
    before = reference_suts()
    for lifetime in ("Scenario", "Worker"):
        out = tmp_path / lifetime
        arguments = ["run", str(campaign(tmp_path, lifetime)), "-o", str(out), "-j", "1"]
        result = CliRunner().invoke(cli, [*arguments, "--plain"])
        assert result.exit_code == 1, result.output  # the smoke campaign's deliberate failure
        found[lifetime] = results(out)
        assert not reference_suts() - before, f"{lifetime}: a worker left its SUT running"
    fresh, warm = found["Scenario"], found["Worker"]
    assert len(fresh) == 6
    assert {k: (v["verdict"], v["reason"]) for k, v in warm.items()} == {
        k: (v["verdict"], v["reason"]) for k, v in fresh.items()
    }
    logs = {
        lifetime: {k: (tmp_path / lifetime / str(v["artifacts"]["sutLog"])).read_text()  # type: ignore[index]
                   for k, v in found[lifetime].items()}
        for lifetime in found
    }  # fmt: skip
    # A fresh SUT per scenario starts six times; the warm one once, for all six.
    assert sum("listening on" in text for text in logs["Scenario"].values()) == 6
    assert sum("listening on" in text for text in logs["Worker"].values()) == 1
    for scenario_id, text in logs["Worker"].items():
        runs = [line for line in text.splitlines() if ": run " in line]
        assert len(runs) == 1 and scenario_id in runs[0], (scenario_id, text)


def test_a_sut_that_does_not_reset_or_failed_is_started_anew(tmp_path: Path) -> None:
    def faulty(mode: str, *extra: str) -> SutConfig:
        command = (sys.executable, str(FAULTY), mode, "5", *extra)
        return dataclasses.replace(
            AEB, external=dataclasses.replace(external(command), lifetime=Lifetime.WORKER)
        )

    def started(out: Path) -> bool:
        return "faulty SUT: mode" in (out / "sut.log").read_text()

    with SutProcesses() as processes:
        # Says reset, behaves: the second run finds it warm.
        good = faulty("kill-never", "resets")
        first = run(good, tmp_path / "a", processes=processes).outcome
        second = run(good, tmp_path / "b", processes=processes).outcome
        assert (first.verdict, second.verdict) == (Verdict.PASSED, Verdict.PASSED)
        assert (started(tmp_path / "a"), started(tmp_path / "b")) == (True, False)
        # Fails a run: not trusted with the next, whatever it said.
        refusing = faulty("refuse", "resets")
        failed = run(refusing, tmp_path / "c", processes=processes).outcome
        assert failed.verdict is Verdict.ERROR
        again = run(refusing, tmp_path / "d", processes=processes).outcome
        assert again.verdict is Verdict.ERROR
        assert (started(tmp_path / "c"), started(tmp_path / "d")) == (True, True)
        # Does not say reset: a fresh process every run.
        plain = faulty("kill-never")
        for name in ("e", "f"):
            outcome = run(plain, tmp_path / name, processes=processes).outcome
            assert outcome.verdict is Verdict.PASSED, outcome.reason
            assert started(tmp_path / name)
