"""Evidence bundles: export a run from SQLite or PostgreSQL, verify offline, catch tampering.

Covers: the bundle holds the scenario and map files (digests equal to the pinned ones), the
recording (its digest equal to the one recorded at run time), verdict and metrics per scenario,
SUT and simulator records, requirements from ``req:`` tags; an unreachable recording (``s3://``)
is named by its recorded digest only; ``simtest evidence verify`` passes an untouched bundle and
fails (exit 1, one line per problem) on a changed file, an unlisted file, an edited manifest, a
recording that is not the one recorded at run time; a scenario edited since the run is not
copied; bad input is a one-line error (exit 2).
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from click.testing import CliRunner

from simtest_operator import results
from simtest_operator.cli.main import cli
from simtest_operator.results import evidence
from simtest_operator.results.querying import ReadOnlyDatabase
from simtest_operator.verdicts import Verdict
from tests.results.resultdata import T0, campaign, outcome
from tests.results.sampleoutdir import write_recording


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _write_run(target: str, root: Path) -> results.RunKey:
    """Two scenarios: a local cut-in with map and recording, a pedestrian with an S3 recording."""
    folder = root / "scenarios"
    folder.mkdir(parents=True)
    (folder / "A9.xodr").write_text("<OpenDRIVE/>\n")
    cut_in = folder / "cut-in.xosc"
    cut_in.write_text("<OpenSCENARIO><!-- cut-in --></OpenSCENARIO>\n")
    walker = folder / "walker.xosc"
    walker.write_text("<OpenSCENARIO><!-- walker --></OpenSCENARIO>\n")
    recording = write_recording(root / "out" / "recording.mcap", "cut-in.xosc")
    infos = [
        results.ScenarioInfo(scenario_id="cut-in.xosc", source=cut_in.as_uri(),
                             sha256=_sha(cut_in), road="A9.xodr",
                             tags=("highway", "req:UN-R157-5.2.5.2")),
        results.ScenarioInfo(scenario_id="walker.xosc", source=str(walker), sha256=_sha(walker),
                             tags=("req:EuroNCAP-VRU-CPNA",)),
    ]  # fmt: skip
    with results.open_store(target) as store:
        key = store.begin_campaign(campaign(), scenarios=infos)
        store.add_outcome(
            key, infos[0],
            outcome("cut-in.xosc", Verdict.FAILED, reason="collision", metrics={"minTtc": 0.4},
                    artifacts={"recording": "recording.mcap"}, versions={"sumo": "1.20.0"}),
            content_hashes={"scenario": infos[0].sha256, "recording": _sha(recording)},
            recorded_at=T0,
        )  # fmt: skip
        store.add_outcome(
            key, infos[1],
            outcome("walker.xosc", metrics={"minTtc": 2.5, "maxDecel": float("inf")},
                    artifacts={"recording": "s3://bucket/runs/walker/recording.mcap"}),
            content_hashes={"scenario": infos[1].sha256, "recording": "ab" * 32},
            recorded_at=T0,
        )  # fmt: skip
    return key


def _export(target: str, root: Path) -> tuple[evidence.Exported, Path]:
    key = _write_run(target, root)
    with ReadOnlyDatabase(target) as db:
        exported = evidence.export(db, key, root / "bundle", base_dir=root / "out")
    return exported, root / "bundle"


def test_export_then_verify(store_target: str, tmp_path: Path) -> None:
    exported, bundle = _export(store_target, tmp_path)
    digest, problems = evidence.verify(bundle)
    assert problems == () and digest == exported.manifest_sha256
    manifest = json.loads((bundle / "manifest.json").read_text())
    cut_in, walker = manifest["scenarios"]
    assert cut_in["requirements"] == ["UN-R157-5.2.5.2"] and cut_in["verdict"] == "Failed"
    items = cut_in["items"]
    assert set(items) == {"scenario", "map", "recording", "verdict", "metrics"}
    assert items["scenario"]["sha256"] == items["scenario"]["recorded_sha256"]
    assert items["recording"]["sha256"] == items["recording"]["recorded_sha256"]
    assert (bundle / items["map"]["path"]).read_text() == "<OpenDRIVE/>\n"
    assert walker["items"]["recording"] == {
        "sha256": "ab" * 32, "included": False,
        "why": "s3://bucket/runs/walker/recording.mcap not reachable"}  # fmt: skip
    assert exported.missing == (
        "walker.xosc: recording (s3://bucket/runs/walker/recording.mcap not reachable)",
    )
    metrics = json.loads((bundle / walker["items"]["metrics"]["path"]).read_text())
    assert metrics == {"maxDecel": None, "minTtc": 2.5}
    assert json.loads((bundle / "environment/sut.json").read_text()) == {
        "name": "idm-driver",
        "version": "1.4.0",
    }
    assert manifest["campaign"]["name"] == "smoke" and manifest["format"] == "simtest-evidence/1"
    assert manifest["campaign"]["run_key"].startswith("smoke-20250301T120000Z-")


def test_tampering_is_found(tmp_path: Path) -> None:
    _, bundle = _export(str(tmp_path / "results.sqlite"), tmp_path)
    manifest = json.loads((bundle / "manifest.json").read_text())
    recording = bundle / manifest["scenarios"][0]["items"]["recording"]["path"]
    recording.write_bytes(recording.read_bytes() + b"x")
    (bundle / "scenarios" / "extra.txt").write_text("hello")
    _, problems = evidence.verify(bundle)
    assert len(problems) == 2
    assert problems[0].startswith("scenarios/cut-in.xosc/recording.mcap: sha256 ")
    assert problems[1] == "scenarios/extra.txt: not listed in the manifest"
    # An edited verdict, with the manifest rewritten to match: the manifest digest gives it away.
    verdict = bundle / manifest["scenarios"][0]["items"]["verdict"]["path"]
    verdict.write_text(verdict.read_text().replace('"Failed"', '"Passed"'))
    manifest["files"][manifest["scenarios"][0]["items"]["verdict"]["path"]] = _sha(verdict)
    (bundle / "manifest.json").write_text(json.dumps(manifest))
    _, problems = evidence.verify(bundle)
    assert any(p.startswith("manifest.json: digest ") for p in problems)
    assert "cut-in.xosc: verdict.json says 'Passed', the manifest 'Failed'" in problems


def test_recording_and_scenario_changed_since_the_run(tmp_path: Path) -> None:
    target = str(tmp_path / "results.sqlite")
    key = _write_run(target, tmp_path)
    (tmp_path / "out" / "recording.mcap").write_bytes(b"not the recording")
    (tmp_path / "scenarios" / "walker.xosc").write_text("<OpenSCENARIO/>\n")
    with ReadOnlyDatabase(target) as db:
        exported = evidence.export(db, key, tmp_path / "bundle", base_dir=tmp_path / "out")
    assert any("walker.xosc: scenario (" in m and "changed since the run" in m
               for m in exported.missing)  # fmt: skip
    _, problems = evidence.verify(tmp_path / "bundle")
    assert len(problems) == 1 and "recording sha256" in problems[0]
    assert "is not the one recorded at run time" in problems[0]


def test_requirements_from_tags() -> None:
    assert evidence.requirements(("highway", "req:UN-R157-5.2.5.2", "req:", "req:A")) == (
        "A", "UN-R157-5.2.5.2")  # fmt: skip


def test_cli(tmp_path: Path) -> None:
    target = tmp_path / "out"
    target.mkdir()
    _write_run(str(target / "results.sqlite"), tmp_path)
    runner = CliRunner()
    exported = runner.invoke(cli, ["evidence", "export", str(target), "--out",
                                   str(tmp_path / "bundle")])  # fmt: skip
    assert exported.exit_code == 0, exported.output
    assert "2 scenarios, 10 files" in exported.output
    assert "digest only: walker.xosc: recording" in exported.output
    digest = exported.output.strip().splitlines()[-1].split()[-1]
    verified = runner.invoke(cli, ["evidence", "verify", str(tmp_path / "bundle")])
    assert verified.exit_code == 0 and verified.output.endswith(
        f"verified; manifest sha256 {digest}\n"
    )
    (tmp_path / "bundle" / "environment" / "sut.json").write_text("{}")
    failed = runner.invoke(cli, ["evidence", "verify", str(tmp_path / "bundle")])
    assert failed.exit_code == 1 and failed.output.startswith("FAIL environment/sut.json: sha256")
    again = runner.invoke(
        cli, ["evidence", "export", str(target), "--out", str(tmp_path / "bundle")]
    )
    assert again.exit_code == 2
    folder = tmp_path / "bundle"
    assert again.output == (
        f"simtest evidence export: evidence folder {folder} exists and is not empty\n"
    )
    unknown = runner.invoke(cli, ["evidence", "export", str(target), "--run", "nope", "--out",
                                  str(tmp_path / "b2")])  # fmt: skip
    assert unknown.exit_code == 2 and "no campaign run 'nope'" in unknown.output
    not_bundle = runner.invoke(cli, ["evidence", "verify", str(target)])
    assert not_bundle.exit_code == 2
    assert (
        not_bundle.output
        == f"simtest evidence verify: {target} is not an evidence bundle: no manifest.json\n"
    )
    missing_db = runner.invoke(cli, ["evidence", "export", str(tmp_path / "nothing.sqlite"),
                                     "--out", str(tmp_path / "b3")])  # fmt: skip
    assert missing_db.exit_code == 2 and "no results database at" in missing_db.output


# --- hostile bundles (issue 29) ------------------------------------------------------------------


def test_links_and_special_files_are_refused(tmp_path: Path) -> None:
    """A symbolic link whose target has the listed digest was ``verified``: the target is outside
    what was archived and may change after the check. Links, FIFOs and devices are refused, and
    verifying never reads through one (a FIFO would hang)."""
    _, bundle = _export(str(tmp_path / "results.sqlite"), tmp_path)
    manifest = json.loads((bundle / "manifest.json").read_text())
    recording = bundle / manifest["scenarios"][0]["items"]["recording"]["path"]
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    (outside / "recording.mcap").write_bytes(recording.read_bytes())
    recording.unlink()
    recording.symlink_to(outside / "recording.mcap")  # same digest
    (outside / "environment").mkdir()
    for name in ("sut.json", "simulator.json"):
        (outside / "environment" / name).write_bytes((bundle / "environment" / name).read_bytes())
        (bundle / "environment" / name).unlink()
    (bundle / "environment").rmdir()
    (bundle / "environment").symlink_to(outside / "environment", target_is_directory=True)
    os.mkfifo(bundle / "scenarios" / "pipe")
    _, problems = evidence.verify(bundle)
    link = "is a symbolic link (a bundle holds regular files only)"
    assert problems == (
        f"environment/simulator.json: {link}",
        f"environment/sut.json: {link}",
        f"scenarios/cut-in.xosc/recording.mcap: {link}",
        f"environment: {link}",
        "scenarios/pipe: is not a regular file",
    )
    result = CliRunner().invoke(cli, ["evidence", "verify", str(bundle)])
    assert result.exit_code == 1 and "verified" not in result.output
    (bundle / "environment").unlink()
    os.mkfifo(bundle / "environment")  # a listed path that is a FIFO on the way
    (bundle / "manifest.sha256").unlink()
    (bundle / "manifest.sha256").symlink_to(outside / "recording.mcap")
    _, problems = evidence.verify(bundle)
    assert "manifest.sha256: " + link in problems
    assert "environment/sut.json: missing" in problems
    assert "environment: is not a regular file" in problems
    manifest_file = bundle / "manifest.json"
    manifest_file.rename(outside / "manifest.json")
    manifest_file.symlink_to(outside / "manifest.json")
    refused = CliRunner().invoke(cli, ["evidence", "verify", str(bundle)])
    assert refused.exit_code == 2
    assert refused.output == (
        f"simtest evidence verify: {bundle} is not an evidence bundle: manifest.json {link}\n"
    )


def test_malformed_manifests_are_one_line(tmp_path: Path) -> None:
    """A manifest nested 100,000 deep was a RecursionError traceback."""
    bundle = tmp_path / "bundle"
    bundle.mkdir()
    deep = "[" * 100_000 + "]" * 100_000
    shaped = {"format": evidence.FORMAT, "files": {}, "scenarios": []}
    cases = {
        deep: "not a simtest-evidence/1 manifest (maximum recursion depth exceeded",
        json.dumps({**shaped, "files": {"a": json.loads("[" * 50 + "]" * 50)}}): "'files' must",
        json.dumps({**shaped, "scenarios": [1]}): "'scenarios' must be a list of objects",
        json.dumps({**shaped, "scenarios": [{"items": {"verdict": "x"}}]}): "'items' are objects",
        json.dumps([1]): "(not a JSON object)",
        json.dumps({**shaped, "format": "x" * 10_000}): "format 'xxx",
    }
    for text, message in cases.items():
        (bundle / "manifest.json").write_text(text)
        result = CliRunner().invoke(cli, ["evidence", "verify", str(bundle)])
        assert result.exit_code == 2, (message, result.output)
        assert message in result.output, result.output
        assert result.output.count("\n") == 1 and len(result.output) < 500
    verdict = bundle / "scenarios" / "verdict.json"
    verdict.parent.mkdir()
    verdict.write_text(deep)
    listed = {"scenarios/verdict.json": _sha(verdict)}
    item = {"path": "scenarios/verdict.json", "sha256": _sha(verdict), "included": True}
    entry = {"id": "a", "verdict": "Passed", "items": {"verdict": item}}
    (bundle / "manifest.json").write_text(
        json.dumps({**shaped, "files": listed, "scenarios": [entry]})
    )
    _, problems = evidence.verify(bundle)
    assert problems == ("a: verdict.json says None, the manifest 'Passed'",)
