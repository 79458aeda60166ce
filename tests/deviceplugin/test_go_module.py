"""The device plugin's own Go tests (deploy/deviceplugin), run as part of the suite.

They cover the plugin against a fake kubelet on a temp socket: registration (version, resource,
endpoint), ListAndWatch, Allocate, re-registration after a kubelet restart, the node-label
override and the flags. The plugin against the real kubelet is in tests/realnode/. Uses the
toolchain's Go module and build caches, so it needs the module proxy only when they are cold.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

from simtest_operator.settings import Settings

MODULE = Path(__file__).resolve().parents[2] / "deploy" / "deviceplugin"


@pytest.mark.slow
def test_go_tests_of_the_device_plugin_pass() -> None:
    go = shutil.which("go")
    assert go, "Go >= 1.26 must be installed (the dev toolchain is built with it)"
    toolchain = Settings.from_env().cache.toolchain
    env = {
        **os.environ,
        "GOTOOLCHAIN": "local",
        "CGO_ENABLED": "0",
        "GOWORK": "off",
        "GOFLAGS": "-modcacherw",
        "GOMODCACHE": str(toolchain / "gomodcache"),
        "GOCACHE": str(toolchain / "gocache"),
    }
    result = subprocess.run(
        [go, "test", "-count=1", "./..."],
        cwd=MODULE,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "FAIL" not in result.stdout
