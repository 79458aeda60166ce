"""Every .xosc of esmini's examples in the shared corpus loads or fails as esmini did.

Covers: classification of all files (scenario/catalog/distribution); every scenario that the
reference player esmini ran (``esmini-reference.json`` rc 0) loads without error; the only
failures are files esmini fails on too (missing catalogs), with their reasons; the distribution
file expands and every concrete run loads; and the inventory of unsupported elements across the
corpus, so a change in coverage is noticed. A table of failures is printed (``pytest -s``).
"""

from __future__ import annotations

import collections
import json
from pathlib import Path

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import FileKind, expand_distribution, file_kind, load_scenario

EXPECTED_UNSUPPORTED: dict[str, str] = {}
"""Unsupported element kinds found in the corpus, each with one file that has it (none since
trailers are simulated)."""


def _reference(corpus: Path) -> dict[str, int]:
    data = json.loads((corpus / "esmini-reference.json").read_text())
    return {key: entry["rc"] for key, entry in data["scenarios"].items()}


def test_corpus_loads_like_esmini(corpus_dir: Path) -> None:
    # esmini's example folder; its unit-test scenarios (esmini/EnvironmentSimulator/Unittest,
    # added to the corpus later) are measured separately, by scenario coverage.
    files = sorted((corpus_dir / "esmini" / "resources").rglob("*.xosc"))
    kinds = collections.Counter(file_kind(path) for path in files)
    loaded: list[Path] = []
    failures: dict[str, str] = {}
    unsupported: dict[str, set[str]] = collections.defaultdict(set)
    runs = 0
    for path in files:
        kind = file_kind(path)
        if kind is FileKind.CATALOG:
            continue
        try:
            if kind is FileKind.DISTRIBUTION:
                for run in expand_distribution(path):
                    load_scenario(run.scenario, overrides=run.overrides)
                    runs += 1
            else:
                scenario = load_scenario(path)
                for node in scenario.unsupported():
                    unsupported[node.element].add(path.name)
            loaded.append(path)
        except ScenarioError as exc:
            failures[str(path.relative_to(corpus_dir))] = str(exc)

    table = "\n".join(f"{name:55} {reason}" for name, reason in sorted(failures.items()))
    print(f"\n{len(loaded)} loaded, {len(failures)} failed, kinds {dict(kinds)}\n{table}")
    print("unsupported:", {k: sorted(v) for k, v in sorted(unsupported.items())})

    assert kinds == {FileKind.SCENARIO: 71, FileKind.CATALOG: 11, FileKind.DISTRIBUTION: 1}
    reference = _reference(corpus_dir)
    esmini_ran = {key for key, rc in reference.items() if rc == 0}
    failed_keys = {f"esmini/{name.removeprefix('esmini/')}" for name in failures}
    assert not failed_keys & esmini_ran, f"esmini ran these but we cannot load them:\n{table}"
    assert failed_keys == {
        "esmini/resources/xosc/auto_light.xosc",
        "esmini/resources/xosc/car_walk.xosc",
    }, table
    assert (
        "no Vehicle/Pedestrian/MiscObject entry" in failures["esmini/resources/xosc/car_walk.xosc"]
    )
    assert len(loaded) == 70  # 69 scenarios + the distribution file
    assert runs == 12
    assert set(unsupported) == set(EXPECTED_UNSUPPORTED)
    for element, example in EXPECTED_UNSUPPORTED.items():
        assert example in unsupported[element]
