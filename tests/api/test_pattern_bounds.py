"""The scenario include/exclude glob lists are bounded (issue 12, item 3): a manifest with more than
256 patterns is refused with one line naming the field, locally and in the CRD schema the API
server enforces (``maxItems``), while 256 are accepted."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner

from simtest_operator.api.v1alpha1 import sources
from simtest_operator.cli.main import cli

CRD = Path(__file__).resolve().parents[2] / "crds" / "simtest.dev_testcampaigns.yaml"
MANIFEST = """apiVersion: simtest.dev/v1alpha1
kind: TestCampaign
metadata: {{name: demo}}
spec:
  scenarios:
    sources: [{{path: suite}}]
    {field}: [{patterns}]
"""


@pytest.mark.parametrize("field", ["include", "exclude"])
def test_more_than_256_patterns_are_refused_in_one_line(tmp_path: Path, field: str) -> None:
    (tmp_path / "suite").mkdir()
    path = tmp_path / "m.yaml"
    patterns = ", ".join(f"'s{i}/*.xosc'" for i in range(sources.MAX_PATTERNS + 1))
    path.write_text(MANIFEST.format(field=field, patterns=patterns))
    result = CliRunner().invoke(
        cli,
        ["run", str(path), "--engine", "fake", "-o", str(tmp_path / "out")],
        env={"SIMTEST_CACHE_DIR": str(tmp_path / "cache")},
    )
    assert result.exit_code == 2, result.output
    assert f"spec.scenarios.{field}" in result.output and "256" in result.output, result.output
    assert result.output.count("\n") == 1, result.output
    assert not (tmp_path / "out").exists()


def test_256_patterns_are_accepted() -> None:
    selection = sources.ScenarioSelection.model_validate(
        {"sources": [{"path": "suite"}], "include": [f"s{i}" for i in range(256)]}
    )
    assert len(selection.include) == 256


def test_the_crd_schema_bounds_the_lists() -> None:
    crd = yaml.safe_load(CRD.read_text())
    schema = crd["spec"]["versions"][0]["schema"]["openAPIV3Schema"]
    scenarios = schema["properties"]["spec"]["properties"]["scenarios"]["properties"]
    assert scenarios["include"]["maxItems"] == sources.MAX_PATTERNS
    assert scenarios["exclude"]["maxItems"] == sources.MAX_PATTERNS
    assert scenarios["selector"]["properties"]["matchTags"]["maxItems"] == 64
