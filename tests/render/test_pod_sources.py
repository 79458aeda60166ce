"""Scenario sources in the rendered pod: ConfigMap volumes, database specs and their tokens.

Covers: the operator's request of an environment names exactly the ConfigMaps and databases its
scenarios need (from their URIs and the campaign's sources); both shipped templates mount each
ConfigMap read-only (optional) where the runner reads it and pass each distinct token once
through a ``secretKeyRef`` variable; the run spec carries the database specs (never a token),
round-trips, and stays byte-identical without them (format version 1 unchanged); a template that
drops the mounts or the variables, or uses a volume type the restricted profile forbids, fails
the render with the reason; a malformed ``sources`` entry is a RenderError.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import pytest

from simtest_operator import render
from simtest_operator.api import v1alpha1
from simtest_operator.errors import RenderError
from simtest_operator.operator import observed, requests
from simtest_operator.render import runspecs
from simtest_operator.scenarios import GraphqlSource, Needs, RestSource, SecretRef
from simtest_operator.settings import InputSettings, OperatorSettings
from tests.render.cases import CASES, request

REPO = Path(__file__).resolve().parents[2]
LIBRARY = render.TemplateLibrary(REPO / "helm-templates")
SOURCES = CASES["scenario-sources"]


def simulator(pod: Any) -> dict[str, Any]:
    return next(c for c in pod["spec"]["containers"] if c["name"] == "simulator")


@pytest.mark.parametrize("template", ["default", "ros2"])
def test_pod_mounts_config_maps_and_passes_tokens(template: str) -> None:
    rendered = render.render_environment(dataclasses.replace(SOURCES, template=template), LIBRARY)
    container = simulator(rendered.pod)
    volumes = {v["name"]: v for v in rendered.pod["spec"]["volumes"]}
    mounts = {m["mountPath"]: m for m in container["volumeMounts"]}
    for name in ("suite-a", "suite-b"):
        mount = mounts[f"/var/run/simtest/configmaps/{name}"]
        assert mount["readOnly"] is True
        assert volumes[mount["name"]]["configMap"] == {"name": name, "optional": True}
    tokens = [e for e in container["env"] if e["name"].startswith("SIMTEST_SOURCE_TOKEN_")]
    assert tokens == [
        {
            "name": "SIMTEST_SOURCE_TOKEN_0",
            "valueFrom": {
                "secretKeyRef": {"name": "scenario-db", "key": "token", "optional": True}
            },
        }
    ]
    spec = runspecs.RunSpec.loads(
        next(e["value"] for e in container["env"] if e["name"] == runspecs.ENV_VAR)
    )
    assert spec.databases == SOURCES.source_needs.databases
    assert rendered.run_spec == spec


def test_run_spec_round_trip_and_compatibility() -> None:
    plain = render.render_environment(request(), LIBRARY).run_spec
    assert "sources" not in plain.to_json()
    with_sources = dataclasses.replace(plain, databases=SOURCES.source_needs.databases)
    text = with_sources.dumps()
    assert runspecs.RunSpec.loads(text) == with_sources
    assert json.loads(text)["version"] == runspecs.FORMAT_VERSION == 1
    assert "secret" not in json.dumps(json.loads(text)["sources"]).replace("secretRef", "")
    for bad, words in (
        ([{"ftp": {}}], "unknown source kind 'ftp'"),
        ([{"graphql": {"query": "{a}"}}], "endpoint"),
        (["rest"], "one field, graphql or rest"),
    ):
        data = {**json.loads(plain.dumps()), "sources": bad}
        with pytest.raises(RenderError, match=words):
            runspecs.RunSpec.loads(json.dumps(data))


def test_secret_variables_are_one_per_distinct_key() -> None:
    a, b = SecretRef(name="db", key="t"), SecretRef(name="db", key="u")
    databases = (
        RestSource(url="https://x/1", secret=a),
        GraphqlSource(endpoint="https://x/g", query="{q}"),
        RestSource(url="https://x/2", secret=b),
        RestSource(url="https://x/3", secret=a),
    )
    assert runspecs.secret_variables(databases) == {
        a: "SIMTEST_SOURCE_TOKEN_0",
        b: "SIMTEST_SOURCE_TOKEN_1",
    }


def campaign_spec() -> v1alpha1.TestCampaignSpec:
    return v1alpha1.TestCampaignSpec.model_validate(
        {
            "scenarios": {
                "sources": [
                    {"configMap": {"name": "suite-a"}},
                    {"graphql": {"endpoint": "https://db/graphql", "query": "{s{id}}"}},
                    {"rest": {"url": "https://db/api", "secretRef": {"name": "d", "key": "k"}}},
                    {"rest": {"url": "https://db/unused"}},
                ]
            }
        }
    )


def test_the_operator_requests_what_the_scenarios_need() -> None:
    refs = (
        render.ScenarioRef(id="a.xosc", source="configmap:suite-a/a.xosc", sha256="01" * 32),
        render.ScenarioRef(id="d.xosc", source="rest+https://db/api#d", sha256="02" * 32),
        render.ScenarioRef(id="e.xosc", source="https://files/e.xosc", sha256="03" * 32),
    )
    view = dataclasses.replace(probe_view(), scenarios=refs)
    config = OperatorSettings(inputs=InputSettings(templates_dir=REPO / "helm-templates"))
    built = requests.environment_request(campaign_spec(), view, config=config)
    assert built.source_needs == Needs(
        config_maps=("suite-a",),
        databases=(RestSource(url="https://db/api", secret=SecretRef(name="d", key="k")),),
    )
    only_http = dataclasses.replace(view, scenarios=refs[2:])
    assert requests.environment_request(campaign_spec(), only_http, config=config).source_needs == (
        Needs()
    )


def probe_view() -> observed.EnvironmentView:
    return observed.EnvironmentView(
        name="c-b00000-e000-a1",
        namespace="ci",
        uid="u",
        resource_version="",
        campaign="c",
        batch="c-b00000",
        attempt=1,
        scenarios=(),
    )


BARE_POD = """
apiVersion: v1
kind: Pod
metadata:
  name: {{ env.name | json }}
  namespace: {{ env.namespace | json }}
  labels: {{ env.labels | json }}
  ownerReferences: [{{ env.ownerReference | json }}]
