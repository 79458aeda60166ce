"""The reproducibility record: lock digest, SUMO version and installed set, in every result.

Covers: the lock beside the environment is found (the checkout's ``.venv`` next to ``uv.lock``,
as ``make`` installs it) and its digest is the file's; the SUMO version is the wheel's; a real
scenario run carries the record in its result, and a local campaign stores it in the results
database's campaign row.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from simtest_operator import provenance

REPO = Path(__file__).resolve().parents[1]


def test_lock_file_is_found_beside_the_environment(tmp_path: Path) -> None:
    (tmp_path / "uv.lock").write_text("version = 1\n")
    assert provenance.lock_file(tmp_path / ".venv") == tmp_path / "uv.lock"
    assert provenance.lock_file(tmp_path / "elsewhere" / "venv") is None


@pytest.mark.skipif(
    Path(sys.prefix).parent != REPO, reason="runs in the checkout's own .venv (make test)"
)
def test_record_names_the_lock_and_the_simulator() -> None:
    record = provenance.versions()
    lock = hashlib.sha256((REPO / "uv.lock").read_bytes()).hexdigest()
    assert record["lock"] == f"sha256:{lock}"
    assert record["sumo"] == importlib.metadata.version("eclipse-sumo")
    assert record["simulator"].startswith(f"SUMO {record['sumo']} ")
    assert record["installed"].startswith("sha256:")


def test_installed_digest_follows_the_installed_set(tmp_path: Path) -> None:
    (tmp_path / "alpha-1.0.dist-info").mkdir()
    (tmp_path / "beta_pkg-2.1.dist-info").mkdir()
    before = provenance.installed_digest([str(tmp_path)])
    (tmp_path / "beta_pkg-2.1.dist-info").rename(tmp_path / "beta_pkg-2.2.dist-info")
    assert provenance.installed_digest([str(tmp_path)]) != before
    names = {
        f"{re.sub(r'[-_.]+', '-', d.metadata['Name']).lower()}=={d.version}"
        for d in importlib.metadata.distributions()
    }
    expected = "sha256:" + hashlib.sha256("\n".join(sorted(names)).encode()).hexdigest()
    assert provenance.installed_digest() == expected


@pytest.mark.slow
def test_a_scenario_result_carries_the_record(tmp_path: Path) -> None:
    scenario = REPO / "scenarios" / "smoke" / "hard-braking_rural_v15_thw2_d4.xosc"
    subprocess.run(
        [
            str(Path(sys.executable).parent / "simtest"),
            "scenario",
            "run",
            str(scenario),
            "--out",
            str(tmp_path),
            "--no-record",
        ],
        check=True,
        capture_output=True,
    )
    result = json.loads((tmp_path / "result.json").read_text())
    assert result["versions"]["sumo"] == importlib.metadata.version("eclipse-sumo")
    assert result["versions"]["lock"] == provenance.versions()["lock"]
    assert result["versions"]["sut"].startswith("idm-driver ")
