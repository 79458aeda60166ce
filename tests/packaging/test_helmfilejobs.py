"""``provisioner: Helmfile``: the Job that runs the real helmfile on a rendered helmfile.

Covers, without a cluster: Job and ConfigMap bodies (helmfile sync/destroy with --skip-deps on the
mounted file, HELM_DRIVER=configmap, restricted profile, owner reference, deadline, labels), names
bounded to 63 characters with a digest, the per-campaign ServiceAccount and RoleBinding, refusals
of an empty helmfile or a non-positive deadline. With the real binaries: every flag the Job uses
exists in this helmfile (sync and destroy), and a helmfile rendered by `render` from an
environment template composing ROS 2 charts (a `simtest package ros` chart and the K8s-ROS base)
goes through `helmfile template`. Against the dev control plane: the Job, ConfigMap,
ServiceAccount and RoleBinding, and everything `helmfile template` produced, pass a server-side
dry-run; `helmfile sync` installs the stack (owned by a real SimEnvironment, release records in
ConfigMaps, restricted Pod Security enforced) and `helmfile destroy` removes it.
"""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path
from typing import Any

import pytest
import yaml

from simtest_operator import render
from simtest_operator.errors import RenderError
from simtest_operator.packaging import helmfilejobs, rospackaging
from simtest_operator.packaging.helmfilejobs import Action, HelmfileJobRequest, Owner
from tests.charts.helmtools import REPO, ROS_CHART, Tool, documents, find, restricted_problems
from tests.render.cases import request as environment_request

TESTDATA = Path(__file__).parent / "testdata"
OWNER = Owner(
    api_version="simtest.dev/v1alpha1",
    kind="SimEnvironment",
    name="demo-b00003-e007-a2",
    uid="0d1e2f3a",
)


def job_request(**changes: Any) -> HelmfileJobRequest:
    base = HelmfileJobRequest(
        environment="demo-b00003-e007-a2",
        namespace="ci",
        action=Action.SYNC,
        helmfile="releases: []\n",
        image="ghcr.io/simtest-dev/simtest-helmfile:0.1.0",
        service_account=helmfilejobs.service_account_name("demo"),
        owner=OWNER,
        labels={"simtest.dev/campaign": "demo", "simtest.dev/batch": "demo-b00003"},
    )
    return dataclasses.replace(base, **changes)


def test_job_runs_helmfile_on_the_mounted_file() -> None:
    job = helmfilejobs.job(job_request())
    assert job["metadata"]["name"] == "demo-b00003-e007-a2-hf-sync"
    assert job["metadata"]["ownerReferences"] == [OWNER.reference()]
    spec = job["spec"]
    assert spec["backoffLimit"] == 0 and spec["activeDeadlineSeconds"] == 600
    pod = spec["template"]["spec"]
    assert pod["restartPolicy"] == "Never"
    assert pod["serviceAccountName"] == "demo-helmfile"
    assert restricted_problems(pod) == []
    container = pod["containers"][0]
    assert container["command"] == ["helmfile"]
    assert container["args"] == [
        "--file", "/etc/simtest/helmfile/helmfile.yaml", "--no-color", "sync", "--skip-deps",
    ]  # fmt: skip
    env = {item["name"]: item["value"] for item in container["env"]}
    assert env["HELM_DRIVER"] == "configmap"
    assert {m["mountPath"] for m in container["volumeMounts"]} == {"/etc/simtest/helmfile", "/tmp"}
    assert pod["volumes"][0] == {"name": "helmfile", "configMap": {"name": job["metadata"]["name"]}}
    labels = spec["template"]["metadata"]["labels"]
    assert labels["simtest.dev/campaign"] == "demo"
    assert labels["simtest.dev/environment"] == "demo-b00003-e007-a2"
    assert labels["simtest.dev/helmfile-action"] == "sync"


