"""``simtest package ros``: a repository's chart generated from its spec, rendered by real helm.

Covers: the generated files (wrapper Chart.yaml with the base dependency, values under `k8s-ros`
with parameter files inlined verbatim, overrides under templates/, vendored base chart);
byte-identical output on every run; refusals (params that are not ROS 2 parameter files, files
outside the spec's folder, a base version that cannot be vendored, --no-vendor without a
repository, override files of the wrong type); the CLI writes and replaces the chart folder; and
with the real helm, for three specs: `helm lint --strict` passes, `helm template` renders the
expected workload, the wrapper's named-template override replaces the base's, and
`--no-vendor` output resolves the base through `helm dependency update` from a file:// repository.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

from simtest_operator.cli.main import cli
from simtest_operator.errors import RenderError
from simtest_operator.packaging import rospackaging
from tests.charts.helmtools import ROS_CHART, Tool, documents, find, restricted_problems

SPECS = Path(__file__).parent / "testdata" / "ros"


def _inputs(name: str) -> rospackaging.PackageInputs:
    return rospackaging.load_inputs(SPECS / name / "package.yaml", ROS_CHART)


def _generate(tmp_path: Path, name: str, *, vendor: bool = True) -> Path:
    files = rospackaging.chart_files(_inputs(name), vendor=vendor)
    return rospackaging.write(files, tmp_path / "out", _inputs(name).spec.name)


def test_generated_files_of_the_planner() -> None:
    files = rospackaging.chart_files(_inputs("planner"))
    chart = yaml.safe_load(files["Chart.yaml"])
    assert chart["name"] == "planner" and chart["version"] == "1.4.0"
    base_version = yaml.safe_load((ROS_CHART / "Chart.yaml").read_text())["version"]
    assert chart["dependencies"] == [{"name": "k8s-ros", "version": base_version, "repository": ""}]
    values = yaml.safe_load(files["values.yaml"])["k8s-ros"]
    assert values["image"] == "ghcr.io/acme/planner:1.4.0"
    assert values["command"] == ["ros2"]
    assert values["ros"] == {"domainId": 3, "rmw": "rmw_cyclonedds_cpp"}
    assert values["env"] == {"PLANNER_MODE": "simulation"}  # spec.values merged in
    source = (SPECS / "planner" / "config" / "planner.yaml").read_text()
    assert values["params"]["planner.yaml"] == source  # verbatim, comments included
    assert list(values["params"]) == ["planner.yaml", "limits.yaml"]
    assert b"planner.yaml: |" in files["values.yaml"]  # readable literal block
    assert files["templates/_overrides.tpl"].startswith(b"{{- /*")
    vendored = {path for path in files if path.startswith("charts/k8s-ros/")}
    assert "charts/k8s-ros/Chart.yaml" in vendored
    assert "charts/k8s-ros/values.schema.json" in vendored
    assert files["charts/k8s-ros/values.yaml"] == (ROS_CHART / "values.yaml").read_bytes()


@pytest.mark.parametrize("name", ["planner", "perception", "minimal"])
def test_generation_is_byte_identical(name: str, tmp_path: Path) -> None:
    first = rospackaging.chart_files(_inputs(name))
    second = rospackaging.chart_files(_inputs(name))
    assert first == second
    target = _generate(tmp_path, name)
    on_disk = {
        p.relative_to(target).as_posix(): p.read_bytes() for p in target.rglob("*") if p.is_file()
    }
    assert on_disk == first


def _spec_folder(tmp_path: Path, spec: str, files: dict[str, str]) -> Path:
    folder = tmp_path / "repo"
    folder.mkdir(exist_ok=True)
    (folder / "package.yaml").write_text(spec)
    for relative, text in files.items():
        (folder / relative).parent.mkdir(parents=True, exist_ok=True)
        (folder / relative).write_text(text)
    return folder / "package.yaml"


BASE = "name: app\nversion: 1.0.0\nimage: a/b:1\n"


@pytest.mark.parametrize(
    ("spec", "files", "message"),
    [
        (BASE + "params: [p.yaml]\n", {"p.yaml": "a: 1\n"}, "not a ROS 2 parameter file"),
        (BASE + "params: [p.yaml]\n", {"p.yaml": "- [\n"}, "not UTF-8 YAML"),
        (BASE + "params: [p.yaml]\n", {}, "cannot read params file"),
        (BASE + "templates: t\n", {"t": "not a folder"}, "is not a folder"),
        (BASE + "base: {version: 9.9.9}\n", {}, "differs from the base chart being vendored"),
        (BASE + "templates: t\n", {"t/deploy.json": "{}"}, "must end with one of"),
    ],
)
def test_refusals(tmp_path: Path, spec: str, files: dict[str, str], message: str) -> None:
    path = _spec_folder(tmp_path, spec, files)
    with pytest.raises(RenderError, match=message):
        rospackaging.chart_files(rospackaging.load_inputs(path, ROS_CHART))


def test_symlinked_params_cannot_escape(tmp_path: Path) -> None:
    outside = tmp_path / "secret.yaml"
    outside.write_text("x:\n  ros__parameters: {token: 1}\n")
    path = _spec_folder(tmp_path, BASE + "params: [p.yaml]\n", {})
    (path.parent / "p.yaml").symlink_to(outside)
    with pytest.raises(RenderError, match="outside the spec's folder"):
        rospackaging.load_inputs(path, ROS_CHART)


def test_no_vendor_needs_a_repository() -> None:
    with pytest.raises(RenderError, match=r"base\.repository"):
        rospackaging.chart_files(_inputs("minimal"), vendor=False)


def test_cli_writes_and_replaces_the_chart(tmp_path: Path) -> None:
    out = tmp_path / "dist"
    (out / "bridge" / "stale.txt").parent.mkdir(parents=True)
    (out / "bridge" / "stale.txt").write_text("old")
    runner = CliRunner()
    args = ["package", "ros", str(SPECS / "minimal" / "package.yaml"), "--out", str(out)]
    result = runner.invoke(cli, [*args, "--base-chart", str(ROS_CHART)])
    assert result.exit_code == 0, result.output
    assert "bridge 0.1.0" in result.output
    assert not (out / "bridge" / "stale.txt").exists()
    assert (out / "bridge" / "charts" / "k8s-ros" / "Chart.yaml").is_file()
    assert [p.name for p in out.iterdir()] == ["bridge"]  # no staging leftovers
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: Bad\n")
    result = runner.invoke(cli, ["package", "ros", str(bad), "--base-chart", str(ROS_CHART)])
    assert result.exit_code == 1 and "RFC 1123" in result.output


# --- with the real helm --------------------------------------------------------------------


@pytest.mark.parametrize("name", ["planner", "perception", "minimal"])
def test_generated_charts_lint_clean(name: str, tmp_path: Path, helm: Tool) -> None:
    chart = _generate(tmp_path, name)
    result = helm.run("lint", "--strict", chart)
    assert "0 chart(s) failed" in result.stdout


def test_planner_renders_with_its_override(tmp_path: Path, helm: Tool) -> None:
    chart = _generate(tmp_path, "planner")
    docs = documents(helm.run("template", "planner", chart, "--namespace", "tests").stdout)
    deployment = find(docs, "Deployment", "planner")
    container = deployment["spec"]["template"]["spec"]["containers"][0]
    assert container["name"] == "planner"
    assert container["image"] == "ghcr.io/acme/planner:1.4.0"
    assert container["command"] == ["ros2"]
    # The wrapper's k8s-ros.args replaced the base's: launch arguments, no --ros-args.
    assert container["args"] == [
        "launch",
        "planner",
        "planner.launch.py",
        "params_file:=/etc/ros/params/limits.yaml",
        "params_file:=/etc/ros/params/planner.yaml",
    ]
    env = {item["name"]: item.get("value") for item in container["env"]}
    assert env["ROS_DOMAIN_ID"] == "3" and env["PLANNER_MODE"] == "simulation"
    params = find(docs, "ConfigMap", "planner-params")["data"]
    assert params["planner.yaml"] == (SPECS / "planner" / "config" / "planner.yaml").read_text()
    dds = find(docs, "ConfigMap", "planner-dds")["data"]["cyclonedds.xml"]
    assert '<Peer Address="10.0.0.12"/>' in dds
    service = find(docs, "Service", "planner")
    assert service["spec"]["clusterIP"] == "None"
    assert restricted_problems(deployment["spec"]["template"]["spec"]) == []


def test_perception_job_renders(tmp_path: Path, helm: Tool) -> None:
    chart = _generate(tmp_path, "perception")
    docs = documents(helm.run("template", "replay", chart, "--namespace", "tests").stdout)
    job = find(docs, "Job")
    assert job["spec"]["activeDeadlineSeconds"] == 900
    pod = job["spec"]["template"]["spec"]
    container = pod["containers"][0]
    assert container["image"].endswith("@sha256:" + "0123456789abcdef" * 4)
    assert container["imagePullPolicy"] == "Always"
    assert container["command"] == ["ros2", "run", "perception", "replay_node"]
    assert container["args"] == [
        "--rate",
        "2.0",
        "--ros-args",
        "--params-file",
        "/etc/ros/params/detector.yaml",
    ]
    env = {item["name"]: item.get("value") for item in container["env"]}
    assert env["RMW_IMPLEMENTATION"] == "rmw_fastrtps_cpp"
    assert env["ROS_LOCALHOST_ONLY"] == "1"
    assert env["FASTRTPS_DEFAULT_PROFILES_FILE"] == "/etc/ros/dds/fastdds.xml"
    assert pod["restartPolicy"] == "Never"


def test_unvendored_chart_resolves_the_base_from_a_repository(tmp_path: Path, helm: Tool) -> None:
    base_copy = tmp_path / "registry" / "k8s-ros"
    shutil.copytree(ROS_CHART, base_copy)
    spec = (SPECS / "minimal" / "package.yaml").read_text()
    spec += f"base: {{repository: 'file://{base_copy}'}}\n"
    path = _spec_folder(tmp_path, spec, {})
    files = rospackaging.chart_files(rospackaging.load_inputs(path, ROS_CHART), vendor=False)
    assert not any(name.startswith("charts/") for name in files)
    chart = rospackaging.write(files, tmp_path / "out", "bridge")
    helm.run("dependency", "update", chart)
    docs = documents(helm.run("template", "bridge", chart).stdout)
    assert find(docs, "Deployment")["spec"]["template"]["spec"]["containers"][0]["image"] == (
        "ghcr.io/acme/bridge:0.1.0"
    )
