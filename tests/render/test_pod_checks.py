"""Invariants of rendered pods and template errors.

Covers: a template that drops the simulator unit, the restricted security context, the owner
reference or the deadline is rejected with every problem named; unknown and malformed templates
and undefined values are RenderErrors naming the template; template names cannot escape the
templates root.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from simtest_operator import render
from simtest_operator.errors import RenderError
from tests.render.cases import request

REPO = Path(__file__).resolve().parents[2]


def _library(tmp_path: Path, pod: str, values: str = "simulator: {}\n") -> render.TemplateLibrary:
    folder = tmp_path / "custom"
    folder.mkdir()
    (folder / "values.yaml.j2").write_text(values)
    (folder / "pod.yaml.j2").write_text(pod)
    return render.TemplateLibrary(tmp_path)


def test_a_pod_missing_the_invariants_is_rejected(tmp_path: Path) -> None:
    pod = """
apiVersion: v1
kind: Pod
metadata: {name: {{ env.name | json }}, namespace: {{ env.namespace | json }}}
spec:
  restartPolicy: Always
  containers:
  - name: simulator
    image: x
    securityContext: {privileged: true}
  volumes:
  - name: host
    hostPath: {path: /}
"""
    with pytest.raises(RenderError) as caught:
        render.render_environment(request(template="custom"), _library(tmp_path, pod))
    text = str(caught.value)
    for words in (
        "restartPolicy must be Never",
        "activeDeadlineSeconds",
        "ownerReferences",
        "operator's labels",
        "runAsNonRoot",
        "allowPrivilegeEscalation",
        "privileged",
        "readOnlyRootFilesystem",
        "drop ALL",
        "seccompProfile",
        "hostPath",
        "exactly one simtest.dev/simulator",
    ):
        assert words in text


def test_unknown_template_lists_the_available_ones() -> None:
    with pytest.raises(RenderError, match="available: composed-sut, default, ros2"):
        render.render_environment(
            request(template="nope"), render.TemplateLibrary(REPO / "helm-templates")
        )


@pytest.mark.parametrize("name", ["../etc", "Default", "a/b"])
def test_template_names_are_folder_names(name: str) -> None:
    with pytest.raises(RenderError, match="DNS label"):
        render.TemplateLibrary(REPO / "helm-templates").load(name)


def test_undefined_values_are_render_errors(tmp_path: Path) -> None:
    with pytest.raises(RenderError, match=r"values\.yaml\.j2"):
        render.render_environment(
            request(template="custom"),
            _library(tmp_path, "kind: Pod\n", values="x: {{ nothing | json }}\n"),
        )


def test_bad_yaml_is_a_render_error(tmp_path: Path) -> None:
    with pytest.raises(RenderError, match="valid YAML"):
        render.render_environment(request(template="custom"), _library(tmp_path, "a: [1\n"))
