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


DIGEST = "sha256:" + "5e" * 32
IMAGE_ID = "sha256:" + "1f" * 32


def _index(tmp_path: Path, images: object) -> Path:
    path = tmp_path / "images.json"
    path.write_text(json.dumps({"format": 1, "images": images}))
    return path


def test_an_image_is_named_by_digest_only_where_someone_knows_it(tmp_path: Path) -> None:
    index = _index(
        tmp_path,
        {
            "registry.local:5000/acme/planner:2.1.0": {"digest": DIGEST, "id": IMAGE_ID},
            "acme/no-digest:1": {"archive": "x.tar"},
            "acme/short-id:1": {"digest": DIGEST, "id": "sha256:" + "1" * 6},
        },
    )  # fmt: skip
    # The build index gives the image id, the form a containerd kubelet reports for an
    # imported archive (no repo digest), not the manifest digest.
    built = provenance.built_image_id("registry.local:5000/acme/planner:2.1.0", index)
    assert built == IMAGE_ID
    assert provenance.built_image_id("acme/no-digest:1", index) == ""
    assert provenance.built_image_id("acme/short-id:1", index) == ""
    assert provenance.built_image_id("acme/other:1", index) == ""
    assert provenance.built_image_id("acme/other:1", tmp_path / "missing.json") == ""
    (tmp_path / "broken.json").write_text("{")
    assert provenance.built_image_id("acme/other:1", tmp_path / "broken.json") == ""
    # A reference pinned by digest names itself (with or without its tag).
    assert provenance.pinned_image_id(f"ghcr.io/acme/planner:2.1@{DIGEST}") == (
        f"ghcr.io/acme/planner@{DIGEST}"
    )
    assert provenance.pinned_image_id("ghcr.io/acme/planner:2.1") == ""
    assert provenance.pinned_image_id("ghcr.io/acme/planner@sha256:short") == ""


@pytest.mark.parametrize(
    ("reported", "recorded"),
    [
        (f"docker.io/library/planner@{DIGEST}", f"docker.io/library/planner@{DIGEST}"),
        (DIGEST, DIGEST),
        (f"docker-pullable://planner@{DIGEST}", f"planner@{DIGEST}"),
        (f"docker://{DIGEST}", DIGEST),
        ("", ""),
        ("planner:latest", ""),
        ("sha256:ABC", ""),
    ],
)
def test_the_kubelets_image_id_is_kept_or_left_empty(reported: str, recorded: str) -> None:
    assert provenance.reported_image_id(reported) == recorded
