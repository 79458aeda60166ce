"""Real pods: what a simulator pod costs on the dev cluster's real node, against a local run.

kwok starts pods in zero time, so the orchestration figures measured on fake nodes hide exactly
the cost the seed paper suffers from: scheduling, sandbox and network set-up, container start,
the runner's own start-up. This bench runs the smoke campaign (six 10-second scenarios) on a
real node (kubelet 1.36 + containerd + runc, 2 simulator slots, images built by
``deploy/docker/build.sh``, scenarios from a PVC, namespace enforcing Pod Security
``restricted``) through a real ``simtest operator``, ``--repeat`` times, and watches every pod:

    created -> scheduled -> container running -> container terminated

(local monotonic timestamps of the watch events, so sub-second), plus the makespan from
``create`` to the campaign's ``Complete`` condition. The baseline in the same run: ``simtest run``
of the same manifest on this machine with 2 worker processes (same parallelism), its makespan
and per-scenario wall time.

    python bench/real_pods.py [--repeat 5] [--json bench/results/real_pods.json]

Needs root and what ``make test`` builds (toolchain, images). Prints a rich table.
"""

from __future__ import annotations

import argparse
import datetime
import json
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import yaml
from kubernetes import client, watch
from rich.console import Console
from rich.table import Table

from kwokbench import REPO, new_namespace, operator_process, percentile
from simtest_operator.devcluster import addons, images, provisioning
from simtest_operator.devcluster.cluster import DevCluster
from simtest_operator.devcluster.toolchain import Toolchain
from simtest_operator.settings import Settings

SCENARIOS = REPO / "scenarios"
SMOKE = SCENARIOS / "smoke-campaign.yaml"
SLOTS = 2
PHASES = ("scheduled", "running", "terminated")


class PodTimeline:
    """First time each simulator pod was seen created, scheduled, running and terminated."""

    def __init__(self, api: client.ApiClient, namespace: str) -> None:
        self.seen: dict[str, dict[str, float]] = {}
        self.specs: dict[str, str] = {}
        """Each pod's run spec (``SIMTEST_RUN_SPEC``): which scenarios it ran."""
        self.finished: dict[str, list[tuple[str, float]]] = {}
        """Each pod's ``finished <id>: ...`` log lines: scenario and the line's container-log
        time (on this clock), read by following the log while the pod runs (a finished pod is
        deleted at once, its log with it)."""
        self._api, self._namespace = api, namespace
        self._followers: dict[str, threading.Thread] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, args=(api, namespace), daemon=True)

    def __enter__(self) -> PodTimeline:
        self._thread.start()
        return self

    def __exit__(self, *_: object) -> None:
        self._stop.set()
        self._thread.join(timeout=10)
        for follower in list(self._followers.values()):
            follower.join(timeout=5)

    def _run(self, api: client.ApiClient, namespace: str) -> None:
        core = client.CoreV1Api(api)
        while not self._stop.is_set():
            watcher: Any = watch.Watch()  # type: ignore[no-untyped-call]
            for event in watcher.stream(
                core.list_namespaced_pod,
                namespace,
                label_selector="simtest.dev/campaign",
                timeout_seconds=2,
            ):
                now, pod = time.monotonic(), event["object"]
                marks = self.seen.setdefault(pod.metadata.name, {"created": now})
                for var in pod.spec.containers[0].env or []:
                    if var.name == "SIMTEST_RUN_SPEC" and var.value:
                        self.specs.setdefault(pod.metadata.name, var.value)
                if pod.spec.node_name:
                    marks.setdefault("scheduled", now)
                for status in pod.status.container_statuses or []:
                    if status.state.running or status.state.terminated:
                        marks.setdefault("running", now)
                        self._follow(pod.metadata.name)
                    if status.state.terminated:
                        marks.setdefault("terminated", now)

    def _follow(self, name: str) -> None:
        if name not in self._followers:
            self._followers[name] = threading.Thread(
                target=self._read_log, args=(name,), daemon=True
            )
            self._followers[name].start()

    def _read_log(self, name: str) -> None:
        """Follow one pod's log; container-log timestamps (RFC 3339) put on the monotonic clock."""
        offset = time.time() - time.monotonic()
        lines = self.finished.setdefault(name, [])
        try:
            stream = client.CoreV1Api(self._api).read_namespaced_pod_log(
                name, self._namespace, follow=True, timestamps=True, _preload_content=False
            )
            for raw in stream.stream():
                for line in raw.decode(errors="replace").splitlines():
                    stamp, _, text = line.partition(" ")
                    if text.startswith("finished ") and ": " in text:
                        when = datetime.datetime.fromisoformat(stamp.replace("Z", "+00:00"))
                        lines.append((text[9:].rsplit(": ", 1)[0], when.timestamp() - offset))
        except (client.ApiException, OSError, ValueError):
            pass  # the pod went away: what was read stays


def scenario_claim(core: client.CoreV1Api, namespace: str, root: Path = SCENARIOS) -> None:
    """``root`` (the repository's scenarios) as a read-only PVC (a hostPath volume bound to it)."""
    core.create_persistent_volume(
        {
            "metadata": {"name": f"scenarios-{namespace}"},
            "spec": {
                "capacity": {"storage": "1Gi"},
                "accessModes": ["ReadOnlyMany"],
                "storageClassName": "",
                "hostPath": {"path": str(root), "type": "Directory"},
                "claimRef": {"namespace": namespace, "name": "scenarios"},
            },
        }
    )
    core.create_namespaced_persistent_volume_claim(
        namespace,
        {
            "metadata": {"name": "scenarios"},
            "spec": {
                "accessModes": ["ReadOnlyMany"],
                "storageClassName": "",
                "volumeName": f"scenarios-{namespace}",
                "resources": {"requests": {"storage": "1Gi"}},
            },
        },
    )


