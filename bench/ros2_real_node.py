"""A ROS 2 stack on the real node against the same logic behind the OSI protocol, scenario by
scenario, for a whole campaign (the seed campaign's 200 scenarios by default).

``tests/realnode/test_ros2_sidecar.py`` runs the smoke campaign both ways in CI; this runs a
campaign too long for CI the same way, once, as a measurement: the test stack
(``tests/sut/ros2_stack.py``) and the ROS 2 bridge as sidecars of each simulator pod (template
``ros2``, ``stack.placement: pod``, DDS on the pod's loopback) and the reference SUT as a sidecar
behind the OSI protocol, both campaigns at once on the real node's two simulator slots, in warm
pods. It records each scenario's verdict and reason both ways, the scenarios whose ``sut.log``
lacks the stack's run line, and each campaign's wall time.

    python bench/ros2_real_node.py [--campaign scenarios/seed-experiment-campaign.yaml] [--batch 10]

Needs root and what ``make test`` builds (toolchain, images). Results go to
``bench/results/ros2_real_node.json`` and ``.md``.
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from kubernetes import client

from kwokbench import REPO, new_namespace, operator_process
from real_pods import scenario_claim
from simtest_operator.devcluster import addons, images, provisioning
from simtest_operator.devcluster.cluster import DevCluster
from simtest_operator.devcluster.toolchain import Toolchain
from simtest_operator.settings import Settings

sys.path.insert(0, str(REPO))  # the campaigns are the real-node test's, one definition

from tests.e2e import support
from tests.realnode.conftest import host_path_claim
from tests.realnode.test_ros2_sidecar import osi_campaign, ros2_campaign

SLOTS = 2


def _sut_log(folder: Path, result: dict[str, Any]) -> str:
    """The scenario's sut.log on the artifacts claim: the path its result names, below the
    pods' ``/artifacts`` mount (the claim's ``runs`` folder)."""
    named = result.get("artifacts", {}).get("sutLog")
    if not named:
        return ""
    try:
        path = folder / "runs" / Path(named).relative_to("/artifacts")
    except ValueError:  # not a path in the pod (an s3:// URI)
        return ""
    return path.read_text(errors="replace") if path.is_file() else ""


def run(base: Path, work: Path, batch: int) -> dict[str, Any]:
    settings = Settings.from_env()
    toolchain = Toolchain(root=settings.cache.toolchain)
    setup = images.real_node_setup(
        settings.cache.root,
        helm=toolchain.binary("helm"),
        chart=REPO / addons.CHART,
        slots=SLOTS,
        wanted=(images.RUNNER_IMAGE, images.DEVICE_PLUGIN_IMAGE),
    )
    cluster = DevCluster(work / "cluster", toolchain, tied_to_this_process=True)
    info = cluster.up(nodes=0, real_node=setup, crds_dir=REPO / "crds", timeout=300)
    api = provisioning.api_client(info.kubeconfig)
    artifacts = work / "artifacts"
    artifacts.mkdir()
    artifacts.chmod(0o1777)  # the pods run as 65532; hostPath volumes get no fsGroup ownership
    try:
        core = client.CoreV1Api(api)
        namespace = new_namespace(api)
        core.patch_namespace(
            namespace,
            {"metadata": {"labels": {"pod-security.kubernetes.io/enforce": "restricted"}}},
        )
        scenario_claim(core, namespace)
        with (
            host_path_claim(
                api, namespace, claim="artifacts", folder=artifacts, access="ReadWriteMany"
            ),
            operator_process(
                namespace=namespace,
                kubeconfig=info.kubeconfig,
                templates=REPO / "helm-templates",
                sources=REPO / "scenarios",
                cache=work / "cache",
                log=work / "operator.log",
                env={"SIMTEST_OPERATOR_SCENARIO_CLAIM": "scenarios"},
            ),
        ):
            k8s = support.Cluster(api, namespace)
            started = time.monotonic()
            k8s.create(ros2_campaign(base, batch))
            k8s.create(osi_campaign(base, batch))
            seconds: dict[str, float] = {}
            while len(seconds) < 2:  # each campaign's own time: the faster one ends first
                for name in ("ros2", "osi"):
                    conditions = k8s.status(name).get("conditions") or []
                    if name not in seconds and any(
                        c["type"] == "Complete" and c["status"] == "True" for c in conditions
                    ):
                        seconds[name] = round(time.monotonic() - started, 1)
                time.sleep(1.0)
            found = {name: k8s.results(name) for name in ("ros2", "osi")}
        logs = {s: _sut_log(artifacts, r) for s, r in found["ros2"].items()}
    finally:
        api.close()  # type: ignore[no-untyped-call]
        cluster.down()
    ros2, osi = found["ros2"], found["osi"]
    rows = {
        scenario: {
            "ros2": [ros2.get(scenario, {}).get("verdict"), ros2.get(scenario, {}).get("reason")],
            "osi": [osi[scenario]["verdict"], osi[scenario].get("reason")],
        }
        for scenario in sorted(osi)
    }
    differing = sorted(s for s, r in rows.items() if r["ros2"] != r["osi"])
    no_stack_line = sorted(s for s in rows if "stack: run from" not in logs.get(s, ""))
    return {
        "campaign": str(base.relative_to(REPO)),
        "scenarios": len(rows),
        "batch": batch,
        "verdicts": {
            name: dict(collections.Counter(r[name][0] for r in rows.values()))
            for name in ("ros2", "osi")
        },
        "differing": differing,
        "withoutStackLog": no_stack_line,
        "wallSecondsSinceCreation": seconds,
        "rows": rows,
    }


def markdown(report: dict[str, Any]) -> str:
    lines = [
        f"# ROS 2 stack vs OSI protocol on the real node: `{report['campaign']}`",
        "",
        f"{report['scenarios']} scenarios, both campaigns at once on {SLOTS} simulator slots, "
        f"warm pods of {report['batch']} scenarios (`isolation: Reuse`).",
        "",
        "| SUT | verdicts | wall time since creation (s) |",
        "|---|---|---|",
    ]
    for name, label in (("ros2", "test stack + bridge (DDS in the pod)"), ("osi", "reference SUT")):
        counts = ", ".join(f"{k} {v}" for k, v in sorted(report["verdicts"][name].items()))
        lines.append(f"| {label} | {counts} | {report['wallSecondsSinceCreation'][name]} |")
    lines += [
        "",
        f"Scenarios whose verdict or reason differ: {len(report['differing'])}"
        + (f" ({', '.join(report['differing'])})" if report["differing"] else ""),
        f"Scenarios whose sut.log lacks the stack's run line: {len(report['withoutStackLog'])}",
        "",
    ]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--campaign", type=Path, default=REPO / "scenarios" / "seed-experiment-campaign.yaml"
    )
    parser.add_argument("--batch", type=int, default=10, help="scenarios per warm pod")
    parser.add_argument(
        "--json", type=Path, default=REPO / "bench" / "results" / "ros2_real_node.json"
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="ros2-real-node-") as tmp:
        report = run(args.campaign.resolve(), Path(tmp), args.batch)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(report, indent=2) + "\n")
    args.json.with_suffix(".md").write_text(markdown(report))
    print(markdown(report))


if __name__ == "__main__":
    main()
