"""The runner image, run for real: ``simtest-runner`` from
``ghcr.io/simtest-dev/simtest-runner`` in a runc container, the way the kubelet runs the
operator's simulator pod.

Covers: the pod the operator renders for a smoke scenario (``simtest render``: command, run spec,
environment, security context) runs from the image's root file system as user 65532 with the
root read-only, a tmpfs ``/tmp``, the scenario folder bind-mounted read-only, an artifacts folder
and the termination log (``/dev/termination-log``) writable; the termination message carries a
real verdict — Passed for a harmless cut-in, Failed with the collision for the close one — and
the recording lands in the artifacts; the root really is read-only for that user; the image
carries the lock it was installed from at ``SIMTEST_LOCK_FILE``.

The image comes from ``deploy/docker/build.sh runner`` (seconds when cached; a cold build takes
minutes, hence the long timeout); runc, buildah and root are needed, nothing is skipped for a
missing image.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from simtest_operator.render import messages
from simtest_operator.verdicts import Verdict
from tests.images import containers

pytestmark = [
    pytest.mark.slow,
    pytest.mark.timeout(1800),
    pytest.mark.skipif(
        sys.platform != "linux" or os.geteuid() != 0,
        reason="real containers need Linux and root (buildah, runc)",
    ),
]

IMAGE = "ghcr.io/simtest-dev/simtest-runner:0.1.0"
SCENARIOS = containers.REPO / "scenarios"
CAMPAIGN = SCENARIOS / "smoke-campaign.yaml"
UID = 65532


@pytest.fixture(scope="module")
def store() -> containers.Store:
    index = containers.build("runner")
    assert IMAGE in index["images"], f"build.sh did not record {IMAGE}"
    storage = index["storage"]
    return containers.Store(root=storage["root"], runroot=storage["runroot"])


@pytest.fixture(scope="module")
def rootfs(store: containers.Store) -> Iterator[Path]:
    with containers.mounted_rootfs(store, IMAGE) as path:
        yield path


@pytest.fixture(scope="module")
def image(store: containers.Store) -> containers.ImageConfig:
    return containers.image_config(store, IMAGE)


def rendered_pod(scenario: str, out: Path) -> dict[str, Any]:
    """The simulator pod the operator would create for one smoke scenario."""
    simtest = Path(sys.executable).with_name("simtest")
    subprocess.run(
        [str(simtest), "render", str(CAMPAIGN), "--scenario", scenario, "--out", str(out)],
        check=True,
        capture_output=True,
    )
    pod: dict[str, Any] = yaml.safe_load((out / "pod.yaml").read_text())
    return pod


def run_pod(
    pod: dict[str, Any],
    *,
    rootfs: Path,
    image: containers.ImageConfig,
    work: Path,
    args: list[str] | None = None,
) -> tuple[subprocess.CompletedProcess[str], Path, Path]:
    """Run the pod's one container in runc: (result, artifacts folder, termination log)."""
    (container,) = pod["spec"]["containers"]
    security = pod["spec"]["securityContext"]
    assert container["securityContext"]["readOnlyRootFilesystem"] is True
    mounts = {m["name"]: m["mountPath"] for m in container["volumeMounts"]}
    artifacts = work / "artifacts"
    artifacts.mkdir(mode=0o777)
    artifacts.chmod(0o777)  # an emptyDir
    termination = work / "termination-log"
    termination.touch(mode=0o666)
    termination.chmod(0o666)
    bundle = work / "bundle"
    bundle.mkdir()
    config = containers.runtime_config(
        rootfs=rootfs,
        args=args or [*container["command"], *container.get("args", [])],
        env=containers.merged_env(image.env, {e["name"]: e["value"] for e in container["env"]}),
        cwd=image.cwd,
        uid=security["runAsUser"],
        gid=security["runAsGroup"],
        mounts=[
            containers.Mount(source=SCENARIOS, target=str(SCENARIOS)),
            containers.Mount(source=artifacts, target=mounts["artifacts"], writable=True),
            containers.Mount(
                source=termination, target=container["terminationMessagePath"], writable=True
            ),
        ],
    )
    result = containers.run(bundle, config, timeout=pod["spec"]["activeDeadlineSeconds"])
    return result, artifacts, termination


@pytest.mark.parametrize(
    ("scenario", "verdict", "reason"),
    [
        ("cut-in_highway_v25_gap30_dv5.xosc", Verdict.PASSED, ""),
        ("cut-in_highway_v30_gap8_dv12.xosc", Verdict.FAILED, "collided"),
    ],
)
def test_runner_image_gives_a_real_verdict(
    scenario: str,
    verdict: Verdict,
    reason: str,
    rootfs: Path,
    image: containers.ImageConfig,
    tmp_path: Path,
) -> None:
    pod = rendered_pod(scenario, tmp_path / "rendered")
    assert pod["spec"]["securityContext"]["runAsUser"] == UID
    assert pod["spec"]["containers"][0]["image"] == IMAGE
    result, artifacts, termination = run_pod(pod, rootfs=rootfs, image=image, work=tmp_path)
    assert result.returncode == 0, f"runner exited {result.returncode}:\n{result.stderr[-3000:]}"
    (outcome,) = messages.decode(termination.read_text())
    assert outcome.scenario_id == scenario
    assert outcome.verdict is verdict, outcome.reason
    assert reason in outcome.reason
    recordings = list(artifacts.rglob("recording.mcap"))
    assert recordings, f"no recording in {sorted(p.name for p in artifacts.rglob('*'))}"
    assert all(p.stat().st_uid == UID and p.stat().st_size > 0 for p in recordings)


def test_root_is_read_only_for_the_runner_user(
    rootfs: Path, image: containers.ImageConfig, tmp_path: Path
) -> None:
    pod = rendered_pod("cut-in_highway_v25_gap30_dv5.xosc", tmp_path / "rendered")
    # Not "Permission denied": root-owned /opt would refuse 65532 anyway; the mount refuses all.
    probe = "id -u; id -g; touch /opt/simtest/probe || echo read-only; touch /tmp/probe && echo tmp"
    result, _, _ = run_pod(pod, rootfs=rootfs, image=image, work=tmp_path, args=["sh", "-c", probe])
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n") == [str(UID), str(UID), "read-only", "tmp", ""]
    assert "Read-only file system" in result.stderr


def test_image_carries_its_lock(rootfs: Path, image: containers.ImageConfig) -> None:
    env = dict(item.split("=", 1) for item in image.env)
    lock = rootfs / env["SIMTEST_LOCK_FILE"].lstrip("/")
    digest = hashlib.sha256(lock.read_bytes()).hexdigest()
    assert digest == hashlib.sha256((containers.REPO / "uv.lock").read_bytes()).hexdigest()
    assert image.user == f"{UID}:{UID}"
    assert list(image.entrypoint) == ["simtest-runner"]