def test_destroy_job_and_config_map() -> None:
    request = job_request(action=Action.DESTROY, helmfile="releases: [{name: a}]\n")
    job = helmfilejobs.job(request)
    assert job["metadata"]["name"].endswith("-hf-destroy")
    assert job["spec"]["template"]["spec"]["containers"][0]["args"][3] == "destroy"
    config_map = helmfilejobs.config_map(request)
    assert config_map["metadata"]["name"] == job["metadata"]["name"]
    assert config_map["immutable"] is True
    assert config_map["data"] == {"helmfile.yaml": "releases: [{name: a}]\n"}


def test_node_selector_places_the_job_only_when_given() -> None:
    pod = helmfilejobs.job(job_request())["spec"]["template"]["spec"]
    assert "nodeSelector" not in pod
    placed = helmfilejobs.job(job_request(node_selector={"pool": "infra", "arch": "amd64"}))
    assert placed["spec"]["template"]["spec"]["nodeSelector"] == {"arch": "amd64", "pool": "infra"}


def test_names_stay_within_63_characters() -> None:
    long_env = "c" * 50 + "-b00042-e007-a12"
    name = helmfilejobs.job_name(long_env, Action.DESTROY)
    assert len(name) <= 63 and name.endswith("-hf-destroy")
    assert name != helmfilejobs.job_name(long_env.replace("a12", "a13"), Action.DESTROY)
    assert helmfilejobs.job_name("short", Action.SYNC) == "short-hf-sync"
    assert len(helmfilejobs.service_account_name("x" * 63)) <= 63


def test_campaign_identity_binds_the_provisioner_role_in_one_namespace() -> None:
    owner = Owner(api_version="simtest.dev/v1alpha1", kind="TestCampaign", name="demo", uid="u1")
    labels = {"simtest.dev/campaign": "demo"}
    account = helmfilejobs.service_account(
        campaign="demo", namespace="ci", owner=owner, labels=labels
    )
    binding = helmfilejobs.role_binding(
        campaign="demo",
        namespace="ci",
        cluster_role="simtest-operator-helmfile-provisioner",
        owner=owner,
        labels=labels,
    )
    assert account["metadata"]["name"] == "demo-helmfile"
    assert binding["kind"] == "RoleBinding" and binding["metadata"]["namespace"] == "ci"
    assert binding["roleRef"]["name"] == "simtest-operator-helmfile-provisioner"
    assert binding["subjects"] == [
        {"kind": "ServiceAccount", "name": "demo-helmfile", "namespace": "ci"}
    ]


@pytest.mark.parametrize(
    ("changes", "message"),
    [({"helmfile": "  \n"}, "rendered helmfile is empty"), ({"deadline_seconds": 0}, "positive")],
)
def test_refusals(changes: dict[str, Any], message: str) -> None:
    with pytest.raises(RenderError, match=message):
        helmfilejobs.job(job_request(**changes))


# --- with the real helmfile ----------------------------------------------------------------


def test_every_flag_the_job_uses_exists(helmfile: Tool) -> None:
    top = helmfile.run("--help").stdout
    assert "--file" in top and "--no-color" in top
    for action in Action:
        assert "--skip-deps" in helmfile.run(action.value, "--help").stdout


def _rendered_stack(
    tmp_path: Path, namespace: str, *, owner_uid: str = "0d1e2f3a"
) -> tuple[Path, render.RenderedEnvironment]:
    """Charts dir (base chart + generated planner) and an environment rendered with the
    ros-stack template (the default template's values and pod, our helmfile)."""
    charts = tmp_path / "charts"
    shutil.copytree(ROS_CHART, charts / "k8s-ros")
    shutil.copytree(REPO / "charts" / "simtest-simulator", charts / "simtest-simulator")
    inputs = rospackaging.load_inputs(TESTDATA / "ros" / "planner" / "package.yaml", ROS_CHART)
    rospackaging.write(rospackaging.chart_files(inputs), charts, "planner")
    templates = tmp_path / "helm-templates"
    (templates / "ros-stack").mkdir(parents=True)
    for name in ("values.yaml.j2", "pod.yaml.j2"):
        shutil.copy(REPO / "helm-templates" / "default" / name, templates / "ros-stack" / name)
    shutil.copy(TESTDATA / "ros-stack" / "helmfile.yaml.j2", templates / "ros-stack")
    request = environment_request(
        template="ros-stack",
        namespace=namespace,
        owner=dataclasses.replace(environment_request().owner, uid=owner_uid),
        values={
            "global": {"chartsDir": str(charts)},
            "ros": {"domainId": 17},
            "replay": {"image": "ghcr.io/acme/replay:2.0"},
        },
    )
    return charts, render.render_environment(request, render.TemplateLibrary(templates))


