"""The SUT interface in real pods: the Go example SUT as a native sidecar on the real node, beside
the same SUT and the in-process driver model run locally, in one run.

``bench/sut.py`` measures the protocol between two local processes. On a cluster the SUT is an
init container with ``restartPolicy: Always`` in the simulator pod (docs/sut-interface.md): its
own container, cgroup and CPU share, reached over the pod's loopback. This bench runs the
20-vehicle scenario of ``bench/simulator.py`` (SUMO backend, the SUT driving the ego from the
start) four ways, ``--repeat`` rounds in alternating order:

* ``local, in-process``: the driver model inside the simulator (``bench/sut.py``'s child);
* ``local, Go SUT process``: ``deploy/sut-go`` as a process on loopback (``bench/sut.py``'s child);
* ``pod, in-process``: one simulator pod on the real node (runner image), no SUT container;
* ``pod, Go SUT sidecar``: the same pod with the ``simtest-sut-go`` image as its sidecar.

Per variant the median run's steps per second and real-time factor of the stepping loop
(simulated seconds over the loop's wall time, start-up excluded: the runner's
``loopRealTimeFactor``; the in-process pod run is paced at an unreachable factor so that it
records it) and, with a SUT, the round trip per step p50/p99 as the simulator measured it. The
pod variants' factor excludes pod start; ``bench/real_table1.py`` measures that.

    python bench/sut_sidecar.py [--vehicles 20] [--seconds 60] [--repeat 3]

Needs root and what ``make test`` builds (toolchain, images). Results go to
``bench/results/sut_sidecar.json``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path
from types import ModuleType
from typing import Any

from kubernetes import client
from rich.console import Console
from rich.table import Table

from kwokbench import REPO, new_namespace, operator_process
from real_pods import scenario_claim
from simtest_operator.devcluster import addons, images, provisioning
from simtest_operator.devcluster.cluster import DevCluster
from simtest_operator.devcluster.toolchain import Toolchain
from simtest_operator.settings import Settings

GROUP, VERSION = "simtest.dev", "v1alpha1"
STEP = 0.05
UNREACHABLE_FACTOR = 100_000.0
"""Paces the in-process pod run without ever sleeping, so that it records its loop factor."""
VARIANTS = ("local, in-process", "local, Go SUT process", "pod, in-process", "pod, Go SUT sidecar")


def _bench_module(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"bench_{name}", Path(__file__).with_name(name))
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def scenario_tree(root: Path, vehicles: int, seconds: float) -> Path:
    """The bench scenario with its road and catalog copied beside it, referenced relatively,
    so that it reads the same from the pod's scenario volume as locally."""
    simulator = _bench_module("simulator.py")
    folder = root / "sut-bench"
    shutil.copytree(simulator.CATALOGS, folder / "catalogs")
    shutil.copy(simulator.CORPUS / "xodr" / "e6mini.xodr", folder / "e6mini.xodr")
    text: str = simulator.scenario_text(vehicles, seconds)
    text = text.replace(str(simulator.CATALOGS), "catalogs").replace(
        str(simulator.CORPUS / "xodr" / "e6mini.xodr"), "e6mini.xodr"
    )
    (folder / "bench.xosc").write_text(text, encoding="utf-8")
    return folder / "bench.xosc"


def campaign(name: str, sidecar: bool, seconds: float) -> dict[str, Any]:
    sut: dict[str, Any] = {"name": "bench", "version": "1", "takeover": "AfterInit"}
    if sidecar:
        sut["external"] = {
            "image": images.SUT_GO_IMAGE,
            "stepDeadlineMilliseconds": 1000,
            "startupTimeoutSeconds": 60,
            "resources": {"requests": {"cpu": "500m", "memory": "64Mi"}},
        }
    return {
        "apiVersion": f"{GROUP}/{VERSION}",
        "kind": "TestCampaign",
        "metadata": {"name": name},
        "spec": {
            "scenarios": {"sources": [{"path": "sut-bench"}], "include": ["bench.xosc"]},
            "environment": {
                "sut": sut,
                "simulator": {
                    "stepLength": STEP,
                    "record": False,
                    "seed": 42,
                    **({} if sidecar else {"realTimeFactor": UNREACHABLE_FACTOR}),
                },
            },
            "execution": {
                "timeoutSeconds": int(seconds * 10) + 120,
                "retries": 0,
                "resources": {"requests": {"cpu": "500m"}},
            },
        },
    }


def run_in_pod(
    custom: client.CustomObjectsApi, namespace: str, name: str, sidecar: bool, seconds: float
) -> dict[str, Any]:
    custom.create_namespaced_custom_object(
        GROUP, VERSION, namespace, "testcampaigns", campaign(name, sidecar, seconds)
    )
    deadline = time.monotonic() + seconds * 10 + 300
    while time.monotonic() < deadline:
        body = custom.get_namespaced_custom_object(GROUP, VERSION, namespace, "testcampaigns", name)
        conditions = (body.get("status") or {}).get("conditions", [])
        if any(c["type"] == "Complete" and c["status"] == "True" for c in conditions):
            batches = custom.list_namespaced_custom_object(
                GROUP,
                VERSION,
                namespace,
                "scenariobatches",
                label_selector=f"simtest.dev/campaign={name}",
            )
            (result,) = [r for b in batches["items"] for r in b["status"]["results"]]
            metrics = result.get("metrics") or {}
            return {
                "verdict": result["verdict"],
                "reason": result.get("reason", ""),
                "real_time_factor": float(metrics["loopRealTimeFactor"]),
                "p50": metrics.get("sutRoundTripP50Ms"),
                "p99": metrics.get("sutRoundTripP99Ms"),
            }
        time.sleep(0.2)
    raise RuntimeError(f"campaign {name} not Complete in time")


