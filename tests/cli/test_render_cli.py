"""``simtest render MANIFEST --scenario ID``: the operator's files for one scenario.

Covers: the summary (environment named as the operator names it from the scenario's position and
the batch size, template, scenario, pod, releases, content hash) and exit 0; ``--out`` writes
values.yaml, pod.yaml and helmfile.yaml, byte-identical across runs; the pod carries the
operator's labels and owner reference and runs the scenario; ``--charts-dir`` and
``--namespace`` (else the manifest's namespace, else ``default``); the campaign's
``spec.environment`` (template, SUT, values) reaches the files; exit 2 with one line for an
unknown scenario (with close matches), an invalid manifest, an unknown template and an override
that removes the simulator unit.
"""

from __future__ import annotations

import json
from pathlib import Path

import yaml
from click.testing import CliRunner

from simtest_operator.cli.main import cli
from tests.runner.support import write_campaign

REPO = Path(__file__).resolve().parents[2]
TEMPLATES = str(REPO / "helm-templates")
ROS2 = """  environment:
    template: ros2
    sut: {name: stack, version: 1.0.0, image: ghcr.io/acme/stack:1.0}
    values:
      ros: {domainId: 42}
"""


def invoke(tmp_path: Path, *args: str) -> tuple[int, str, str]:
    env = {"SIMTEST_CACHE_DIR": str(tmp_path / "cache")}
    result = CliRunner().invoke(cli, ["render", *args, "--templates", TEMPLATES], env=env)
    return result.exit_code, result.stdout, result.stderr


def campaign(tmp_path: Path, extra: str = "") -> Path:
    return write_campaign(
        tmp_path, {"a": "pass", "b": "pass", "cut-in": "pass"}, batch_size=2, extra=extra
    )


def test_summary_names_the_environment_as_the_operator_would(tmp_path: Path) -> None:
    manifest = campaign(tmp_path)
    code, out, err = invoke(tmp_path, str(manifest), "--scenario", "cut-in.xosc")
    assert code == 0, err
    lines = out.splitlines()
    assert lines[0] == "environment  default/demo-b00001-e000-a1 (template default)"
    assert lines[1] == "scenario     cut-in.xosc"
    assert lines[2].startswith("pod          demo-b00001-e000-a1 image ")
    assert lines[3] == "release      demo-b00001-e000-a1-sim (simtest-simulator)"
    assert lines[-1].startswith("hash         sha256:") and len(lines[-1]) == 13 + 7 + 64
    assert invoke(tmp_path, str(manifest), "--scenario", "cut-in.xosc")[1] == out


def test_out_writes_the_files_byte_identically(tmp_path: Path) -> None:
    manifest = campaign(tmp_path, ROS2)
    outputs = []
    for run in ("one", "two"):
        code, out, err = invoke(
            tmp_path, str(manifest), "--scenario", "b.xosc", "--out", str(tmp_path / run),
            "--charts-dir", "/srv/charts", "--namespace", "ci",
        )  # fmt: skip
        assert code == 0, err
        assert f"wrote        {tmp_path / run / 'helmfile.yaml'}, " in out
        outputs.append({p.name: p.read_bytes() for p in sorted((tmp_path / run).iterdir())})
    assert outputs[0] == outputs[1]
    assert sorted(outputs[0]) == ["helmfile.yaml", "pod.yaml", "values.yaml"]
    pod = yaml.safe_load(outputs[0]["pod.yaml"])
    meta = pod["metadata"]
    assert (meta["name"], meta["namespace"]) == ("demo-b00000-e001-a1", "ci")
    assert meta["labels"]["simtest.dev/campaign"] == "demo"
    assert meta["labels"]["simtest.dev/batch"] == "demo-b00000"
    assert meta["labels"]["app.kubernetes.io/managed-by"] == "simtest-operator"
    assert meta["ownerReferences"][0]["kind"] == "SimEnvironment"
    env = {e["name"]: e.get("value") for e in pod["spec"]["containers"][0]["env"]}
    assert [s["id"] for s in json.loads(env["SIMTEST_RUN_SPEC"])["scenarios"]] == ["b.xosc"]
    assert env["ROS_DOMAIN_ID"] == "42"
    helmfile = yaml.safe_load(outputs[0]["helmfile.yaml"])
    charts = {r["chart"] for r in helmfile["releases"]}
    assert charts == {"/srv/charts/simtest-simulator", "/srv/charts/k8s-ros"}
    values = yaml.safe_load(outputs[0]["values.yaml"])
    assert values["stack"]["image"] == "ghcr.io/acme/stack:1.0"


def test_the_manifest_namespace_is_the_default(tmp_path: Path) -> None:
    manifest = campaign(tmp_path)
    manifest.write_text(
        manifest.read_text().replace("  name: demo\n", "  name: demo\n  namespace: sim\n")
    )
    code, out, err = invoke(tmp_path, str(manifest), "--scenario", "a.xosc")
    assert code == 0, err
    assert out.splitlines()[0] == "environment  sim/demo-b00000-e000-a1 (template default)"


def test_an_unknown_scenario_exits_2_with_close_matches(tmp_path: Path) -> None:
    code, out, err = invoke(tmp_path, str(campaign(tmp_path)), "--scenario", "cutin")
    assert code == 2 and out == ""
    assert err == (
        "simtest render: unknown scenario 'cutin': campaign demo selects 3 scenario(s); "
        "close matches: cut-in.xosc\n"
    )


def test_bad_input_exits_2_with_one_line(tmp_path: Path) -> None:
    manifest = campaign(tmp_path)
    text = manifest.read_text()
    cases = {
        "timeoutSecs": (text.replace("timeoutSeconds: 20", "timeoutSecs: 20"), "timeoutSecs"),
        "template": (
            text + "  environment:\n    template: nowhere\n",
            "environment template 'nowhere' not found",
        ),
        "override": (
            text + "  environment:\n    values: {simulator: null}\n",
            "removes the simulator unit",
        ),
    }
    for name, (body, words) in cases.items():
        bad = tmp_path / f"{name}.yaml"
        bad.write_text(body)
        code, out, err = invoke(tmp_path, str(bad), "--scenario", "a.xosc")
        assert code == 2, (name, out, err)
        assert err.startswith("simtest render: ") and err.count("\n") == 1, err
        assert words in err, err
