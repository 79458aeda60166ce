"""``simtest-runner`` imports the runner with the cyclic collector off and runs it with it on.

Covers, in a fresh interpreter through the console script's own entry: the collector is off
while the entrypoint module is imported, on again (with the imported objects frozen) when the
entrypoint runs, and the console script is :func:`launch.main`.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

_PROBE = """
import gc, importlib.abc, json, sys
seen = {}

class Watch(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name == "simtest_operator.runner.entrypoint":
            seen["collector on while importing"] = gc.isenabled()
        return None

sys.meta_path.insert(0, Watch())
from simtest_operator.runner import launch
sys.argv = ["simtest-runner"]  # no run spec: the entrypoint runs and exits with status 2
try:
    launch.main()
except SystemExit as exit:
    seen["status"] = exit.code
seen["collector on after"] = gc.isenabled()
seen["frozen"] = gc.get_freeze_count()
print(json.dumps(seen))
"""


def test_the_runner_is_imported_with_the_collector_off() -> None:
    done = subprocess.run(
        [sys.executable, "-c", _PROBE],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
        env={"PATH": "/usr/bin:/bin"},
    )
    seen = json.loads(done.stdout)
    assert seen["collector on while importing"] is False
    assert seen["status"] == 2
    assert seen["collector on after"] is True
    assert seen["frozen"] > 1000


def test_the_console_script_is_the_launcher() -> None:
    with (ROOT / "pyproject.toml").open("rb") as file:
        scripts = tomllib.load(file)["project"]["scripts"]
    assert scripts["simtest-runner"] == "simtest_operator.runner.launch:main"
