"""``provisioner: Helmfile`` planning (operator/provisioning.py), without a cluster.

Covers: the sync action (ConfigMap with the rendered helmfile, Job named and labelled for the
environment, owned by it, placed by the operator's node selector, deadline from
pendingTimeoutSeconds; campaign identities owned by the campaign; status with provisioner, Job
name and hash); an operator without helmfile image/role or a template without helmfile ends the
environment as Error; assessment before the pod exists (not provisioned -> needs provisioning,
Job running -> Provisioning with a backstop wake-up, Job failed -> Error with the Job's reason
and its pod's termination message, Job succeeded without a pod -> Error after the grace, Job
gone -> Error) and once it exists (the Pod path's verdicts; a failed sync still ends it);
teardown (destroy Job owned by the batch with its ConfigMap owned by the Job, recorded in status;
a still-running sync is stopped first; nothing to destroy when nothing was applied; the
environment may be deleted only once the destroy Job is recorded); clean-up of finished destroy
Jobs (deleted; a failed one reported on its batch first); Job views.
"""

from __future__ import annotations

import datetime
import json
from typing import Any

import pytest

from simtest_operator.api.v1alpha1 import EnvironmentPhase
from simtest_operator.operator import helmfileteardown, jobviews, observed, provisioning, requests
from simtest_operator.operator.actions import Delete, Emit, Kind, PatchStatus, RunHelmfile
from simtest_operator.operator.environments import Limits
from simtest_operator.render import EnvironmentRequest, RenderedEnvironment
from simtest_operator.render.rendering import run_spec_for
from simtest_operator.settings import HelmfileSettings, OperatorSettings
from simtest_operator.verdicts import Verdict

T0 = datetime.datetime(2030, 1, 1, tzinfo=datetime.UTC)
NAME = "camp-b00000-e000-a1"
LIMITS = Limits(
    timeout_seconds=60,
    pending_seconds=300,
    deadline_seconds=90,
    backstop_grace=30,
    missing_grace=10,
)
CONFIG = OperatorSettings(
    helmfile=HelmfileSettings(
        image="simtest-helmfile:1", role="op-helmfile-provisioner", node_selector={"pool": "system"}
    )
)
HELMFILE = "releases:\n- name: camp-b00000-e000-a1-sim\n"


def at(seconds: float) -> datetime.datetime:
    return T0 + datetime.timedelta(seconds=seconds)


def iso(seconds: float) -> str:
    return at(seconds).strftime("%Y-%m-%dT%H:%M:%SZ")


def campaign(provisioner: str = "Helmfile") -> observed.CampaignView:
    return observed.campaign_view(
        {
            "apiVersion": "simtest.dev/v1alpha1",
            "kind": "TestCampaign",
            "metadata": {"name": "camp", "namespace": "ns", "uid": "cu"},
            "spec": {
                "scenarios": {"sources": [{"path": "scenarios"}]},
                "environment": {"provisioner": provisioner},
                "execution": {"pendingTimeoutSeconds": 120},
            },
        }
    )


def env(
    status: dict[str, Any] | None = None, *, deleting: bool = False
) -> observed.EnvironmentView:
    meta: dict[str, Any] = {
        "name": NAME,
        "namespace": "ns",
        "uid": "eu",
        "creationTimestamp": iso(0),
    }
    if deleting:
        meta["deletionTimestamp"] = iso(50)
    return observed.environment_view(
        {
            "metadata": meta,
            "spec": {
                "campaign": "camp",
                "batch": "camp-b00000",
                "attempt": 1,
                "scenarios": [{"id": "a.xosc", "source": "file:///a.xosc", "sha256": "0" * 64}],
            },
            "status": status or {},
        }
    )


PROVISIONED = {
    "phase": "Provisioning",
    "provisioner": "Helmfile",
    "pod": NAME,
    "jobs": {"sync": f"{NAME}-hf-sync"},
    "timings": {"queued": iso(0)},
    "conditions": [
        {
            "type": "Provisioned",
            "status": "True",
            "reason": "HelmfileJobCreated",
            "lastTransitionTime": iso(1),
            "message": "",
        }
    ],
}
FINISHED = {
    **PROVISIONED,
    "phase": "Finished",
    "verdict": "Passed",
    "results": [{"id": "a.xosc", "verdict": "Passed", "reason": "ok", "attempts": 1}],
}


