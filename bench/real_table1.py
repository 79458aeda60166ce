"""The seed paper's Table 1 with real pods: real SUMO scenarios in real containers on the real node.

``bench/operator_table1.py`` measures the orchestration on kwok, where a pod costs nothing. Here
every simulator is a container the kubelet starts (containerd + runc, the runner image, scenarios
from a PVC, Pod Security ``restricted``), so pod start, sandbox, image and Python start-up are
paid as on a cluster. For each number of simulator slots ``s`` (the node's
``simtest.dev/simulator`` capacity, one dev cluster per ``s``) a campaign of real scenarios from
``scenarios/library`` runs, batch size 9, with the paper's batch barrier and our refilled window,
each with one pod per scenario (``PerScenario``) and with warm pods (``Reuse``). The scenarios are
paced (``simulator.realTimeFactor``) so each one takes seconds of wall time, as a simulator
coupled to a real-time stack would, and the timeouts scaled to match.

Reported per run: makespan; the lower bound ``max(W / s, max d)`` with ``d`` each scenario's
run time measured by the runner and ``W`` their sum, and makespan / bound; pod start latency
(bound to the node -> container running) p50/p95; orchestration overhead per scenario p50/p95
(each pod's time from getting a slot to its end, minus the run time of its scenarios, per
scenario); API requests per scenario (the operator's own client, from its /metrics). A prefetched
pod waiting Pending for a slot is queueing and counts in neither.

    python bench/real_table1.py                                 # 60 scenarios, s = 1, 2, 3
    python bench/real_table1.py --scenarios 30 --s 2 --name quick

The maps' networks are shipped beside them first (``simtest scenario nets``, as a user stages a
scenario volume), so pods run no netconvert; ``--no-shipped-nets`` takes them away.

Needs root and what ``make test`` builds (toolchain, images). Results go to
``bench/results/real_table1[-NAME].{json,md,png}``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import shutil
import statistics
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from kubernetes import client
from rich.console import Console
from rich.table import Table

from kwokbench import (
    REPO,
    metric_total,
    new_namespace,
    operator_metrics,
    operator_process,
    percentile,
)
from real_pods import PodTimeline, scenario_claim
from simtest_operator.devcluster import addons, images, provisioning
from simtest_operator.devcluster.cluster import DevCluster
from simtest_operator.devcluster.toolchain import Toolchain
from simtest_operator.render import RunSpec
from simtest_operator.settings import Settings
from simtest_operator.sim import netcache

SCENARIOS = REPO / "scenarios"
LIBRARY = SCENARIOS / "library"
ROADS = SCENARIOS / "roads"
"""The library's maps (``../../roads/*.xodr``)."""
GROUP, VERSION = "simtest.dev", "v1alpha1"
NODE_CPU_MILLIS = 1800
"""CPU the simulator pods of the 2-core node share (the rest: kubelet, device plugin, operator)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Config:
    slots: int
    barrier: bool
    reuse: bool
    baseline: bool = False
    """Run with the ``--baseline`` operator settings (the product as it was before a cut)."""

    @property
    def label(self) -> str:
        mode = "barrier" if self.barrier else "window"
        suffix = " (baseline)" if self.baseline else ""
        return f"s{self.slots}-{mode}-{'Reuse' if self.reuse else 'PerScenario'}{suffix}"


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Result:
    config: Config
    scenarios: int
    passed: int
    makespan: float
    work: float
    """Sum of the scenarios' run times as the runner measured them (s)."""
    bound: float
    bound_ratio: float
    """bound / makespan: the share of the best possible speed the whole system reaches."""
    start_p50: float
    start_p95: float
    overhead_p50: float
    overhead_p95: float
    api_requests_per_scenario: float
    scenario_overhead_p50: float = float("nan")
    """Per scenario, not per pod: the slot time from the previous scenario's end in the same pod
    (or the pod's binding) to this one's ``finished`` log line, minus its run; the pod's exit
    counts to its last scenario. Equal to the per-pod figure with a pod per scenario; with warm
    pods it separates the warm gap from the pod start."""
    scenario_overhead_p95: float = float("nan")
    refill_p50: float = float("nan")
    """Seconds a freed slot stays empty: from a pod's end to the next pod's binding."""
    refill_p95: float = float("nan")
    durations: dict[str, float] = dataclasses.field(default_factory=dict)
    """Each scenario's run time as the runner measured it (s)."""
    marks: dict[str, dict[str, float]] = dataclasses.field(default_factory=dict)
    """Each pod's timeline (seconds since the campaign was created), for later analysis."""