def run_on_real_node(
    api: client.ApiClient, namespace: str, name: str, cpu: str
) -> tuple[float, PodTimeline]:
    manifest = yaml.safe_load(SMOKE.read_text())
    manifest["metadata"]["name"] = name
    manifest["spec"]["execution"]["resources"] = {"requests": {"cpu": cpu}, "limits": {"cpu": cpu}}
    custom = client.CustomObjectsApi(api)
    with PodTimeline(api, namespace) as timeline:
        started = time.monotonic()
        custom.create_namespaced_custom_object(
            "simtest.dev", "v1alpha1", namespace, "testcampaigns", manifest
        )
        while True:
            status = (
                custom.get_namespaced_custom_object(
                    "simtest.dev", "v1alpha1", namespace, "testcampaigns", name
                ).get("status")
                or {}
            )
            if any(
                c["type"] == "Complete" and c["status"] == "True"
                for c in status.get("conditions", [])
            ):
                break
            if time.monotonic() - started > 600:
                raise RuntimeError(f"campaign {name} not Complete after 600 s: {status}")
            time.sleep(0.1)
        makespan = time.monotonic() - started
        time.sleep(1.0)
    return makespan, timeline


def run_locally(out: Path) -> tuple[float, list[float]]:
    started = time.monotonic()
    simtest = Path(sys.executable).parent / "simtest"
    subprocess.run(
        [str(simtest), "run", str(SMOKE), "-o", str(out), "--parallel", str(SLOTS)],
        capture_output=True,
        check=False,
    )
    makespan = time.monotonic() - started
    walls = [json.loads(p.read_text())["wallSeconds"] for p in out.glob("**/result.json")]
    return makespan, walls


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument(
        "--cpu",
        default="900m",
        help="CPU request = limit per simulator pod (the campaign default, 1, lets only one pod "
        "fit next to the device plugin on 2 cores: the scheduler then backs off for seconds)",
    )
    parser.add_argument("--json", type=Path, default=REPO / "bench" / "results" / "real_pods.json")
    args = parser.parse_args()
    settings = Settings.from_env()
    toolchain = Toolchain(root=settings.cache.toolchain)
    console = Console()
    with tempfile.TemporaryDirectory(prefix="real-pods-") as tmp:
        work = Path(tmp)
        cluster = DevCluster(work / "cluster", toolchain, tied_to_this_process=True)
        up_started = time.monotonic()
        setup = images.real_node_setup(
            settings.cache.root,
            helm=toolchain.binary("helm"),
            chart=REPO / addons.CHART,
            slots=SLOTS,
            wanted=(images.RUNNER_IMAGE, images.DEVICE_PLUGIN_IMAGE),
        )
        info = cluster.up(nodes=0, real_node=setup, crds_dir=REPO / "crds", timeout=300)
        up_seconds = time.monotonic() - up_started
        api = provisioning.api_client(info.kubeconfig)
        try:
            namespace = new_namespace(api)
            client.CoreV1Api(api).patch_namespace(
                namespace,
                {"metadata": {"labels": {"pod-security.kubernetes.io/enforce": "restricted"}}},
            )
            scenario_claim(client.CoreV1Api(api), namespace)
            real: list[float] = []
            local: list[float] = []
            local_walls: list[float] = []
            phases: dict[str, list[float]] = {p: [] for p in PHASES}
            with operator_process(
                namespace=namespace,
                kubeconfig=info.kubeconfig,
                templates=REPO / "helm-templates",
                sources=SCENARIOS,
                cache=work / "cache",
                log=work / "operator.log",
                env={"SIMTEST_OPERATOR_SCENARIO_CLAIM": "scenarios"},
            ):
                for round_ in range(args.repeat):
                    makespan, timeline = run_on_real_node(
                        api, namespace, f"smoke-{round_}", args.cpu
                    )
                    real.append(makespan)
                    for marks in timeline.seen.values():
                        for phase in PHASES:
                            if phase in marks:
                                phases[phase].append(marks[phase] - marks["created"])
                    seconds, walls = run_locally(work / f"local-{round_}")
                    local.append(seconds)
                    local_walls.extend(walls)
                    console.print(
                        f"round {round_ + 1}: real node {makespan:.1f} s, local {seconds:.1f} s"
                    )
        finally:
            api.close()  # type: ignore[no-untyped-call]
            cluster.down()
    table = Table(
        title=f"smoke campaign (6 scenarios, {SLOTS} slots, cpu {args.cpu}), {args.repeat} rounds"
    )
    for column in ("measure", "p50 (s)", "p95 (s)", "n"):
        table.add_column(column, justify="right" if column != "measure" else "left")
    rows = {
        "pod created -> scheduled": phases["scheduled"],
        "pod created -> container running": phases["running"],
        "pod created -> container terminated": phases["terminated"],
        "local: scenario wall (simtest run)": local_walls,
        "makespan, real node": real,
        "makespan, simtest run (2 workers)": local,
    }
    for label, values in rows.items():
        table.add_row(
            label,
            f"{percentile(values, 0.5):.2f}",
            f"{percentile(values, 0.95):.2f}",
            str(len(values)),
        )
    console.print(table)
    ratio = statistics.median(real) / statistics.median(local)
    console.print(
        f"real node / local makespan: {ratio:.2f}x (medians); cluster up {up_seconds:.1f} s"
    )
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(
        json.dumps(
            {
                "rounds": args.repeat,
                "slots": SLOTS,
                "up_seconds": up_seconds,
                "phases": phases,
                "makespan_real": real,
                "makespan_local": local,
                "local_walls": local_walls,
            },
            indent=2,
        )
        + "\n"
    )


if __name__ == "__main__":
    main()
