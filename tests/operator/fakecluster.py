"""An in-memory cluster for driving the campaign planner without an API server.

Holds object bodies, applies plans the way the API server would (merge patches of status,
``AlreadyExists``/``NotFound``/``Conflict`` semantics, ownerReference cascade on delete), and
plays scheduler and kubelet for simulator pods: binds a pod to a node with a free
``simtest.dev/simulator`` unit, starts it, and after its scripted duration terminates it with a
scripted exit code and termination message. The clock is explicit.
"""

from __future__ import annotations

import copy
import dataclasses
import datetime
import itertools
import json
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from simtest_operator.operator import admission, jobviews, observed, planning, scenariolists
from simtest_operator.operator.actions import (
    Create,
    Delete,
    Emit,
    Kind,
    PatchStatus,
    Plan,
    Provision,
)
from simtest_operator.render import TemplateLibrary, render_environment
from simtest_operator.scenarios import FrozenList, PinnedScenario
from simtest_operator.settings import InputSettings, OperatorSettings

REPO = Path(__file__).resolve().parents[2]
T0 = datetime.datetime(2030, 1, 1, tzinfo=datetime.UTC)
NAMESPACE = "tests"


def stamp(moment: datetime.datetime) -> str:
    return moment.strftime("%Y-%m-%dT%H:%M:%SZ")


@dataclasses.dataclass
class Script:
    """What the fake kubelet does with one attempt of a scenario."""

    seconds: float = 5.0
    message: str | None = None
    """Termination message; None writes a Passed outcome for the scenario."""
    exit_code: int = 0
    reason: str = ""
    """Container terminated reason (e.g. OOMKilled)."""
    pod_reason: str = ""
    """Pod status reason (Evicted, DeadlineExceeded)."""
    never_starts: bool = False
    waiting_reason: str = ""


ScriptFn = Callable[[str, int], Script]
"""(scenario id, attempt) -> Script."""


def passing(scenario_id: str, attempt: int) -> Script:
    return Script()


def campaign_body(name: str = "camp", **execution: Any) -> dict[str, Any]:
    return {
        "apiVersion": "simtest.dev/v1alpha1",
        "kind": "TestCampaign",
        "metadata": {"name": name, "namespace": NAMESPACE},
        "spec": {"scenarios": {"sources": [{"path": "scenarios"}]}, "execution": execution},
    }


def frozen_list(count: int, campaign: str = "camp") -> FrozenList:
    return FrozenList(
        campaign=campaign,
        scenarios=tuple(
            PinnedScenario(
                id=f"s{i:03d}.xosc", source=f"file:///s/s{i:03d}.xosc", sha256=f"{i:064x}"
            )
            for i in range(count)
        ),
    )