def _helmfile_template(helmfile: Tool, tmp_path: Path, text: str) -> list[dict[str, Any]]:
    path = tmp_path / "helmfile.yaml"
    path.write_text(text)
    result = helmfile.run("--file", path, "--no-color", "template", "--skip-deps", cwd=tmp_path)
    return documents(result.stdout)


def test_rendered_helmfile_goes_through_helmfile_template(tmp_path: Path, helmfile: Tool) -> None:
    _, rendered = _rendered_stack(tmp_path, "ci")
    assert rendered.helmfile is not None
    docs = _helmfile_template(helmfile, tmp_path, rendered.helmfile)
    planner = find(docs, "Deployment", "demo-b00003-e007-a2-planner")
    replay = find(docs, "Job", "demo-b00003-e007-a2-replay-k8s-ros")
    for workload in (planner, replay):
        assert workload["metadata"]["namespace"] == "ci"
        assert workload["metadata"]["ownerReferences"][0]["uid"] == "0d1e2f3a"
        assert workload["metadata"]["labels"]["simtest.dev/campaign"] == "demo"
        pod = workload["spec"]["template"]["spec"]
        env = {item["name"]: item.get("value") for item in pod["containers"][0]["env"]}
        assert env["ROS_DOMAIN_ID"] == "17"
        assert restricted_problems(pod) == []
    # planner: params + CycloneDDS; replay: Fast DDS (no params)
    assert len([d for d in docs if d["kind"] == "ConfigMap"]) == 3


# --- against the dev control plane ---------------------------------------------------------


def _dry_run(kubectl: Tool, kubeconfig: Path, namespace: str, docs: list[dict[str, Any]]) -> str:
    text = yaml.safe_dump_all(docs)
    result = kubectl.run(
        "--kubeconfig", kubeconfig, "apply", "--server-side", "--dry-run=server",
        "--field-manager=simtest-tests", "--namespace", namespace, "-f", "-",
        stdin=text,
    )  # fmt: skip
    return result.stdout


def test_job_objects_pass_a_server_side_dry_run(
    kubectl: Tool, kubeconfig_path: Path, k8s_namespace: str
) -> None:
    request = job_request(namespace=k8s_namespace, helmfile="releases: []\n")
    owner = Owner(api_version="simtest.dev/v1alpha1", kind="TestCampaign", name="demo", uid="u1")
    docs = [
        helmfilejobs.service_account(
            campaign="demo", namespace=k8s_namespace, owner=owner, labels={}
        ),
        helmfilejobs.role_binding(
            campaign="demo",
            namespace=k8s_namespace,
            cluster_role="simtest-operator-helmfile-provisioner",
            owner=owner,
            labels={},
        ),
        helmfilejobs.config_map(request),
        helmfilejobs.job(request),
        helmfilejobs.job(dataclasses.replace(request, action=Action.DESTROY)),
    ]
    out = _dry_run(kubectl, kubeconfig_path, k8s_namespace, docs)
    assert out.count("serverside-applied (server dry run)") == len(docs)


def _simulator_service_account(
    kubectl: Tool, kubeconfig: Path, namespace: str, rendered: render.RenderedEnvironment
) -> None:
    """The ServiceAccount the operator creates before the simulator pod (admission checks it)."""
    name = rendered.pod["spec"]["serviceAccountName"]
    kubectl.run("--kubeconfig", kubeconfig, "--namespace", namespace, "create", "sa", name)


