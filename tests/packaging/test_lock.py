"""The lock file: current with pyproject.toml, and what the images and set-up install from.

Covers: ``uv lock --check`` (the pinned uv of deploy/setup.sh) agrees that uv.lock satisfies
pyproject.toml — a dependency added without re-locking fails here; the set-up script installs
with ``--frozen`` only (never re-resolving); pyarrow is locked at the Arrow ABI libsumo is built
against.
"""

from __future__ import annotations

import os
import re
import subprocess
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SETUP = REPO / "deploy" / "setup.sh"


def _uv() -> Path:
    version = re.search(r"^UV_VERSION=(\S+)$", SETUP.read_text(), re.MULTILINE)
    assert version, "deploy/setup.sh pins UV_VERSION"
    cache = Path(
        os.environ.get("SIMTEST_CACHE_DIR")
        or Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "simtest"
    )
    return cache / "uv" / version.group(1) / "bin" / "uv"


def test_lock_matches_pyproject() -> None:
    result = subprocess.run(
        [str(_uv()), "lock", "--check", "--quiet"],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=False,
        env={**os.environ, "UV_PYTHON_DOWNLOADS": "never"},
    )
    assert result.returncode == 0, f"uv.lock is stale; run `make lock-upgrade`:\n{result.stderr}"


def test_setup_installs_from_the_lock_only() -> None:
    text = SETUP.read_text()
    assert "sync --frozen" in text
    assert "pip install -e" not in text and "uv lock" not in text.split("# ---")[-1]


def test_every_locked_package_has_hashes() -> None:
    lock = tomllib.loads((REPO / "uv.lock").read_text())
    for package in lock["package"]:
        if package.get("source", {}).get("editable") or package.get("source", {}).get("virtual"):
            continue
        artifacts = [
            *package.get("wheels", []),
            *([package["sdist"]] if "sdist" in package else []),
        ]
        assert artifacts, package["name"]
        assert all(a.get("hash", "").startswith("sha256:") for a in artifacts), package["name"]
