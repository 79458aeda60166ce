"""Chart artefacts that need no helm: generated copies, documentation and values schemas.

Covers: the operator chart's CRDs are byte copies of crds/ (the one source) and the values tables
in docs/ match the charts (``simtest package sync --check``); every key of both charts' values.yaml
is documented with a ``# --`` comment; values.yaml and values.schema.json describe the same keys
(no key the schema would reject, no schema key without a default), the schemas reject unknown keys
at every fixed level, and `helm lint` (test_chart_render) validates the defaults against them.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml

from simtest_operator.packaging import syncing, valuesdoc
from tests.charts.helmtools import OPERATOR_CHART, REPO, ROS_CHART, SIMULATOR_CHART

CHARTS = [OPERATOR_CHART, ROS_CHART, SIMULATOR_CHART]


def test_chart_crds_and_docs_are_in_sync() -> None:
    assert syncing.sync_all(REPO, check=True) == []


def test_crd_copies_detect_drift(tmp_path: Path) -> None:
    source, target = tmp_path / "crds", tmp_path / "chart"
    source.mkdir()
    (source / "a.yaml").write_text("a: 1\n")
    (source / "b.yaml").write_text("b: 1\n")
    target.mkdir()
    (target / "a.yaml").write_text("a: 2\n")
    (target / "stale.yaml").write_text("x: 1\n")
    assert syncing.sync(source, target, check=True) == ["a.yaml", "b.yaml", "stale.yaml"]
    assert (target / "a.yaml").read_text() == "a: 2\n"  # check mode writes nothing
    assert syncing.sync(source, target) == ["a.yaml", "b.yaml", "stale.yaml"]
    assert sorted(p.name for p in target.iterdir()) == ["a.yaml", "b.yaml"]
    assert syncing.sync(source, target, check=True) == []


@pytest.mark.parametrize("chart", CHARTS, ids=lambda c: c.name)
def test_every_value_is_documented(chart: Path) -> None:
    text = (chart / "values.yaml").read_text(encoding="utf-8")
    assert valuesdoc.undocumented(text) == []
    rows = valuesdoc.documented(text)
    assert all(row.description for row in rows)


def _fixed(schema: dict[str, Any]) -> bool:
    return "properties" in schema and schema.get("additionalProperties") is False


def _schema_paths(schema: dict[str, Any], prefix: str = "") -> set[str]:
    """Keys a schema fixes (objects with ``properties`` and ``additionalProperties: false``)."""
    paths = set()
    for key, sub in schema.get("properties", {}).items():
        path = f"{prefix}.{key}" if prefix else key
        paths.add(path)
        if _fixed(sub):
            paths |= _schema_paths(sub, path)
    return paths


def _value_paths(values: Any, schema: dict[str, Any], prefix: str = "") -> set[str]:
    """Keys of values.yaml down to where the schema stops fixing them."""
    paths = set()
    for key, value in values.items():
        path = f"{prefix}.{key}" if prefix else key
        paths.add(path)
        sub = schema.get("properties", {}).get(key, {})
        if isinstance(value, dict) and _fixed(sub):
            paths |= _value_paths(value, sub, path)
    return paths


def _closed(schema: dict[str, Any], path: str = "<root>") -> list[str]:
    """Objects with properties that do not say whether they accept unknown keys (an explicit
    ``additionalProperties: true`` marks a deliberately open object, such as a Pod)."""
    open_objects = []
    if "properties" in schema and "additionalProperties" not in schema:
        open_objects.append(path)
    for key, sub in schema.get("properties", {}).items():
        open_objects += _closed(sub, f"{path}.{key}")
    for option in schema.get("oneOf", []):
        open_objects += _closed(option, path)
    return open_objects


@pytest.mark.parametrize("chart", CHARTS, ids=lambda c: c.name)
def test_values_and_schema_describe_the_same_keys(chart: Path) -> None:
    schema = json.loads((chart / "values.schema.json").read_text(encoding="utf-8"))
    values = yaml.safe_load((chart / "values.yaml").read_text(encoding="utf-8"))
    in_schema = _schema_paths(schema) - {"global"}
    in_values = _value_paths(values, schema) - {"global"}
    assert sorted(in_values - in_schema) == [], "values the schema would reject"
    assert sorted(in_schema - in_values) == [], "schema keys without a default in values.yaml"
    assert _closed(schema) == [], "objects that silently accept typos"
    assert schema["$schema"] == "http://json-schema.org/draft-07/schema#"


def test_valuesdoc_reads_multiline_comments_and_nested_keys() -> None:
    text = (
        "# -- Top.\ntop: 1\nsection:\n  # -- First line\n  # second line.\n  inner: [a]\n"
        "  plain: x\n# a normal comment\nlast: {}\n"
    )
    rows = {row.path: row for row in valuesdoc.documented(text)}
    assert rows["top"].type == "int" and rows["top"].default == "1"
    assert rows["section.inner"].description == "First line second line."
    assert rows["section.inner"].default == '["a"]'
    assert valuesdoc.undocumented(text) == ["section.plain", "last"]
    embedded = valuesdoc.embed(
        f"intro\n{valuesdoc.BEGIN}\nold\n{valuesdoc.END}\n", list(rows.values())
    )
    assert "| `section.inner` | list |" in embedded and "old" not in embedded