def test_helmfile_output_passes_a_server_side_dry_run(
    tmp_path: Path, helmfile: Tool, kubectl: Tool, kubeconfig_path: Path, k8s_namespace: str
) -> None:
    _, rendered = _rendered_stack(tmp_path, k8s_namespace)
    assert rendered.helmfile is not None
    _simulator_service_account(kubectl, kubeconfig_path, k8s_namespace, rendered)
    docs = _helmfile_template(helmfile, tmp_path, rendered.helmfile)
    out = _dry_run(kubectl, kubeconfig_path, k8s_namespace, docs)
    assert out.count("serverside-applied (server dry run)") == len(docs)


def test_helmfile_sync_and_destroy_on_the_dev_cluster(
    tmp_path: Path, helmfile: Tool, kubectl: Tool, kubeconfig_path: Path, k8s_namespace: str
) -> None:
    """What the Job does, run here: `helmfile sync` installs the stack into a namespace that
    enforces the restricted profile, owned by a real SimEnvironment; `destroy` removes it."""
    kube = ("--kubeconfig", str(kubeconfig_path), "--namespace", k8s_namespace)
    kubectl.run(
        *kube, "label", "namespace", k8s_namespace, "pod-security.kubernetes.io/enforce=restricted"
    )
    environment = {
        "apiVersion": "simtest.dev/v1alpha1",
        "kind": "SimEnvironment",
        "metadata": {"name": "demo-b00003-e007-a2"},
        "spec": {
            "campaign": "demo",
            "batch": "demo-b00003",
            "scenarios": [{"id": "a.xosc", "source": "file:///s/a.xosc", "sha256": "ab" * 32}],
        },
    }
    created = yaml.safe_load(
        kubectl.run(
            *kube, "create", "-o", "yaml", "-f", "-", stdin=yaml.safe_dump(environment)
        ).stdout
    )
    _, rendered = _rendered_stack(tmp_path, k8s_namespace, owner_uid=created["metadata"]["uid"])
    assert rendered.helmfile is not None
    _simulator_service_account(kubectl, kubeconfig_path, k8s_namespace, rendered)
    path = tmp_path / "helmfile.yaml"
    path.write_text(rendered.helmfile)
    runner = dataclasses.replace(helmfile, env={**helmfile.env, "KUBECONFIG": str(kubeconfig_path)})
    runner.run("--file", path, "--no-color", "sync", "--skip-deps", cwd=tmp_path)
    selector = "simtest.dev/campaign=demo"
    listed = yaml.safe_load(
        kubectl.run(*kube, "get", "deployments,jobs,pods", "-l", selector, "-o", "yaml").stdout
    )["items"]
    listed = [
        i
        for i in listed
        if i["kind"] != "Pod" or i["metadata"]["name"] == rendered.pod["metadata"]["name"]
    ]
    assert sorted(item["kind"] for item in listed) == ["Deployment", "Job", "Pod"]
    for item in listed:
        assert item["metadata"]["ownerReferences"][0]["uid"] == created["metadata"]["uid"]
    releases = kubectl.run(*kube, "get", "configmaps", "-l", "owner=helm", "-o", "name").stdout
    assert len(releases.split()) == 3  # HELM_DRIVER=configmap: release records, no Secrets
    runner.run("--file", path, "--no-color", "destroy", "--skip-deps", cwd=tmp_path)
    left = yaml.safe_load(
        kubectl.run(*kube, "get", "deployments,jobs,pods", "-l", selector, "-o", "yaml").stdout
    )["items"]
    alive = [i["metadata"]["name"] for i in left if not i["metadata"].get("deletionTimestamp")]
    assert rendered.pod["metadata"]["name"] not in alive
    assert not [
        i for i in left if i["kind"] in ("Deployment", "Job") and i["metadata"]["name"] in alive
    ]
