"""The CRDs in crds/ are generated from the models: no drift, structural, with printer columns,
CEL rules, short names, the `simtest` category and the status subresource."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml
from click.testing import CliRunner

from simtest_operator.api import crdgen
from simtest_operator.api.v1alpha1 import kinds
from simtest_operator.cli.main import cli

REPO = Path(__file__).resolve().parents[2]
CRDS = REPO / "crds"


def _crd(kind: kinds.ResourceKind[Any]) -> dict[str, Any]:
    return dict(yaml.safe_load((CRDS / crdgen.CRD_FILES[kind.kind]).read_text(encoding="utf-8")))


def _schema(kind: kinds.ResourceKind[Any]) -> dict[str, Any]:
    return dict(_crd(kind)["spec"]["versions"][0]["schema"]["openAPIV3Schema"])


def test_check_passes_on_the_committed_crds() -> None:
    result = CliRunner().invoke(
        cli, ["crds", "--check", "--out", str(CRDS), "--docs", str(REPO / "docs")]
    )
    assert result.exit_code == 0, result.output


def test_check_fails_on_drift(tmp_path: Path) -> None:
    runner = CliRunner()
    args = ["crds", "--out", str(tmp_path), "--docs", str(tmp_path)]
    assert runner.invoke(cli, args).exit_code == 0
    assert runner.invoke(cli, [*args, "--check"]).exit_code == 0
    target = tmp_path / crdgen.CRD_FILES["TestCampaign"]
    target.write_text(target.read_text(encoding="utf-8").replace("batchSize", "batchsize"))
    result = runner.invoke(cli, [*args, "--check"])
    assert result.exit_code == 1
    assert crdgen.CRD_FILES["TestCampaign"] in result.output


def test_generation_is_deterministic() -> None:
    assert [crdgen.render(k) for k in kinds.KINDS] == [crdgen.render(k) for k in kinds.KINDS]


@pytest.mark.parametrize(
    ("kind", "columns"),
    [
        (
            kinds.TEST_CAMPAIGN,
            ["Phase", "Passed", "Failed", "Errored", "Progress", "Evaluated", "Age"],
        ),
        (kinds.SCENARIO_BATCH, ["Campaign", "Index", "Phase", "Progress", "Age"]),
        (kinds.SIM_ENVIRONMENT, ["Scenario", "Phase", "Verdict", "Node", "Age"]),
    ],
    ids=lambda value: getattr(value, "kind", None) or "columns",
)
def test_printer_columns_names_and_category(
    kind: kinds.ResourceKind[Any], columns: list[str]
) -> None:
    version = _crd(kind)["spec"]["versions"][0]
    assert [c["name"] for c in version["additionalPrinterColumns"]] == columns
    assert version["subresources"] == {"status": {}}
    names = _crd(kind)["spec"]["names"]
    assert "simtest" in names["categories"]
    assert names["shortNames"]


def _walk(node: Any, path: str = "") -> list[tuple[str, dict[str, Any]]]:
    found: list[tuple[str, dict[str, Any]]] = []
    if isinstance(node, dict):
        found.append((path, node))
        for name, child in node.get("properties", {}).items():
            found.extend(_walk(child, f"{path}.{name}"))
        if "items" in node:
            found.extend(_walk(node["items"], f"{path}[]"))
        if isinstance(node.get("additionalProperties"), dict):
            found.extend(_walk(node["additionalProperties"], f"{path}{{}}"))
    return found


@pytest.mark.parametrize("kind", kinds.KINDS, ids=lambda k: k.kind)
def test_schema_is_structural(kind: kinds.ResourceKind[Any]) -> None:
    for path, node in _walk(_schema(kind)):
        assert "type" in node or node.get("x-kubernetes-preserve-unknown-fields"), path
        for forbidden in ("$ref", "anyOf", "oneOf", "allOf", "title", "$defs"):
            assert forbidden not in node, f"{path} has {forbidden}"
        if node.get("exclusiveMinimum") is not None:
            assert isinstance(node["exclusiveMinimum"], bool), path


def test_cel_rules_are_present() -> None:
    rules = [
        (path, rule["rule"])
        for path, node in _walk(_schema(kinds.TEST_CAMPAIGN))
        for rule in node.get("x-kubernetes-validations", [])
    ]
    paths = {path for path, _ in rules}
    assert ".spec.scenarios.sources[]" in paths
    assert ".spec.execution" in paths
    assert "" in paths  # the root rule on metadata.name


def test_nested_defaults_apply() -> None:
    spec = _schema(kinds.TEST_CAMPAIGN)["properties"]["spec"]["properties"]
    assert spec["execution"]["default"] == {}
    assert spec["execution"]["properties"]["batchSize"]["default"] == 10
    assert spec["execution"]["properties"]["isolation"]["enum"] == ["PerScenario", "Reuse"]
    assert spec["scenarios"]["properties"]["include"]["default"] == ["**/*.xosc"]


def test_conditions_are_a_map_list() -> None:
    status = _schema(kinds.TEST_CAMPAIGN)["properties"]["status"]["properties"]
    assert status["conditions"]["x-kubernetes-list-type"] == "map"
    assert status["conditions"]["x-kubernetes-list-map-keys"] == ["type"]
