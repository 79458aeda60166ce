"""The run-specific helmfile and its contract with the operator, without any tool.

Covers: the charts root defaults to the helmfile image's (``packaging.IMAGE_CHARTS_DIR``) and is
overridable; both shipped templates install the simulator through one ``simtest-simulator``
release whose ``pod`` value is the rendered pod verbatim, in the environment's namespace; a
template helmfile that drops the simulator release, changes the pod or installs elsewhere is a
RenderError naming the problem; campaign overrides that remove the simulator unit are
RenderErrors; release names stay within Helm's limit and unique for long environment names;
ROS domain ids are deterministic and in range; SUT releases get K8s-ROS-shaped values (only with
an image); the ros2 template composes its components from the merged values (domain id reaching
the simulator pod and every component, disabled components dropped from releases and peers);
template markup inside custom-resource data stays data.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import pytest
import yaml

from simtest_operator import packaging, render
from simtest_operator.errors import RenderError
from simtest_operator.render import naming
from tests.render.cases import CASES, SCENARIO, request

REPO = Path(__file__).resolve().parents[2]
LIBRARY = render.TemplateLibrary(REPO / "helm-templates")


def _releases(rendered: render.RenderedEnvironment) -> dict[str, dict[str, Any]]:
    assert rendered.helmfile is not None
    return {r["name"]: r for r in yaml.safe_load(rendered.helmfile)["releases"]}


def _values(release: dict[str, Any]) -> dict[str, Any]:
    (values,) = release["values"]
    assert isinstance(values, dict)
    return values


def test_charts_dir_defaults_to_the_helmfile_image_and_is_overridable() -> None:
    assert render.CHARTS_DIR == packaging.IMAGE_CHARTS_DIR
    rendered = render.render_environment(request(), LIBRARY)
    assert rendered.values["global"]["chartsDir"] == packaging.IMAGE_CHARTS_DIR
    sim = _releases(rendered)["demo-b00003-e007-a2-sim"]
    assert sim["chart"] == f"{packaging.IMAGE_CHARTS_DIR}/simtest-simulator"
    moved = render.render_environment(request(charts_dir="/src/charts/"), LIBRARY)
    assert _releases(moved)["demo-b00003-e007-a2-sim"]["chart"] == "/src/charts/simtest-simulator"


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_simulator_release_carries_the_rendered_pod_verbatim(case: str) -> None:
    rendered = render.render_environment(CASES[case], LIBRARY)
    releases = _releases(rendered)
    sims = [r for r in releases.values() if r["chart"].endswith("/simtest-simulator")]
    assert len(sims) == 1
    assert sims[0]["namespace"] == rendered.pod["metadata"]["namespace"] == "ci"
    assert _values(sims[0])["pod"] == rendered.pod
    assert all(r["namespace"] == "ci" for r in releases.values())


def _custom(tmp_path: Path, helmfile: str) -> render.TemplateLibrary:
    folder = tmp_path / "custom"
    folder.mkdir()
    for name in ("values.yaml.j2", "pod.yaml.j2"):
        (folder / name).write_text((REPO / "helm-templates" / "default" / name).read_text())
    (folder / "helmfile.yaml.j2").write_text(helmfile)
    return render.TemplateLibrary(tmp_path)


@pytest.mark.parametrize(
    ("helmfile", "words"),
    [
        ("releases: []\n", "non-empty `releases:`"),
        (
            "releases:\n- {name: x, namespace: ci, "
            'chart: "{{ values.global.chartsDir }}/k8s-ros"}\n',
            "exactly one release must use the simtest-simulator chart (found 0)",
        ),
        (
            "releases:\n- {{ simulatorRelease | toyaml | indent(2) }}\n"
            "- {{ simulatorRelease | toyaml | indent(2) }}\n",
            "appears twice",
        ),
        (
            "releases:\n- {{ simulatorRelease | merge({'namespace': 'other'}) "
            "| toyaml | indent(2) }}\n",
            "must be installed in 'ci'",
        ),
        (
            "releases:\n- name: sim\n  namespace: ci\n  chart: /c/simtest-simulator\n"
            "  values:\n  - pod: {{ pod | merge({'metadata': {'labels': {'x': 'y'}}}) | json }}\n",
            "must pass the rendered pod unchanged",
        ),
        (
            "releases:\n- name: Sim_1\n  namespace: ci\n  chart: /c/simtest-simulator\n"
            "  values: [values/sim.yaml]\n",
            "DNS label",
        ),
    ],
)
def test_a_helmfile_breaking_the_contract_is_refused(
    tmp_path: Path, helmfile: str, words: str
) -> None:
    with pytest.raises(RenderError) as caught:
        render.render_environment(request(template="custom"), _custom(tmp_path, helmfile))
    assert "renders a helmfile the operator cannot use" in str(caught.value)
    assert words in str(caught.value)


@pytest.mark.parametrize("template", ["default", "ros2"])
@pytest.mark.parametrize(
    ("override", "lost"),
    [
        ({"simulator": None}, "simulator"),
        ({"simulator": {"image": None}}, "simulator.image"),
        ({"simulator": {"resources": {"limits": None}}}, "simulator.resources.limits.cpu"),
        ({"simulator": {"resources": {"requests": {"memory": ""}}}}, "requests.memory"),
    ],
)
def test_overrides_cannot_remove_the_simulator_unit(
    template: str, override: dict[str, Any], lost: str
) -> None:
    with pytest.raises(RenderError) as caught:
        render.render_environment(request(template=template, values=override), LIBRARY)
    message = str(caught.value)
    assert "spec.environment.values removes the simulator unit" in message
    assert lost in message


def test_overrides_may_change_the_simulator_unit() -> None:
    values = {"simulator": {"image": "registry.example.org/runner:dev", "gpu": 1}}
    rendered = render.render_environment(request(values=values), LIBRARY)
    container = rendered.pod["spec"]["containers"][0]
    assert container["image"] == "registry.example.org/runner:dev"
    assert container["resources"]["limits"]["nvidia.com/gpu"] == "1"


def test_release_names_stay_within_helms_limit() -> None:
    long_env = "a-very-long-campaign-name-for-release-tests-b00003-e007-a2"
    names = {naming.release_name(long_env, c) for c in ("sim", "perception", "planning")}
    assert len(names) == 3
    assert all(len(n) <= naming.RELEASE_LENGTH for n in names)
    assert naming.release_name(long_env, "sim") == naming.release_name(long_env, "sim")
    assert naming.release_name("short", "sim") == "short-sim"
    rendered = render.render_environment(request(template="ros2", name=long_env), LIBRARY)
    assert all(len(name) <= naming.RELEASE_LENGTH for name in _releases(rendered))
    assert rendered.pod["metadata"]["name"] == long_env


def test_ros_domain_ids_are_deterministic_and_in_range() -> None:
    ids = {naming.ros_domain_id("ci", f"demo-b00000-e{i:03d}-a1") for i in range(300)}
    assert ids <= set(range(1, 102)) and len(ids) > 50
    assert naming.ros_domain_id("ci", "x") == naming.ros_domain_id("ci", "x")


def test_the_sut_release_exists_only_with_an_image_and_has_k8s_ros_values() -> None:
    without = _releases(render.render_environment(request(), LIBRARY))
    assert list(without) == ["demo-b00003-e007-a2-sim"]
    rendered = render.render_environment(CASES["reuse-values-override"], LIBRARY)
    sut = _releases(rendered)["demo-b00003-e007-a2-sut"]
    assert sut["chart"].endswith("/k8s-ros")
    values = _values(sut)
    schema = json_properties(REPO / "charts" / "k8s-ros" / "values.schema.json")
    assert set(values) <= schema
    assert values["image"] == "registry.example.org/stack:2.0.0"
    assert values["ownerReferences"][0]["uid"] == "0d1e2f3a"
    assert values["resources"] == {"requests": {"cpu": "250m"}}  # the campaign's override
    assert values["labels"]["simtest.dev/environment"] == "demo-b00003-e007-a2"
    assert "app.kubernetes.io/managed-by" not in values["labels"]  # the chart sets its own


def json_properties(path: Path) -> set[str]:
    return set(yaml.safe_load(path.read_text())["properties"])


def test_ros2_composes_the_stack_from_the_merged_values() -> None:
    rendered = render.render_environment(CASES["ros2-overrides"], LIBRARY)
    releases = _releases(rendered)
    components = sorted(r["labels"]["component"] for r in releases.values())
    assert components == ["evaluator", "perception", "planning", "simulator"]  # control off
    env = {e["name"]: e["value"] for e in rendered.pod["spec"]["containers"][0]["env"]}
    assert env["ROS_DOMAIN_ID"] == "42"
    schema = json_properties(REPO / "charts" / "k8s-ros" / "values.schema.json")
    for release in releases.values():
        if release["labels"]["component"] == "simulator":
            continue
        values = _values(release)
        assert set(values) <= schema
        assert values["ros"] == {"domainId": 42, "rmw": "rmw_fastrtps_cpp"}
        assert values["image"] == "ghcr.io/acme/stack:3.1.0"
        assert values["dds"]["peers"] == []  # unicastPeers: false
        assert values["fullnameOverride"] == release["name"]
    planning = _values(releases["demo-b00003-e007-a2-planning"])
    assert planning["args"] == ["ros2", "launch", "acme_planning", "planner.launch.py"]
    assert planning["resources"]["requests"] == {"cpu": "1", "memory": "128Mi"}
    assert set(planning["params"]) == {"planning.yaml", "stack.yaml"}


def test_ros2_peers_are_the_enabled_components() -> None:
    rendered = render.render_environment(
        request(template="ros2", values={"stack": {"components": {"evaluator": {"enabled": 0}}}}),
        LIBRARY,
    )
    domain = naming.ros_domain_id("ci", "demo-b00003-e007-a2")
    for name, release in _releases(rendered).items():
        if name.endswith("-sim"):
            continue
        values = _values(release)
        assert values["dds"]["peers"] == [
            f"demo-b00003-e007-a2-{c}" for c in ("control", "perception", "planning")
        ]
        assert values["ros"]["domainId"] == domain
        assert values["ports"][0]["containerPort"] == 7410 + 250 * domain


def test_markup_in_resource_data_stays_data() -> None:
    markup = "{{ 7 * 7 }}{% raw %}"
    scenario = dataclasses.replace(SCENARIO, overrides={"Speed": markup})
    rendered = render.render_environment(
        request(template="ros2", scenarios=(scenario,), sut={"config": {"k": markup}}), LIBRARY
    )
    assert rendered.run_spec.scenarios[0].overrides["Speed"] == markup
    perception = _values(_releases(rendered)["demo-b00003-e007-a2-perception"])
    assert perception["params"]["stack.yaml"]["/**"]["ros__parameters"]["sut"] == {"k": markup}
    assert "49" not in yaml.safe_dump(perception)