def job(
    action: str = "sync", *, state: str = "", at_s: float = 5, name: str = ""
) -> jobviews.JobView:
    conditions = []
    if state == "complete":
        conditions.append({"type": "Complete", "status": "True", "lastTransitionTime": iso(at_s)})
    if state == "failed":
        conditions.append(
            {
                "type": "Failed",
                "status": "True",
                "reason": "BackoffLimitExceeded",
                "message": "Job has reached the specified backoff limit",
                "lastTransitionTime": iso(at_s),
            }
        )
    return jobviews.job_view(
        {
            "metadata": {
                "name": name or f"{NAME}-hf-{action}",
                "namespace": "ns",
                "uid": f"ju-{action}",
                "creationTimestamp": iso(1),
                "labels": {
                    "simtest.dev/campaign": "camp",
                    "simtest.dev/batch": "camp-b00000",
                    "simtest.dev/environment": NAME,
                    "simtest.dev/helmfile-action": action,
                },
            },
            "status": {"conditions": conditions},
        }
    )


def job_pod(job_name: str, message: str, exit_code: int = 1) -> observed.PodView:
    return observed.pod_view(
        {
            "metadata": {
                "name": f"{job_name}-x1y2z",
                "namespace": "ns",
                "ownerReferences": [{"kind": "Job", "name": job_name, "uid": "ju"}],
                "labels": {"simtest.dev/campaign": "camp"},
            },
            "status": {
                "phase": "Failed",
                "containerStatuses": [
                    {
                        "name": "helmfile",
                        "state": {
                            "terminated": {
                                "exitCode": exit_code,
                                "reason": "Error",
                                "message": message,
                                "finishedAt": iso(4),
                            }
                        },
                    }
                ],
            },
        }
    )


def simulator_pod(message: str) -> observed.PodView:
    return observed.pod_view(
        {
            "metadata": {
                "name": NAME,
                "namespace": "ns",
                "creationTimestamp": iso(3),
                "labels": {"simtest.dev/campaign": "camp"},
            },
            "spec": {"nodeName": "n0"},
            "status": {
                "phase": "Succeeded",
                "startTime": iso(4),
                "containerStatuses": [
                    {
                        "name": "simulator",
                        "state": {
                            "terminated": {
                                "exitCode": 0,
                                "message": message,
                                "startedAt": iso(4),
                                "finishedAt": iso(9),
                            }
                        },
                    }
                ],
            },
        }
    )


def rendered(request: EnvironmentRequest, helmfile: str | None = HELMFILE) -> RenderedEnvironment:
    return RenderedEnvironment(
        values={}, pod={}, helmfile=helmfile, run_spec=run_spec_for(request), content_hash="f" * 64
    )


def assess(
    view: observed.EnvironmentView,
    *,
    jobs: tuple[jobviews.JobView, ...] = (),
    pods: tuple[observed.PodView, ...] = (),
    pod: observed.PodView | None = None,
    now: float = 20,
) -> Any:
    return provisioning.assess(
        view,
        pod,
        jobs={j.name: j for j in jobs},
        pods={p.name: p for p in pods},
        nodes=None,
        now=at(now),
        limits=LIMITS,
    )


# --- provisioning ------------------------------------------------------------------------------