class FakeCluster:
    """Objects, an apiserver's write semantics, a scheduler and a kubelet."""

    def __init__(
        self,
        *,
        nodes: Mapping[str, int] | None = None,
        script: ScriptFn = passing,
        config: OperatorSettings | None = None,
    ) -> None:
        self.now = T0
        self.objects: dict[tuple[Kind | str, str], dict[str, Any]] = {}
        self.nodes = dict(nodes if nodes is not None else {"n0": 3, "n1": 3, "n2": 3})
        self.script = script
        self.config = config or OperatorSettings(
            inputs=InputSettings(templates_dir=REPO / "helm-templates")
        )
        self.library = TemplateLibrary(self.config.inputs.templates_dir)
        self._uids = itertools.count(1)
        self._rv = itertools.count(1)
        self.events: list[Emit] = []
        self.max_per_node: dict[str, int] = {}
        self.max_in_flight = 0
        self.max_live_envs = 0
        self.pods_started: list[tuple[str, int]] = []
        self.pod_deletes: list[tuple[str, int | None]] = []
        """Each pod delete the operator asked for, with its grace (None: the pod's own)."""
        self.conflicts = 0
        self.last_status_write: datetime.datetime | None = None
        self.refusing: dict[tuple[Kind, str], str] = {}
        """Creates the API server refuses for good, with its answer (RBAC, admission)."""
        self.refused: dict[tuple[Kind, str], str] = {}
        """What it refused so far, as the campaign loop keeps it for the planner."""

    # --- objects -----------------------------------------------------------------------------

    def add(self, kind: Kind | str, body: Mapping[str, Any]) -> dict[str, Any]:
        obj = copy.deepcopy(dict(body))
        meta = obj.setdefault("metadata", {})
        meta.setdefault("namespace", NAMESPACE)
        meta["uid"] = f"uid-{next(self._uids)}"
        meta["resourceVersion"] = str(next(self._rv))
        meta["creationTimestamp"] = stamp(self.now)
        meta.setdefault("generation", 1)
        self.objects[(kind, meta["name"])] = obj
        return obj

    def of(self, kind: Kind | str) -> list[dict[str, Any]]:
        return [o for (k, _), o in sorted(self.objects.items()) if k == kind]

    def get(self, kind: Kind | str, name: str) -> dict[str, Any] | None:
        return self.objects.get((kind, name))

    def start_campaign(
        self, body: Mapping[str, Any], frozen: FrozenList, *, batch_size: int
    ) -> None:
        campaign = self.add(Kind.CAMPAIGN, body)
        owner = {
            "apiVersion": "simtest.dev/v1alpha1",
            "kind": "TestCampaign",
            "name": campaign["metadata"]["name"],
            "uid": campaign["metadata"]["uid"],
        }
        for cm in scenariolists.config_maps(
            scenariolists.StoredList(frozen=frozen, batch_size=batch_size),
            namespace=NAMESPACE,
            campaign=campaign["metadata"]["name"],
            owner=owner,
        ):
            self.add(Kind.CONFIG_MAP, cm)

    # --- planning ----------------------------------------------------------------------------

    def inputs(self, name: str = "camp") -> planning.Inputs:
        campaign = self.get(Kind.CAMPAIGN, name)
        assert campaign is not None
        cm = self.get(Kind.CONFIG_MAP, f"{name}-scenarios")
        return planning.Inputs(
            campaign=observed.campaign_view(campaign),
            stored=self._stored(cm) if cm else None,
            batches=[observed.batch_view(b) for b in self.of(Kind.BATCH)],
            envs=[observed.environment_view(e) for e in self.of(Kind.ENVIRONMENT)],
            pods={p["metadata"]["name"]: observed.pod_view(p) for p in self.of(Kind.POD)},
            nodes={n: self._node_view(n) for n in self.nodes},
            now=self.now,
            last_status_write=self.last_status_write,
            jobs={j["metadata"]["name"]: jobviews.job_view(j) for j in self.of(Kind.JOB)},
            workload=self._workload(name),
            refused=dict(self.refused),
        )

    def _workload(self, campaign: str) -> admission.WorkloadView | None:
        """The campaign's Kueue Workload (admitted by a test's hand: no Kueue here)."""
        body = self.get(Kind.WORKLOAD, admission.workload_name(campaign))
        return admission.workload_view(body) if body is not None else None

    def _stored(self, head: Mapping[str, Any]) -> scenariolists.StoredList:
        chunks = [self.get(Kind.CONFIG_MAP, n) for n in scenariolists.chunk_names(head)]
        return scenariolists.read(head, [c for c in chunks if c is not None])

    def _node_view(self, name: str) -> observed.NodeView:
        return observed.NodeView(
            name=name, ready=True, unschedulable=False, slots=self.nodes[name], labels=(), taints=()
        )

    def plan(self, name: str = "camp") -> Plan:
        return planning.plan(
            self.inputs(name),
            config=self.config,
            render=lambda request: render_environment(request, self.library),
        )

    def apply(self, plan: Plan, *, limit: int | None = None) -> None:
        """Apply the plan's actions (only the first ``limit``: a crash mid-apply)."""
        for action in plan.actions[:limit]:
            if isinstance(action, Create):
                answer = self.refusing.get((action.kind, action.name))
                if answer is not None:
                    self.refused[(action.kind, action.name)] = answer
                elif (action.kind, action.name) not in self.objects:
                    self.add(action.kind, action.body)
            elif isinstance(action, Provision):
                env = self.get(Kind.ENVIRONMENT, action.environment)
                if env is None:
                    continue
                if (Kind.POD, action.pod["metadata"]["name"]) not in self.objects:
                    self.add(Kind.POD, {**action.pod, "status": {"phase": "Pending"}})
                self._patch(env, action.status)
            elif isinstance(action, PatchStatus):
                target = self.get(action.kind, action.name)
                if target is None:
                    continue
                if (
                    action.resource_version
                    and target["metadata"]["resourceVersion"] != action.resource_version
                ):
                    self.conflicts += 1
                    continue
                self._patch(target, action.patch)
                if action.kind is Kind.CAMPAIGN:
                    self.last_status_write = self.now
            elif isinstance(action, Delete):
                if action.kind is Kind.POD:
                    self.pod_deletes.append((action.name, action.grace_seconds))
                self.delete(action.kind, action.name, uid=action.uid)
            elif isinstance(action, Emit):
                self.events.append(action)

    def _patch(self, target: dict[str, Any], patch: Mapping[str, Any]) -> None:
        target["status"] = _merge(target.get("status") or {}, json.loads(json.dumps(patch)))
        target["metadata"]["resourceVersion"] = str(next(self._rv))

    def delete(self, kind: Kind | str, name: str, *, uid: str | None = None) -> None:
        obj = self.objects.get((kind, name))
        if obj is None or (uid is not None and obj["metadata"]["uid"] != uid):
            return
        del self.objects[(kind, name)]
        owned = [
            key
            for key, child in self.objects.items()
            if any(
                o.get("uid") == obj["metadata"]["uid"]
                for o in child["metadata"].get("ownerReferences", [])
            )
        ]
        for child_kind, child_name in owned:
            self.delete(child_kind, child_name)

    # --- scheduler and kubelet ---------------------------------------------------------------

    def kubelet(self) -> None:
        """Advance every pod as far as the current time allows."""
        used = dict.fromkeys(self.nodes, 0)
        for pod in self.of(Kind.POD):
            node = pod["spec"].get("nodeName")
            if node in used and pod["status"]["phase"] in ("Pending", "Running"):
                used[node] += 1
        for pod in self.of(Kind.POD):
            self._advance(pod, used)
        for node, count in used.items():
            self.max_per_node[node] = max(self.max_per_node.get(node, 0), count)
        running = sum(
            1 for p in self.of(Kind.POD) if p["status"]["phase"] in ("Pending", "Running")
        )
        self.max_in_flight = max(self.max_in_flight, running)
        self.max_live_envs = max(self.max_live_envs, len(self.of(Kind.ENVIRONMENT)))

    def _script(self, pod: Mapping[str, Any]) -> Script:
        spec = json.loads(pod["spec"]["containers"][0]["env"][0]["value"])
        return self.script(spec["scenarios"][0]["id"], spec["attempt"])

    def _advance(self, pod: dict[str, Any], used: dict[str, int]) -> None:
        if any(o.get("kind") == "Job" for o in pod["metadata"].get("ownerReferences", [])):
            return  # a Job's pod: the test plays the Job controller
        status = pod["status"]
        script = self._script(pod)
        if status["phase"] == "Pending" and not pod["spec"].get("nodeName"):
            if script.never_starts:
                status["conditions"] = [
                    {
                        "type": "PodScheduled",
                        "status": "False",
                        "reason": "Unschedulable",
                        "message": "0/3 nodes are available",
                    }
                ]
                return
            node = next((n for n in sorted(self.nodes) if used[n] < self.nodes[n]), None)
            if node is None:
                return
            used[node] += 1
            pod["spec"]["nodeName"] = node
            status["conditions"] = [
                {"type": "PodScheduled", "status": "True", "lastTransitionTime": stamp(self.now)}
            ]
            if script.waiting_reason:
                status["containerStatuses"] = [
                    {
                        "name": "simulator",
                        "state": {
                            "waiting": {"reason": script.waiting_reason, "message": "cannot pull"}
                        },
                    }
                ]
                return
            status["phase"] = "Running"
            status["startTime"] = stamp(self.now)
            status["containerStatuses"] = [
                {"name": "simulator", "state": {"running": {"startedAt": stamp(self.now)}}}
            ]
            self.pods_started.append((pod["metadata"]["name"], 1))
            pod["metadata"]["annotations"] = {"started": self.now.isoformat()}
            return
        if status["phase"] != "Running":
            return
        started = datetime.datetime.fromisoformat(pod["metadata"]["annotations"]["started"])
        if (self.now - started).total_seconds() < script.seconds:
            return
        spec = json.loads(pod["spec"]["containers"][0]["env"][0]["value"])
        message = script.message
        if message is None:
            message = (
                json.dumps(
                    {
                        "results": [
                            {
                                "scenarioId": s["id"],
                                "verdict": "Passed",
                                "wallSeconds": script.seconds / len(spec["scenarios"]),
                            }
                            for s in spec["scenarios"]
                        ]
                    }
                )
                if len(spec["scenarios"]) > 1
                else json.dumps(
                    {
                        "scenarioId": spec["scenarios"][0]["id"],
                        "verdict": "Passed",
                        "wallSeconds": script.seconds,
                        "metrics": {"minTTC": 2.5},
                    }
                )
            )
        status["phase"] = "Succeeded" if script.exit_code == 0 else "Failed"
        if script.pod_reason:
            status["reason"] = script.pod_reason
            status["message"] = "scripted"
        status["containerStatuses"] = [
            {
                "name": "simulator",
                "state": {
                    "terminated": {
                        "exitCode": script.exit_code,
                        "reason": script.reason
                        or ("Completed" if script.exit_code == 0 else "Error"),
                        "message": message,
                        "startedAt": stamp(started),
                        "finishedAt": stamp(self.now),
                    }
                },
            }
        ]

    # --- driving -----------------------------------------------------------------------------

    def step(self, seconds: float = 1.0, *, rounds: int = 4, limit: int | None = None) -> None:
        """Let time pass, then reconcile until quiet (a few rounds, as watch events would)."""
        self.now += datetime.timedelta(seconds=seconds)
        for _ in range(rounds):
            self.kubelet()
            self.apply(self.plan(), limit=limit)

    def run(
        self,
        *,
        seconds: float = 1.0,
        max_steps: int = 2000,
        limit: Callable[[int], int | None] | None = None,
    ) -> int:
        for steps in range(1, max_steps + 1):
            self.step(seconds, limit=limit(steps) if limit else None)
            campaign = self.get(Kind.CAMPAIGN, "camp")
            assert campaign is not None
            if (campaign.get("status") or {}).get("phase") in (
                "Succeeded",
                "Failed",
                "Error",
                "Cancelled",
            ) and not self.of(Kind.ENVIRONMENT):
                return steps
        raise AssertionError("campaign did not finish")

    def status(self, kind: Kind | str = Kind.CAMPAIGN, name: str = "camp") -> dict[str, Any]:
        obj = self.get(kind, name)
        assert obj is not None
        return obj.get("status") or {}

    def results(self) -> dict[str, dict[str, Any]]:
        out: dict[str, dict[str, Any]] = {}
        for batch in self.of(Kind.BATCH):
            for result in (batch.get("status") or {}).get("results", []):
                assert result["id"] not in out, f"{result['id']} has two results"
                out[result["id"]] = result
        return out


def _merge(base: Mapping[str, Any], patch: Mapping[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for key, value in patch.items():
        if value is None:
            out.pop(key, None)
        elif isinstance(value, Mapping) and isinstance(out.get(key), Mapping):
            out[key] = _merge(out[key], value)
        else:
            out[key] = value
    return out
