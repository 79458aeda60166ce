"""The library generator is deterministic and the committed files are its current output.

Covers: regenerating into an empty folder gives exactly the committed set of .xosc/.xodr files,
byte for byte; running again over that output changes nothing and removes stale files.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

GENERATED = ("roads/*.xodr", "library/**/*.xosc", "smoke/*.xosc")


def _files(root: Path) -> dict[str, bytes]:
    found: dict[str, bytes] = {}
    for pattern in GENERATED:
        for path in root.glob(pattern):
            found[path.relative_to(root).as_posix()] = path.read_bytes()
    return found


def _generate(library_root: Path, out: Path) -> None:
    subprocess.run(
        [sys.executable, str(library_root / "generate.py"), "--out", str(out)],
        check=True,
        capture_output=True,
        timeout=120,
    )


@pytest.fixture(scope="module")
def generated(library_root: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("library")
    _generate(library_root, out)
    return out


def test_regenerated_files_equal_the_committed_ones(library_root: Path, generated: Path) -> None:
    fresh, committed = _files(generated), _files(library_root)
    assert sorted(fresh) == sorted(committed), "file set differs: run python scenarios/generate.py"
    changed = [name for name in fresh if fresh[name] != committed[name]]
    assert not changed, f"regenerate the library; these differ: {changed[:5]}"


def test_rerun_is_stable_and_removes_stale_files(library_root: Path, generated: Path) -> None:
    before = _files(generated)
    stale = generated / "library" / "cut-in" / "cut-in_dropped_from_the_grid.xosc"
    stale.write_bytes(b"<OpenSCENARIO/>")
    _generate(library_root, generated)
    assert not stale.exists()
    assert _files(generated) == before
