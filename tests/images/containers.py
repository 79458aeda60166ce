"""Run a command of a built image in a real container: runc on the image's root file system.

The image comes from the store ``deploy/docker/build.sh`` keeps (its ``images.json`` names the
store); ``buildah mount`` gives its root file system, and an OCI runtime config written here
runs it the way the kubelet runs a simulator pod: the image's environment and working directory
plus the pod's, a numeric user, a read-only root, a tmpfs ``/tmp``, bind mounts, every capability
dropped, ``no_new_privs``. No network namespace (the runner needs none for local scenarios).
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import subprocess
import uuid
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from simtest_operator.settings import Settings

REPO = Path(__file__).resolve().parents[2]
BUILD_SCRIPT = REPO / "deploy" / "docker" / "build.sh"
RUNC_ROOT = Path("/run/simtest-tests-runc")


@dataclasses.dataclass(frozen=True, slots=True)
class Store:
    """The buildah store of the build script (``storage`` of its ``images.json``)."""

    root: str
    runroot: str

    def buildah(self, *args: str) -> str:
        result = subprocess.run(
            [
                "buildah",
                "--root",
                self.root,
                "--runroot",
                self.runroot,
                "--storage-driver",
                "overlay",
                *args,
            ],
            capture_output=True,
            text=True,
            check=False,
        )
        if result.returncode != 0:
            raise RuntimeError(f"buildah {' '.join(args)}: {result.stderr.strip()}")
        return result.stdout.strip()


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Mount:
    source: Path
    target: str
    writable: bool = False


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ImageConfig:
    """What the image says about running it."""

    env: tuple[str, ...]
    cwd: str
    user: str
    entrypoint: tuple[str, ...]


def build(*images: str) -> dict[str, Any]:
    """Run the build script for ``images`` (cached: seconds) and return its ``images.json``."""
    result = subprocess.run(
        ["bash", str(BUILD_SCRIPT), *images], capture_output=True, text=True, check=False
    )
    if result.returncode != 0:
        raise RuntimeError(f"{BUILD_SCRIPT} {' '.join(images)} failed:\n{result.stderr[-3000:]}")
    index = Settings.from_env().cache.root / "images" / "images.json"
    data: dict[str, Any] = json.loads(index.read_text())
    return data


def image_config(store: Store, image: str) -> ImageConfig:
    data = json.loads(store.buildah("inspect", "--type", "image", image))
    config = data["OCIv1"]["config"]
    return ImageConfig(
        env=tuple(config.get("Env") or ()),
        cwd=config.get("WorkingDir") or "/",
        user=config.get("User") or "0",
        entrypoint=tuple(config.get("Entrypoint") or ()),
    )


@contextlib.contextmanager
def mounted_rootfs(store: Store, image: str) -> Iterator[Path]:
    """The image's root file system, mounted for the duration (a throw-away working container)."""
    container = store.buildah(
        "from", "--quiet", "--pull=never", "--name", f"simtest-test-{uuid.uuid4().hex[:10]}", image
    )
    try:
        yield Path(store.buildah("mount", container))
    finally:
        store.buildah("umount", container)
        store.buildah("rm", container)


def merged_env(image_env: Sequence[str], pod_env: Mapping[str, str]) -> list[str]:
    """The image's variables overridden by the pod's, as the kubelet merges them."""
    env = dict(item.split("=", 1) for item in image_env)
    env.update(pod_env)
    return [f"{key}={value}" for key, value in env.items()]


def runtime_config(
    *,
    rootfs: Path,
    args: Sequence[str],
    env: Sequence[str],
    cwd: str,
    uid: int,
    gid: int,
    mounts: Sequence[Mount],
    hostname: str = "simulator",
) -> dict[str, Any]:
    """An OCI runtime config (runc 1.1) close to what containerd makes for a restricted pod."""
    return {
        "ociVersion": "1.0.2",
        "process": {
            "terminal": False,
            "user": {"uid": uid, "gid": gid, "additionalGids": [gid]},
            "args": list(args),
            "env": list(env),
            "cwd": cwd,
            "capabilities": {
                "bounding": [],
                "effective": [],
                "permitted": [],
                "inheritable": [],
                "ambient": [],
            },
            "noNewPrivileges": True,
        },
        "root": {"path": str(rootfs), "readonly": True},
        "hostname": hostname,
        "mounts": [
            {"destination": "/proc", "type": "proc", "source": "proc"},
            {
                "destination": "/dev",
                "type": "tmpfs",
                "source": "tmpfs",
                "options": ["nosuid", "strictatime", "mode=755", "size=65536k"],
            },
            {
                "destination": "/dev/pts",
                "type": "devpts",
                "source": "devpts",
                "options": ["nosuid", "noexec", "newinstance", "ptmxmode=0666", "mode=0620"],
            },
            {
                "destination": "/dev/shm",
                "type": "tmpfs",
                "source": "shm",
                "options": ["nosuid", "noexec", "nodev", "mode=1777", "size=65536k"],
            },
            {
                "destination": "/dev/mqueue",
                "type": "mqueue",
                "source": "mqueue",
                "options": ["nosuid", "noexec", "nodev"],
            },
            {
                "destination": "/sys",
                "type": "sysfs",
                "source": "sysfs",
                "options": ["nosuid", "noexec", "nodev", "ro"],
            },
            {
                "destination": "/tmp",
                "type": "tmpfs",
                "source": "tmpfs",
                "options": ["nosuid", "nodev", "mode=1777", "size=1g"],
            },
            *(
                {
                    "destination": m.target,
                    "type": "bind",
                    "source": str(m.source),
                    "options": ["rbind", "rw" if m.writable else "ro", "nosuid", "nodev"],
                }
                for m in mounts
            ),
        ],
        "linux": {
            "namespaces": [{"type": t} for t in ("pid", "ipc", "uts", "mount")],
            "maskedPaths": [
                "/proc/acpi",
                "/proc/kcore",
                "/proc/keys",
                "/proc/latency_stats",
                "/proc/timer_list",
                "/proc/timer_stats",
                "/proc/sched_debug",
                "/proc/scsi",
                "/sys/firmware",
            ],
            "readonlyPaths": [
                "/proc/asound",
                "/proc/bus",
                "/proc/fs",
                "/proc/irq",
                "/proc/sys",
                "/proc/sysrq-trigger",
            ],
        },
    }


def run(
    bundle: Path, config: Mapping[str, Any], *, timeout: float
) -> subprocess.CompletedProcess[str]:
    """``runc run`` the config in ``bundle`` (foreground; output captured); always cleaned up."""
    (bundle / "config.json").write_text(json.dumps(config, indent=2))
    container_id = f"simtest-test-{uuid.uuid4().hex[:12]}"
    runc = ["runc", "--root", str(RUNC_ROOT)]
    try:
        return subprocess.run(
            [*runc, "run", "--bundle", str(bundle), container_id],
            capture_output=True,
            text=True,
            timeout=timeout,
            check=False,
        )
    finally:
        subprocess.run([*runc, "delete", "--force", container_id], capture_output=True, check=False)
