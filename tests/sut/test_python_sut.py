"""The standalone Python example SUT (deploy/sut-python/sut.py: OSI through betterosi, written
from docs/sut-interface.md) imports nothing of simtest; its verdicts equal the in-process model's
on the whole smoke campaign through ``simtest run`` (the hard-braking cases are in
test_example_suts.py), and its own log becomes each scenario's ``sut.log``."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import yaml
from click.testing import CliRunner

from simtest_operator.cli.main import cli

REPO = Path(__file__).resolve().parents[2]
EXAMPLE = REPO / "deploy" / "sut-python" / "sut.py"
SCENARIO = REPO / "tests" / "sim" / "data" / "hard_braking_lead.xosc"


def test_the_example_uses_nothing_of_simtest() -> None:
    tree = ast.parse(EXAMPLE.read_text(encoding="utf-8"))
    imported = {
        alias.name.split(".")[0]
        for node in ast.walk(tree)
        if isinstance(node, ast.Import)
        for alias in node.names
    } | {
        (node.module or "").split(".")[0]
        for node in ast.walk(tree)
        if isinstance(node, ast.ImportFrom)
    }
    assert "simtest_operator" not in imported
    assert "betterosi" in imported


def test_the_smoke_campaign_driven_by_the_example_gives_the_smoke_verdicts(
    tmp_path: Path,
) -> None:
    manifest = yaml.safe_load((REPO / "scenarios" / "external-sut-campaign.yaml").read_text())
    manifest["spec"]["scenarios"]["sources"] = [{"path": str(REPO / "scenarios" / "smoke")}]
    manifest["spec"]["environment"]["sut"]["external"]["command"] = [
        "{python}",
        str(EXAMPLE),
        "--port",
        "{port}",
    ]
    path = tmp_path / "campaign.yaml"
    path.write_text(yaml.safe_dump(manifest))
    found = {}
    for name, campaign in (("smoke", REPO / "scenarios" / "smoke-campaign.yaml"), ("py", path)):
        arguments = ["run", str(campaign), "-o", str(tmp_path / name), "-j", "1", "--plain"]
        result = CliRunner().invoke(cli, arguments)
        assert result.exit_code == 1, result.output  # the smoke campaign's deliberate failure
        found[name] = {
            (result := json.loads(p.read_text()))["scenarioId"]: result
            for p in (tmp_path / name).glob("scenarios/*/result.json")
        }
    assert len(found["smoke"]) == 6
    assert {k: v["verdict"] for k, v in found["py"].items()} == {
        k: v["verdict"] for k, v in found["smoke"].items()
    }
    for scenario_id, result in found["py"].items():
        log = tmp_path / "py" / result["artifacts"]["sutLog"]  # relative to the output folder
        assert f"sut-python: run {scenario_id}" in log.read_text(), scenario_id