def pick(count: int) -> list[str]:
    """``count`` library scenarios spread evenly over its types (ids relative to the library)."""
    files = sorted(p.relative_to(LIBRARY).as_posix() for p in LIBRARY.rglob("*.xosc"))
    step = max(len(files) / count, 1.0)
    return [files[int(i * step)] for i in range(min(count, len(files)))]


def ship_nets(*, remove: bool) -> None:
    """Stage the maps as a user would (``simtest scenario nets``), or take the networks away."""
    for xodr in sorted(ROADS.glob("*.xodr")):
        if remove:
            shutil.rmtree(netcache.shipped_dir(xodr), ignore_errors=True)
        else:
            netcache.ship_net(xodr)


def campaign(name: str, ids: Sequence[str], config: Config, args: argparse.Namespace) -> Any:
    cpu = f"{NODE_CPU_MILLIS // config.slots}m"
    return {
        "apiVersion": f"{GROUP}/{VERSION}",
        "kind": "TestCampaign",
        "metadata": {"name": name},
        "spec": {
            "scenarios": {"sources": [{"path": "library"}], "include": list(ids)},
            "environment": {
                "sut": {"name": "idm-driver", "version": "1.0.0"},
                "simulator": {
                    "realTimeFactor": args.real_time_factor,
                    "record": True,
                    "seed": 42,
                },
            },
            "execution": {
                "batchSize": 9,
                "batchBarrier": config.barrier,
                "isolation": "Reuse" if config.reuse else "PerScenario",
                "maxSimulatorsPerNode": config.slots,
                "timeoutSeconds": args.timeout,
                "pendingTimeoutSeconds": 3600,
                "retries": 0,
                "resources": {"requests": {"cpu": cpu}, "limits": {"cpu": cpu}},
            },
            "evaluation": {"criteria": {"collision": "Forbidden", "minTtc": 1.5}},
        },
    }


def wait_complete(custom: client.CustomObjectsApi, namespace: str, name: str) -> dict[str, Any]:
    deadline = time.monotonic() + 3600
    while time.monotonic() < deadline:
        body = custom.get_namespaced_custom_object(GROUP, VERSION, namespace, "testcampaigns", name)
        status: dict[str, Any] = body.get("status") or {}
        if any(
            c["type"] == "Complete" and c["status"] == "True" for c in status.get("conditions", [])
        ):
            return status
        time.sleep(0.1)
    raise RuntimeError(f"campaign {name} not Complete after an hour")


def results_of(custom: client.CustomObjectsApi, namespace: str) -> dict[str, dict[str, Any]]:
    batches = custom.list_namespaced_custom_object(GROUP, VERSION, namespace, "scenariobatches")
    return {
        r["id"]: r for b in batches["items"] for r in (b.get("status") or {}).get("results", [])
    }


def scenario_overheads(
    marks: dict[str, float], finished: Sequence[tuple[str, float]], runs: dict[str, float]
) -> list[float]:
    """Each scenario's share of its pod's slot time beyond its run (see ``Result``)."""
    out: list[float] = []
    previous = marks["scheduled"]
    for index, (scenario, at) in enumerate(finished):
        end = marks["terminated"] if index == len(finished) - 1 else at
        out.append(max(end - previous - runs.get(scenario, 0.0), 0.0))
        previous = at
    return out