def test_sync_action_builds_job_config_map_identities_and_status() -> None:
    spec = campaign().spec
    assert spec is not None and provisioning.uses_helmfile(spec)
    view = env()
    request = requests.environment_request(spec, view, config=CONFIG)
    action = provisioning.provision(
        spec, view, rendered(request), config=CONFIG, campaign_uid="cu", now=at(1)
    )
    assert isinstance(action, RunHelmfile) and not action.config_map_owned_by_job
    body = action.job
    assert body["metadata"]["name"] == f"{NAME}-hf-sync"
    assert body["metadata"]["ownerReferences"][0]["uid"] == "eu"
    assert body["metadata"]["labels"]["simtest.dev/campaign"] == "camp"
    assert body["spec"]["activeDeadlineSeconds"] == 120
    pod_spec = body["spec"]["template"]["spec"]
    assert pod_spec["nodeSelector"] == {"pool": "system"}
    assert pod_spec["serviceAccountName"] == "camp-helmfile"
    assert pod_spec["containers"][0]["image"] == "simtest-helmfile:1"
    assert "sync" in pod_spec["containers"][0]["args"]
    assert body["spec"]["template"]["metadata"]["labels"]["simtest.dev/campaign"] == "camp"
    assert action.config_map["data"] == {"helmfile.yaml": HELMFILE}
    kinds = [(k, b["metadata"]["name"]) for k, b in action.identities]
    assert kinds == [
        (Kind.SERVICE_ACCOUNT, "camp-simulator"),
        (Kind.SERVICE_ACCOUNT, "camp-helmfile"),
        (Kind.ROLE_BINDING, "camp-helmfile"),
    ]
    binding = action.identities[2][1]
    assert binding["roleRef"]["name"] == "op-helmfile-provisioner"
    assert all(b["metadata"]["ownerReferences"][0]["uid"] == "cu" for _, b in action.identities)
    assert action.status is not None
    assert action.status["provisioner"] == "Helmfile"
    assert action.status["jobs"] == {"sync": f"{NAME}-hf-sync"}
    assert action.status["renderedHash"] == "f" * 64


@pytest.mark.parametrize(
    ("config", "helmfile", "words"),
    [
        (OperatorSettings(), HELMFILE, "not enabled in this operator"),
        (CONFIG, None, "has no helmfile.yaml.j2"),
    ],
)
def test_sync_impossible_ends_the_environment_as_error(
    config: OperatorSettings, helmfile: str | None, words: str
) -> None:
    spec = campaign().spec
    assert spec is not None
    view = env()
    request = requests.environment_request(spec, view, config=config)
    action = provisioning.provision(
        spec, view, rendered(request, helmfile), config=config, campaign_uid="cu", now=at(1)
    )
    assert isinstance(action, PatchStatus)
    assert action.patch["verdict"] == "Error" and words in action.patch["reason"]


def test_pod_campaigns_keep_the_direct_path() -> None:
    spec = campaign("Pod").spec
    assert spec is not None and not provisioning.uses_helmfile(spec)
    judged = assess(env())
    assert judged.needs_pod


# --- assessment --------------------------------------------------------------------------------


def test_not_provisioned_needs_provisioning() -> None:
    assert assess(env(), jobs=()).needs_pod


def test_running_sync_job_is_provisioning_with_backstop() -> None:
    judged = assess(env(PROVISIONED), jobs=(job(),))
    assert judged.phase is EnvironmentPhase.PROVISIONING and not judged.ended
    assert judged.wake_at == at(1 + 300 + 30)
    late = assess(env(PROVISIONED), jobs=(job(),), now=400)
    assert late.ended and "still running" in late.reason


def test_failed_sync_job_is_error_with_helmfile_output() -> None:
    name = f"{NAME}-hf-sync"
    judged = assess(
        env(PROVISIONED),
        jobs=(job(state="failed"),),
        pods=(job_pod(name, "Building dependency\nError: chart not found: /opt/x\n"),),
    )
    assert judged.ended and judged.results is not None
    assert judged.results[0].verdict is Verdict.ERROR
    assert "BackoffLimitExceeded" in judged.reason
    assert "exit code 1" in judged.reason and "chart not found" in judged.reason


def test_succeeded_sync_without_pod_is_error_after_grace() -> None:
    waiting = assess(env(PROVISIONED), jobs=(job(state="complete", at_s=5),), now=10)
    assert not waiting.ended and waiting.wake_at == at(15)
    judged = assess(env(PROVISIONED), jobs=(job(state="complete", at_s=5),), now=16)
    assert judged.ended and "installed no simulator pod" in judged.reason


def test_missing_sync_job_is_error_after_grace() -> None:
    assert not assess(env(PROVISIONED), now=5).ended
    judged = assess(env(PROVISIONED), now=30)
    assert judged.ended and "disappeared" in judged.reason


def test_pod_is_judged_as_in_the_pod_path() -> None:
    message = json.dumps({"verdict": "Failed", "reason": "ego collided", "wallSeconds": 5})
    judged = assess(
        env(PROVISIONED), jobs=(job(state="complete"),), pod=simulator_pod(message), now=12
    )
    assert judged.results is not None and judged.results[0].verdict is Verdict.FAILED
    assert judged.node == "n0"


