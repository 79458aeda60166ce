"""A campaign's fetched scenario may read only its own source: the tree it was fetched into.

Covers: ``uris.source_root`` for every URI kind (the git tree, the unpacked archive, a single
download's folder, a database's or ConfigMap's files, nothing for local files); a scenario from a
git source whose road is an absolute path outside the repository ends ``Invalid`` naming the
source root, while the same scenario from a local ``path`` source outside any git work tree (the
user's own files) runs;
a road inside the repository (``../roads``) keeps working.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import yaml

from simtest_operator.scenarios import uris

REPO = Path(__file__).resolve().parents[2]
SCENARIO = REPO / "scenarios" / "smoke" / "hard-braking_rural_v15_thw2_d4.xosc"
ROAD = REPO / "scenarios" / "roads" / "rural_curved.xodr"


def test_source_root_of_each_uri_kind(tmp_path: Path) -> None:
    tree = tmp_path / "cache" / "git" / "abc"
    file = tree / "suite" / "a.xosc"
    commit = "0" * 40
    assert uris.source_root(file, f"git+https://h/r.git@{commit}#suite/a.xosc") == tree
    assert uris.source_root(file, "https://h/s.tgz#suite/a.xosc") == tree
    assert uris.source_root(file, "https://h/a.xosc") == file.parent
    assert uris.source_root(file, "graphql+https://h/graphql#suite%2Fa.xosc") == tree
    assert uris.source_root(file, "rest+https://h/api#a.xosc") == file.parent
    assert uris.source_root(file, "configmap:roads/a.xosc") == file.parent
    assert uris.source_root(file, file.as_uri()) is None


def _git(repo: Path, *args: str) -> None:
    subprocess.run(
        ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t", *args],
        check=True,
        capture_output=True,
    )


def _run(manifest: Path, out: Path, cache: Path) -> dict[str, str]:
    simtest = Path(sys.executable).parent / "simtest"
    done = subprocess.run(
        [str(simtest), "run", str(manifest), "-o", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
        env={**os.environ, "SIMTEST_CACHE_DIR": str(cache)},
    )
    assert done.returncode in (0, 1, 2), done.stderr
    results = {}
    for result in out.glob("**/result.json"):
        data = json.loads(result.read_text())
        results[data["scenarioId"]] = f"{data['verdict']}: {data.get('reason', '')}"
    return results


def _manifest(folder: Path, source: dict[str, object]) -> Path:
    body = {
        "apiVersion": "simtest.dev/v1alpha1",
        "kind": "TestCampaign",
        "metadata": {"name": "confined"},
        "spec": {
            "scenarios": {"sources": [source], "include": ["suite/*.xosc"]},
            "environment": {"simulator": {"record": False}},
        },
    }
    path = folder / "campaign.yaml"
    path.write_text(yaml.safe_dump(body))
    return path


def test_a_fetched_scenario_cannot_read_outside_its_repository(tmp_path: Path) -> None:
    outside = tmp_path / "elsewhere" / "road.xodr"
    outside.parent.mkdir()
    shutil.copy(ROAD, outside)
    repo = tmp_path / "repo"
    (repo / "suite").mkdir(parents=True)
    (repo / "roads").mkdir()
    shutil.copy(ROAD, repo / "roads" / ROAD.name)
    text = SCENARIO.read_text()
    (repo / "suite" / "inside.xosc").write_text(text)  # ../roads/rural_curved.xodr
    escaping = text.replace("../roads/rural_curved.xodr", str(outside))
    assert escaping != text
    (repo / "suite" / "escaping.xosc").write_text(escaping)
    _git(repo, "init", "-q", "-b", "main")
    _git(repo, "add", "-A")
    _git(repo, "commit", "-q", "-m", "suite")

    fetched = _run(
        _manifest(tmp_path, {"git": {"url": str(repo)}}), tmp_path / "out-git", tmp_path / "c1"
    )
    assert fetched["suite/inside.xosc"].startswith("Passed"), fetched
    verdict, _, reason = fetched["suite/escaping.xosc"].partition(": ")
    assert verdict == "Invalid", fetched
    assert "outside the scenario's source root" in reason and str(outside) in reason

    # The user's own files outside any git work tree: only system folders are refused.
    plain = tmp_path / "plain"
    shutil.copytree(repo, plain, ignore=shutil.ignore_patterns(".git"))
    local = _run(_manifest(tmp_path, {"path": str(plain)}), tmp_path / "out-path", tmp_path / "c2")
    assert local["suite/escaping.xosc"].startswith("Passed"), local