def run_one(
    api: client.ApiClient,
    kubeconfig: Path,
    config: Config,
    ids: Sequence[str],
    args: argparse.Namespace,
    workdir: Path,
) -> Result:
    core, custom = client.CoreV1Api(api), client.CustomObjectsApi(api)
    namespace = new_namespace(api)
    core.patch_namespace(
        namespace, {"metadata": {"labels": {"pod-security.kubernetes.io/enforce": "restricted"}}}
    )
    scenario_claim(core, namespace)
    with operator_process(
        namespace=namespace,
        kubeconfig=kubeconfig,
        templates=REPO / "helm-templates",
        sources=SCENARIOS,
        cache=workdir / "cache",
        log=workdir / f"{config.label}.log",
        env={
            "SIMTEST_OPERATOR_SCENARIO_CLAIM": "scenarios",
            **dict(args.operator_env),
            **(dict(args.baseline) if config.baseline else {}),
        },
    ) as (_, port):
        before = metric_total(operator_metrics(port), "simtest_api_requests_total")
        with PodTimeline(api, namespace) as timeline:
            started = time.monotonic()
            custom.create_namespaced_custom_object(
                GROUP, VERSION, namespace, "testcampaigns", campaign("t1", ids, config, args)
            )
            wait_complete(custom, namespace, "t1")
            makespan = time.monotonic() - started
            time.sleep(1.0)
        requests = metric_total(operator_metrics(port), "simtest_api_requests_total") - before
    found = results_of(custom, namespace)
    runs = {i: float(r.get("durationSeconds", 0.0)) for i, r in found.items()}
    work = sum(runs.values())
    bound = max(work / config.slots, max(runs.values(), default=0.0))
    # From the moment the scheduler gave the pod a slot (prefetched pods wait Pending for one,
    # which is queueing, not overhead): container start, then the runner's work around the runs.
    starts, overheads, per_scenario = [], [], []
    for name, marks in timeline.seen.items():
        if "running" in marks and "scheduled" in marks:
            starts.append(marks["running"] - marks["scheduled"])
        spec = timeline.specs.get(name)
        if spec is None or "terminated" not in marks or "scheduled" not in marks:
            continue
        queue = [s.id for s in RunSpec.loads(spec).scenarios]
        ran = sum(runs.get(i, 0.0) for i in queue)
        overheads.append((marks["terminated"] - marks["scheduled"] - ran) / len(queue))
        per_scenario.extend(scenario_overheads(marks, timeline.finished.get(name, []), runs))
    ends = sorted(m["terminated"] for m in timeline.seen.values() if "terminated" in m)
    binds = sorted(m["scheduled"] for m in timeline.seen.values() if "scheduled" in m)
    refills = []
    for end in ends:
        later = [b for b in binds if b >= end]
        if later:
            refills.append(later[0] - end)
    client.CoreV1Api(api).delete_persistent_volume(f"scenarios-{namespace}")
    return Result(
        config=config,
        scenarios=len(found),
        passed=sum(1 for r in found.values() if r["verdict"] == "Passed"),
        makespan=round(makespan, 2),
        work=round(work, 2),
        bound=round(bound, 2),
        bound_ratio=round(bound / makespan, 3),
        start_p50=round(percentile(starts, 0.5), 2),
        start_p95=round(percentile(starts, 0.95), 2),
        overhead_p50=round(percentile(overheads, 0.5), 2),
        overhead_p95=round(percentile(overheads, 0.95), 2),
        scenario_overhead_p50=round(percentile(per_scenario, 0.5), 2),
        scenario_overhead_p95=round(percentile(per_scenario, 0.95), 2),
        api_requests_per_scenario=round(requests / max(len(found), 1), 1),
        refill_p50=round(percentile(refills, 0.5), 2),
        refill_p95=round(percentile(refills, 0.95), 2),
        durations=runs,
        marks={
            name: {
                **{k: round(v - started, 3) for k, v in marks.items()},
                **{
                    f"finished {i}": round(at - started, 3)
                    for i, at in timeline.finished.get(name, [])
                },
            }
            for name, marks in timeline.seen.items()
        },
    )


def table(results: Sequence[Result], title: str) -> Table:
    out = Table(title=title)
    columns = (
        "config", "n", "passed", "makespan s", "work s", "bound s", "bound/makespan",
        "pod start p50/p95 s", "overhead/pod p50/p95 s", "overhead/scenario p50/p95 s",
        "refill p50/p95 s", "API req/scenario",
    )  # fmt: skip
    for column in columns:
        out.add_column(column, justify="left" if column == "config" else "right")
    for r in results:
        out.add_row(
            r.config.label, str(r.scenarios), str(r.passed), f"{r.makespan:.1f}",
            f"{r.work:.1f}", f"{r.bound:.1f}", f"{r.bound_ratio:.2f}",
            f"{r.start_p50:.2f} / {r.start_p95:.2f}",
            f"{r.overhead_p50:.2f} / {r.overhead_p95:.2f}",
            f"{r.scenario_overhead_p50:.2f} / {r.scenario_overhead_p95:.2f}",
            f"{r.refill_p50:.2f} / {r.refill_p95:.2f}",
            f"{r.api_requests_per_scenario:.1f}",
        )  # fmt: skip
    return out


