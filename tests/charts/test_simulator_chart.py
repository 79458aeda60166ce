"""The simtest-simulator chart: the rendered simulator pod as a release (provisioner: Helmfile).

Covers: for every render golden case, `helm template` with `pod:` set to the pod `render` produced
returns that pod unchanged except for the release namespace; `helm lint --strict` passes; the chart
refuses a missing pod, a restartable pod, a pod without (or with more than) one simulator unit,
and (schema) anything that is not a Pod; the rendered pod passes a server-side dry-run in a
namespace that enforces the restricted profile.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest
import yaml

from simtest_operator import render
from tests.charts.helmtools import REPO, SIMULATOR_CHART, Tool, documents, template
from tests.render.cases import CASES

LIBRARY = render.TemplateLibrary(REPO / "helm-templates")


def _pod(case: str) -> dict[str, Any]:
    return copy.deepcopy(dict(render.render_environment(CASES[case], LIBRARY).pod))


def test_lint(helm: Tool, tmp_path: Path) -> None:
    values = tmp_path / "values.yaml"
    values.write_text(yaml.safe_dump({"pod": _pod("minimal")}))
    assert "0 chart(s) failed" in helm.run("lint", "--strict", SIMULATOR_CHART, "-f", values).stdout


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_rendered_pod_is_installed_unchanged(case: str, helm: Tool) -> None:
    pod = _pod(case)
    docs = documents(
        template(
            helm, SIMULATOR_CHART, release="sim", namespace="other", values={"pod": pod}
        ).stdout
    )
    assert len(docs) == 1
    expected = copy.deepcopy(pod)
    expected["metadata"]["namespace"] = "other"
    assert docs[0] == expected


def _broken(change: str) -> dict[str, Any]:
    pod = _pod("minimal")
    container = pod["spec"]["containers"][0]
    if change == "restart":
        pod["spec"]["restartPolicy"] = "OnFailure"
    elif change == "no unit":
        del container["resources"]["limits"]["simtest.dev/simulator"]
    elif change == "two units":
        pod["spec"]["containers"].append(copy.deepcopy(container) | {"name": "second"})
    elif change == "kind":
        pod["kind"] = "Deployment"
    return {"pod": pod}


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({}, "pod is required"),
        (_broken("restart"), "restartPolicy must be Never"),
        (_broken("no unit"), "exactly one simtest.dev/simulator unit"),
        (_broken("two units"), "exactly one simtest.dev/simulator unit"),
        (_broken("kind"), "/pod/kind"),
    ],
    ids=["missing", "restart", "no-unit", "two-units", "kind"],
)
def test_refusals(values: dict[str, Any], message: str, helm: Tool) -> None:
    result = template(helm, SIMULATOR_CHART, release="sim", values=values, check=False)
    assert result.returncode != 0
    assert message in result.stderr


def test_rendered_pod_passes_a_restricted_dry_run(
    helm: Tool, kubectl: Tool, kubeconfig_path: Path, k8s_namespace: str
) -> None:
    kube = ("--kubeconfig", str(kubeconfig_path), "--namespace", k8s_namespace)
    kubectl.run(
        *kube, "label", "namespace", k8s_namespace, "pod-security.kubernetes.io/enforce=restricted"
    )
    pod = _pod("gpu-pvc-placement")
    kubectl.run(*kube, "create", "serviceaccount", pod["spec"]["serviceAccountName"])
    text = template(
        helm, SIMULATOR_CHART, release="sim", namespace=k8s_namespace, values={"pod": pod}
    ).stdout
    result = kubectl.run(*kube, "apply", "--server-side", "--dry-run=server", "-f", "-", stdin=text)
    assert "serverside-applied (server dry run)" in result.stdout
    assert "Warning" not in result.stderr
