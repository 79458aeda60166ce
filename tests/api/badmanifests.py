"""The table of invalid manifests (testdata/bad-manifests.yaml), shared by the local and the
API-server variants of the bad-input test."""

from __future__ import annotations

import copy
import dataclasses
from pathlib import Path
from typing import Any

import yaml

TABLE = Path(__file__).parent / "testdata" / "bad-manifests.yaml"


@dataclasses.dataclass(frozen=True)
class BadManifest:
    id: str
    manifest: dict[str, Any]
    field: str
    local_only: bool

    def names_field(self, message: str) -> bool:
        """Whether ``message`` points at the field: its parent path and its own name both appear.

        The API server says ``spec.execution.maxParallel: Invalid value`` where a model-level rule
        says ``spec.execution: ... maxParallel ...``; both name the field for a person."""
        parent, _, leaf = self.field.rpartition(".")
        leaf_name = leaf.split("[", 1)[0]
        return (not parent or parent in message) and leaf_name in message


def merge(base: dict[str, Any], patch: dict[str, Any]) -> dict[str, Any]:
    """Deep-merge ``patch`` into a copy of ``base``; ``None`` deletes a key."""
    merged = copy.deepcopy(base)
    for key, value in patch.items():
        if value is None:
            merged.pop(key, None)
        elif isinstance(value, dict) and isinstance(merged.get(key), dict):
            merged[key] = merge(merged[key], value)
        else:
            merged[key] = copy.deepcopy(value)
    return merged


def load() -> list[BadManifest]:
    """Every case of the table, with its manifest built."""
    table = yaml.safe_load(TABLE.read_text(encoding="utf-8"))
    return [
        BadManifest(
            id=case["id"],
            manifest=merge(table["base"], case["patch"]),
            field=case["field"],
            local_only=bool(case.get("local_only", False)),
        )
        for case in table["cases"]
    ]


def base() -> dict[str, Any]:
    """The valid manifest every case starts from."""
    return dict(yaml.safe_load(TABLE.read_text(encoding="utf-8"))["base"])