def markdown(results: Sequence[Result]) -> str:
    lines = [
        "| config | n | makespan s | work s | bound s | bound/makespan | pod start p50/p95 s "
        "| overhead/pod p50/p95 s | overhead/scenario p50/p95 s | refill p50/p95 s "
        "| API req/scenario |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {r.config.label} | {r.scenarios} | {r.makespan:.1f} | {r.work:.1f} | {r.bound:.1f} "
        f"| {r.bound_ratio:.2f} | {r.start_p50:.2f} / {r.start_p95:.2f} "
        f"| {r.overhead_p50:.2f} / {r.overhead_p95:.2f} "
        f"| {r.scenario_overhead_p50:.2f} / {r.scenario_overhead_p95:.2f} "
        f"| {r.refill_p50:.2f} / {r.refill_p95:.2f} "
        f"| {r.api_requests_per_scenario:.1f} |"
        for r in results
    ]
    return "\n".join(lines) + "\n"


def plot(results: Sequence[Result], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.5))
    labels = [r.config.label for r in results]
    left.barh(labels, [r.bound_ratio for r in results], color="tab:blue")
    left.axvline(0.90, color="tab:orange", ls="--", label="goal PerScenario 0.90")
    left.axvline(0.95, color="tab:green", ls="--", label="goal Reuse 0.95")
    left.set_xlabel("lower bound / makespan (1 = no orchestration cost)")
    left.set_xlim(0, 1.05)
    left.legend(loc="lower right", fontsize=8)
    left.invert_yaxis()
    right.barh(labels, [r.scenario_overhead_p50 for r in results], color="tab:red", label="p50")
    right.barh(
        labels,
        [max(r.scenario_overhead_p95 - r.scenario_overhead_p50, 0.0) for r in results],
        left=[r.scenario_overhead_p50 for r in results],
        color="tab:pink",
        label="to p95",
    )
    right.set_xlabel("orchestration overhead per scenario (s)")
    right.legend(loc="lower right", fontsize=8)
    right.invert_yaxis()
    right.set_yticklabels([])
    fig.suptitle("Real pods on the real node: slots, window vs barrier, PerScenario vs Reuse")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenarios", type=int, default=60)
    parser.add_argument("--s", default="1,2,3", help="simulator slots of the node, comma-separated")
    parser.add_argument("--real-time-factor", type=float, default=4.0)
    parser.add_argument("--timeout", type=int, default=35, help="timeoutSeconds per scenario")
    parser.add_argument("--name", default="")
    parser.add_argument(
        "--configs",
        default="window-PerScenario,window-Reuse,barrier-PerScenario,barrier-Reuse",
        help="which of the four runs per s, comma-separated",
    )
    parser.add_argument(
        "--no-shipped-nets",
        action="store_true",
        help="remove the converted networks shipped beside the maps (`simtest scenario nets`): "
        "every pod runs netconvert, as before session 10",
    )
    parser.add_argument(
        "--operator-env",
        action="append",
        default=[],
        type=lambda text: tuple(text.split("=", 1)),
        metavar="NAME=VALUE",
        help="an environment variable for the operator, e.g. SIMTEST_OPERATOR_PREFETCH=0",
    )
    parser.add_argument(
        "--baseline",
        action="append",
        default=[],
        type=lambda text: tuple(text.split("=", 1)),
        metavar="NAME=VALUE",
        help="also run every window config with this operator setting, side by side "
        "(e.g. SIMTEST_OPERATOR_RELEASE_EXITED=false, the graceful delete before the cut)",
    )
    parser.add_argument(
        "--from-json",
        nargs="+",
        type=Path,
        default=[],
        metavar="FILE",
        help="run nothing: write the table and plot of these results files (several: merged)",
    )
    args = parser.parse_args()
    console = Console()
    if args.from_json:
        results, title = loaded(args.from_json)
    else:
        results, title = measure(args, console)
    write(results, title, args.name, console)