def test_failed_sync_ends_a_running_simulator() -> None:
    running = observed.pod_view(
        {
            "metadata": {"name": NAME, "namespace": "ns", "creationTimestamp": iso(3)},
            "spec": {"nodeName": "n0"},
            "status": {
                "phase": "Running",
                "containerStatuses": [
                    {"name": "simulator", "state": {"running": {"startedAt": iso(4)}}}
                ],
            },
        }
    )
    judged = assess(env(PROVISIONED), jobs=(job(state="failed"),), pod=running)
    assert judged.ended and judged.delete_pod and "helmfile sync Job" in judged.reason


# --- teardown ----------------------------------------------------------------------------------


def batch() -> observed.BatchView:
    return observed.batch_view(
        {
            "metadata": {"name": "camp-b00000", "namespace": "ns", "uid": "bu"},
            "spec": {"campaign": "camp", "index": 0, "scenarios": []},
        }
    )


def teardown(view: observed.EnvironmentView, *jobs: jobviews.JobView) -> tuple[Any, ...]:
    spec = campaign().spec
    assert spec is not None
    return helmfileteardown.teardown(
        spec,
        view,
        jobs={j.name: j for j in jobs},
        batch=batch(),
        render=rendered,
        config=CONFIG,
    )


def test_finished_environment_gets_a_destroy_job_owned_by_its_batch() -> None:
    view = env(FINISHED)
    assert not helmfileteardown.torn_down(view, {})
    (action,) = teardown(view, job(state="complete"))
    assert isinstance(action, RunHelmfile) and action.config_map_owned_by_job
    assert action.job["metadata"]["name"] == f"{NAME}-hf-destroy"
    owner = action.job["metadata"]["ownerReferences"][0]
    assert (owner["kind"], owner["uid"]) == ("ScenarioBatch", "bu")
    assert "destroy" in action.job["spec"]["template"]["spec"]["containers"][0]["args"]
    assert action.status == {"jobs": {"destroy": f"{NAME}-hf-destroy"}}
    recorded = env(
        {**FINISHED, "jobs": {"sync": f"{NAME}-hf-sync", "destroy": f"{NAME}-hf-destroy"}}
    )
    assert helmfileteardown.torn_down(recorded, {})
    assert teardown(recorded) == ()


def test_running_sync_is_stopped_before_destroying() -> None:
    (action,) = teardown(env(FINISHED), job())
    assert isinstance(action, Delete) and action.kind is Kind.JOB
    assert action.name == f"{NAME}-hf-sync"


def test_nothing_to_destroy_when_nothing_was_applied() -> None:
    failed = env({"phase": "Finished", "verdict": "Error", "reason": "x"})
    assert teardown(failed) == ()
    assert helmfileteardown.torn_down(failed, {})
    assert teardown(env(PROVISIONED)) == ()  # still running: no teardown yet


def test_deleted_environment_is_destroyed_without_a_status_write() -> None:
    (action,) = teardown(env(PROVISIONED, deleting=True))
    assert isinstance(action, RunHelmfile) and action.status is None


def test_finished_destroy_jobs_are_deleted_failed_ones_reported() -> None:
    done = job("destroy", state="complete")
    broken = job("destroy", state="failed", name="other-hf-destroy")
    running = job("destroy", name="third-hf-destroy")
    actions = helmfileteardown.collect(
        (done, broken, running),
        pods={"p": job_pod("other-hf-destroy", "Error: uninstall: timed out")},
        batches=(batch(),),
    )
    deletes = [a.name for a in actions if isinstance(a, Delete)]
    assert deletes == [done.name, broken.name]
    (event,) = [a for a in actions if isinstance(a, Emit)]
    assert event.warning and event.name == "camp-b00000" and "timed out" in event.message


def test_job_views() -> None:
    view = job(state="failed")
    assert view.failed and not view.succeeded and view.done
    assert (view.campaign, view.batch, view.environment, view.action) == (
        "camp",
        "camp-b00000",
        NAME,
        "sync",
    )
    assert view.finished_at == at(5) and "BackoffLimitExceeded" in view.reason
    assert not job().done