spec:
  restartPolicy: Never
  activeDeadlineSeconds: 100
  serviceAccountName: {{ env.serviceAccount | json }}
  securityContext: {runAsNonRoot: true, seccompProfile: {type: RuntimeDefault}}
  containers:
  - name: simulator
    image: x
    env: [{name: SIMTEST_RUN_SPEC, value: {{ runSpec | json }}}]
    resources:
      requests: {simtest.dev/simulator: "1"}
      limits: {simtest.dev/simulator: "1"}
    securityContext:
      allowPrivilegeEscalation: false
      readOnlyRootFilesystem: true
      capabilities: {drop: [ALL]}
  volumes: [{name: share, nfs: {server: nas, path: /}}]
"""


def test_a_template_that_drops_the_sources_is_rejected(tmp_path: Path) -> None:
    folder = tmp_path / "bare"
    folder.mkdir()
    (folder / "values.yaml.j2").write_text("simulator: {}\n")
    (folder / "pod.yaml.j2").write_text(BARE_POD)
    library = render.TemplateLibrary(tmp_path)
    with pytest.raises(RenderError) as caught:
        render.render_environment(dataclasses.replace(SOURCES, template="bare"), library)
    text = str(caught.value)
    for words in (
        "volume share: nfs is not allowed (restricted Pod Security)",
        "ConfigMap suite-a must be mounted at /var/run/simtest/configmaps/suite-a",
        "ConfigMap suite-b must be mounted",
        "SIMTEST_SOURCE_TOKEN_0 must come from Secret scenario-db key token",
    ):
        assert words in text
    (folder / "pod.yaml.j2").write_text(BARE_POD.replace("SIMTEST_RUN_SPEC", "OTHER"))
    fresh = render.TemplateLibrary(tmp_path)  # a library compiles each template once
    with pytest.raises(RenderError, match="no container has SIMTEST_RUN_SPEC"):
        render.render_environment(dataclasses.replace(SOURCES, template="bare"), fresh)