def run_locally(
    sut_bench: ModuleType, scenario: Path, nets: Path, variant: str, go_sut: str
) -> dict[str, Any]:
    row = sut_bench.run_child(scenario, nets, variant, go_sut)
    metrics = row["metrics"]
    return {
        "verdict": row["verdict"],
        "reason": row["reason"],
        "real_time_factor": float(row["simulated"]) / (float(row["wall"]) - float(row["startup"])),
        "p50": metrics.get("sutRoundTripP50Ms"),
        "p99": metrics.get("sutRoundTripP99Ms"),
    }


def summarise(runs: dict[str, list[dict[str, Any]]]) -> dict[str, dict[str, Any]]:
    out: dict[str, dict[str, Any]] = {}
    for variant, rows in runs.items():
        factors = sorted(r["real_time_factor"] for r in rows)
        median = statistics.median(factors)
        entry: dict[str, Any] = {
            "verdicts": sorted({r["verdict"] for r in rows}),
            "real_time_factor": round(median, 1),
            "steps_per_second": round(median / STEP, 1),
            "runs": len(rows),
        }
        if rows[0]["p50"] is not None:
            entry["round_trip_p50_ms"] = round(statistics.median(r["p50"] for r in rows), 4)
            entry["round_trip_p99_ms"] = round(statistics.median(r["p99"] for r in rows), 4)
        out[variant] = entry
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--vehicles", type=int, default=20)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument(
        "--json", type=Path, default=REPO / "bench" / "results" / "sut_sidecar.json"
    )
    args = parser.parse_args()
    settings = Settings.from_env()
    toolchain = Toolchain(root=settings.cache.toolchain)
    console = Console()
    sut_bench = _bench_module("sut.py")
    runs: dict[str, list[dict[str, Any]]] = {v: [] for v in VARIANTS}
    with tempfile.TemporaryDirectory(prefix="sut-sidecar-") as tmp:
        work = Path(tmp)
        scenario = scenario_tree(work / "scenarios", args.vehicles, args.seconds)
        go_sut = (
            subprocess.run(
                ["bash", str(REPO / "deploy" / "sut-go" / "build.sh")],
                check=True,
                capture_output=True,
                text=True,
            )
            .stdout.strip()
            .splitlines()[-1]
        )
        nets = work / "nets"
        sut_bench.run_child(scenario, nets, "in-process", go_sut)  # warm the network cache
        setup = images.real_node_setup(
            settings.cache.root,
            helm=toolchain.binary("helm"),
            chart=REPO / addons.CHART,
            slots=1,
            wanted=(images.RUNNER_IMAGE, images.DEVICE_PLUGIN_IMAGE, images.SUT_GO_IMAGE),
        )
        cluster = DevCluster(work / "cluster", toolchain, tied_to_this_process=True)
        info = cluster.up(nodes=0, real_node=setup, crds_dir=REPO / "crds", timeout=300)
        api = provisioning.api_client(info.kubeconfig)
        try:
            core, custom = client.CoreV1Api(api), client.CustomObjectsApi(api)
            namespace = new_namespace(api)
            core.patch_namespace(
                namespace,
                {"metadata": {"labels": {"pod-security.kubernetes.io/enforce": "restricted"}}},
            )
            scenario_claim(core, namespace, root=work / "scenarios")
            with operator_process(
                namespace=namespace,
                kubeconfig=info.kubeconfig,
                templates=REPO / "helm-templates",
                sources=work / "scenarios",
                cache=work / "cache",
                log=work / "operator.log",
                env={"SIMTEST_OPERATOR_SCENARIO_CLAIM": "scenarios"},
            ):
                for round_ in range(args.repeat):
                    order = VARIANTS if round_ % 2 == 0 else VARIANTS[::-1]
                    for variant in order:
                        if variant.startswith("pod"):
                            sidecar = variant.endswith("sidecar")
                            name = f"{'sidecar' if sidecar else 'inproc'}-{round_}"
                            row = run_in_pod(custom, namespace, name, sidecar, args.seconds)
                        else:
                            kind = "in-process" if variant.endswith("in-process") else "external-go"
                            row = run_locally(sut_bench, scenario, nets, kind, go_sut)
                        runs[variant].append(row)
                        console.print(f"round {round_ + 1} {variant}: {json.dumps(row)}")
        finally:
            api.close()  # type: ignore[no-untyped-call]
            cluster.down()
    summary = summarise(runs)
    table = Table(
        title=f"{args.vehicles} vehicles, {args.seconds:g} s simulated, {args.repeat} rounds "
        "(median run)"
    )
    for column in (
        "ego driven by",
        "verdicts",
        "steps/s",
        "real-time factor",
        "round trip p50 / p99",
    ):
        table.add_column(
            column, justify="left" if column in ("ego driven by", "verdicts") else "right"
        )
    for variant, entry in summary.items():
        trip = (
            f"{entry['round_trip_p50_ms']:.2f} / {entry['round_trip_p99_ms']:.2f} ms"
            if "round_trip_p50_ms" in entry
            else "-"
        )
        table.add_row(
            variant,
            ",".join(entry["verdicts"]),
            f"{entry['steps_per_second']:,.0f}",
            f"{entry['real_time_factor']:.0f}x",
            trip,
        )
    console.print(table)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({"summary": summary, "runs": runs}, indent=2) + "\n")


if __name__ == "__main__":
    main()
