"""Where the dev-cluster binaries are, and how to (re)build them.

The binaries are built from Go modules by ``deploy/devcluster/build.sh`` into the toolchain cache
(``CacheSettings.toolchain``); the script keeps ``<toolchain>/bin/`` pointing at the versions pinned
in ``deploy/devcluster/versions.env``. This module only locates those files and runs the script; it
never builds anything itself, so there is exactly one build recipe.
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
from pathlib import Path

from simtest_operator.errors import ToolchainError

CONTROL_PLANE_BINARIES = (
    "etcd",
    "kube-apiserver",
    "kube-controller-manager",
    "kube-scheduler",
    "kwok",
)
"""What ``DevCluster.up`` starts."""

DEVICE_PLUGIN_BINARY = "simtest-device-plugin"
"""The simulator-slot device plugin (``deploy/deviceplugin``), run beside a real node's kubelet."""

ALL_BINARIES = (
    *CONTROL_PLANE_BINARIES,
    "kubectl",
    "kwokctl",
    "helm",
    "helmfile",
    DEVICE_PLUGIN_BINARY,
    "kueue",
)
"""Everything ``build.sh`` produces (``kueue`` only for ``up --kueue``)."""

BUILD_SCRIPT = Path("deploy/devcluster/build.sh")
"""The build script, relative to the repository root."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Toolchain:
    """The built binaries under one toolchain cache directory."""

    root: Path
    """The toolchain cache, e.g. ``~/.cache/simtest/toolchain`` (``CacheSettings.toolchain``)."""

    @property
    def bin_dir(self) -> Path:
        """Symlinks to the pinned versions; put this on ``PATH`` to use kubectl, helm, ..."""
        return self.root / "bin"

    def binary(self, name: str) -> Path:
        """Absolute path of one binary; raises :class:`ToolchainError` when it is not built."""
        path = self.bin_dir / name
        if not (path.is_file() and os.access(path, os.X_OK)):
            raise ToolchainError(
                f"{name} is not built in {self.bin_dir}; run `bash {BUILD_SCRIPT}` "
                "(or `simtest dev-cluster build`) from the repository root"
            )
        return path.resolve()

    def missing(self, names: tuple[str, ...] = CONTROL_PLANE_BINARIES) -> tuple[str, ...]:
        """The binaries among ``names`` that are not built yet."""
        return tuple(
            name
            for name in names
            if not ((self.bin_dir / name).is_file() and os.access(self.bin_dir / name, os.X_OK))
        )


def find_build_script(start: Path) -> Path:
    """The build script of the repository containing ``start`` (searching upwards)."""
    for folder in (start.resolve(), *start.resolve().parents):
        candidate = folder / BUILD_SCRIPT
        if candidate.is_file():
            return candidate
    raise ToolchainError(
        f"cannot find {BUILD_SCRIPT} above {start}; run this from a simtest-operator checkout"
    )


def build(
    script: Path,
    *,
    cache_root: Path,
    log_file: Path,
    components: tuple[str, ...] = (),
) -> Toolchain:
    """Run the build script (seconds when cached) and return the toolchain it filled.

    ``cache_root`` is ``CacheSettings.root``; the script puts the toolchain under its
    ``toolchain/`` folder. Output goes to ``log_file``; on failure its tail is in the error.
    """
    log_file.parent.mkdir(parents=True, exist_ok=True)
    with log_file.open("ab") as log:
        result = subprocess.run(
            ["bash", str(script), "--cache-dir", str(cache_root), *components],
            stdout=log,
            stderr=subprocess.STDOUT,
            check=False,
        )
    if result.returncode != 0:
        tail = "\n".join(log_file.read_text(errors="replace").splitlines()[-15:])
        raise ToolchainError(
            f"{script} failed with exit code {result.returncode}; log {log_file}:\n{tail}"
        )
    return Toolchain(root=cache_root / "toolchain")
