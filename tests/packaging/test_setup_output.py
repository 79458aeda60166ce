"""The set-up is quiet: a newcomer's first screen shows what the product does, not build noise.

Covers (issue 17, item 1): ``bash deploy/setup.sh run`` on a set-up machine prints exactly one
``setup: ready`` line and nothing on stderr (the first call brings the machine there, so the
second is the steady state every ``make run`` after the first sees); an unknown mode is one
error line and exit 2; building the project (what ``uv sync`` does whenever pyproject changes)
emits no deprecation warnings and carries the SPDX licence expression plus the LICENSE file.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import time
import zipfile
from pathlib import Path

import pytest

pytestmark = pytest.mark.timeout(600)

REPO = Path(__file__).resolve().parents[2]
SETUP = REPO / "deploy" / "setup.sh"


def setup(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        ["bash", str(SETUP), *args], cwd=REPO, capture_output=True, text=True, check=False
    )


def cache_root() -> Path:
    """The cache setup.sh uses (same precedence as its CACHE_ROOT line)."""
    if os.environ.get("SIMTEST_CACHE_DIR"):
        return Path(os.environ["SIMTEST_CACHE_DIR"])
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(xdg) / "simtest"


def test_a_set_up_machine_gets_one_line() -> None:
    first = setup("run")
    assert first.returncode == 0, first.stdout + first.stderr
    started = time.monotonic()
    second = setup("run")
    elapsed = time.monotonic() - started
    assert second.returncode == 0, second.stdout + second.stderr
    assert second.stderr == ""
    lines = second.stdout.splitlines()
    assert len(lines) == 1, second.stdout
    assert lines[0].startswith("setup: ready (simtest, version ")
    assert lines[0].endswith(", run, from uv.lock)")
    # Only checks remain (about a second); a generous bound still catches a re-install.
    assert elapsed < 30, f"a set-up machine took {elapsed:.1f} s"


def test_an_unknown_mode_is_one_error_line() -> None:
    result = setup("everything")
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr.splitlines() == [
        "setup.sh: error: unknown mode 'everything' (run or test)"
    ]


def test_building_the_project_is_warning_free(tmp_path: Path) -> None:
    version = next(
        line.split("=", 1)[1]
        for line in SETUP.read_text().splitlines()
        if line.startswith("UV_VERSION=")
    )
    uv = cache_root() / "uv" / version / "bin" / "uv"
    assert uv.is_file(), "run deploy/setup.sh first: it installs the pinned uv"
    source = tmp_path / "src-copy"  # a copy: a build leaves build/ and egg-info behind
    source.mkdir()
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(REPO / name, source / name)
    shutil.copytree(
        REPO / "src", source / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info")
    )
    env = {**os.environ, "UV_CACHE_DIR": str(cache_root() / "uv" / "cache")}
    result = subprocess.run(
        [str(uv), "build", "--offline", "--no-python-downloads", "--wheel", "--out-dir", "dist"],
        cwd=source,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    output = result.stdout + result.stderr
    assert result.returncode == 0, output
    assert "Deprecat" not in output and "Warning" not in output, output
    (wheel,) = (source / "dist").glob("*.whl")
    with zipfile.ZipFile(wheel) as archive:
        names = archive.namelist()
        (metadata,) = (n for n in names if n.endswith(".dist-info/METADATA"))
        headers = archive.read(metadata).decode()
    assert "License-Expression: Apache-2.0" in headers.splitlines()
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names)