def loaded(paths: Sequence[Path]) -> tuple[list[Result], str]:
    """The results of earlier runs, in file order, and the first file's title."""
    results: list[Result] = []
    titles: list[str] = []
    for path in paths:
        data = json.loads(path.read_text())
        titles.append(data["title"])
        for item in data["results"]:
            config = Config(**item.pop("config"))
            results.append(Result(config=config, **item))
    return results, titles[0]


def measure(args: argparse.Namespace, console: Console) -> tuple[list[Result], str]:
    """Run every configuration of ``args`` on a real-node dev cluster per ``s``."""
    settings = Settings.from_env()
    toolchain = Toolchain(root=settings.cache.toolchain)
    ids = pick(args.scenarios)
    ship_nets(remove=args.no_shipped_nets)
    results: list[Result] = []
    with tempfile.TemporaryDirectory(prefix="real-table1-") as tmp:
        work = Path(tmp)
        for slots in (int(s) for s in args.s.split(",")):
            setup = images.real_node_setup(
                settings.cache.root,
                helm=toolchain.binary("helm"),
                chart=REPO / addons.CHART,
                slots=slots,
                wanted=(images.RUNNER_IMAGE, images.DEVICE_PLUGIN_IMAGE),
            )
            cluster = DevCluster(work / f"cluster-s{slots}", toolchain, tied_to_this_process=True)
            info = cluster.up(nodes=0, real_node=setup, crds_dir=REPO / "crds", timeout=300)
            api = provisioning.api_client(info.kubeconfig)
            try:
                for label in args.configs.split(","):
                    mode, isolation = label.split("-")
                    variants = (False, True) if args.baseline and mode == "window" else (False,)
                    for baseline in variants:
                        config = Config(
                            slots=slots,
                            barrier=mode == "barrier",
                            reuse=isolation == "Reuse",
                            baseline=baseline,
                        )
                        result = run_one(api, info.kubeconfig, config, ids, args, work)
                        results.append(result)
                        console.print(table([result], config.label))
            finally:
                api.close()  # type: ignore[no-untyped-call]
                cluster.down()
    title = (
        f"{len(ids)} library scenarios, real node, realTimeFactor {args.real_time_factor}, "
        "batch size 9"
    )
    return results, title


def write(results: Sequence[Result], title: str, name: str, console: Console) -> None:
    """Print the table and the comparisons; write the JSON, markdown and plot."""
    console.print(table(results, title))
    stem = REPO / "bench" / "results" / ("real_table1" + (f"-{name}" if name else ""))
    stem.parent.mkdir(parents=True, exist_ok=True)
    stem.with_suffix(".json").write_text(
        json.dumps({"title": title, "results": [dataclasses.asdict(r) for r in results]}, indent=2)
        + "\n"
    )
    stem.with_suffix(".md").write_text(markdown(results))
    plot(results, stem.with_suffix(".png"))
    window = [r for r in results if not r.config.barrier and not r.config.baseline]
    barrier = {(r.config.slots, r.config.reuse): r for r in results if r.config.barrier}
    before = {(r.config.slots, r.config.reuse): r for r in results if r.config.baseline}
    for r in window:
        old = before.get((r.config.slots, r.config.reuse))
        if old is not None:
            console.print(
                f"{r.config.label}: makespan {r.makespan / old.makespan:.2f}x the baseline's, "
                f"bound/makespan {old.bound_ratio:.2f} -> {r.bound_ratio:.2f}, "
                f"refill p50 {old.refill_p50:.2f} -> {r.refill_p50:.2f} s"
            )
    for r in window:
        other = barrier.get((r.config.slots, r.config.reuse))
        if other is not None:
            console.print(
                f"{r.config.label}: window / barrier makespan {r.makespan / other.makespan:.2f}x"
            )
    console.print(f"median bound/makespan {statistics.median(r.bound_ratio for r in results):.2f}")


if __name__ == "__main__":
    main()
