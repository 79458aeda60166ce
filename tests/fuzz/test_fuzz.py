"""Fuzzing the readers of untrusted input (issue 12): the OpenDRIVE and OpenSCENARIO readers, the
``${...}`` expression evaluator and the manifest loader.

Two checks per target: every committed corpus input (seeds, the hostile fixtures and each crash
fuzzing found, e.g. ``found-parampoly3-*.bin``) gives a result or a SimtestError, quickly; and a
bounded atheris run (``SIMTEST_FUZZ_SECONDS``, default 15 s per target) from that corpus finds no
crash, hang (10 s per input) or memory blow-up (1 GiB). Longer runs: ``python -m tests.fuzz``.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.fuzz.targets import CORPUS, TARGETS

SECONDS = int(os.environ.get("SIMTEST_FUZZ_SECONDS", "15"))
ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.timeout(120)
@pytest.mark.parametrize("name", TARGETS)
def test_corpus_replays_without_crash_or_hang(name: str) -> None:
    inputs = sorted((CORPUS / name).iterdir())
    assert len(inputs) >= 4, f"corpus {name} is nearly empty"
    for path in inputs:
        started = time.monotonic()
        TARGETS[name](path.read_bytes())
        assert time.monotonic() - started < 10, f"{path.name} took too long"


@pytest.mark.timeout(SECONDS + 120)
@pytest.mark.parametrize("name", TARGETS)
def test_bounded_fuzzing_finds_nothing(name: str, tmp_path: Path) -> None:
    pytest.importorskip("atheris")
    artifacts = tmp_path / "artifacts"
    command = [sys.executable, "-m", "tests.fuzz", name, "--seconds", str(SECONDS),
               "--keep", str(tmp_path / "found"), "--artifacts", str(artifacts)]  # fmt: skip
    result = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, check=False)
    found = sorted(p.name for p in artifacts.iterdir()) if artifacts.is_dir() else []
    tail = "\n".join(result.stderr.splitlines()[-40:])
    assert result.returncode == 0 and not found, f"fuzzing {name} found {found}:\n{tail}"
    assert "DONE" in result.stderr, tail
