"""Every example manifest in the repository validates (examples are executable documentation)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from simtest_operator.api import v1alpha1

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = sorted([*REPO.glob("scenarios/*-campaign.yaml"), *REPO.glob("deploy/examples/*.yaml")])


def test_examples_exist() -> None:
    names = {path.name for path in EXAMPLES}
    assert {"smoke-campaign.yaml", "seed-experiment-campaign.yaml"} <= names


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_example_validates(path: Path) -> None:
    for document in yaml.safe_load_all(path.read_text(encoding="utf-8")):
        if document and document.get("apiVersion") == v1alpha1.API_VERSION:
            v1alpha1.parse(document, source=str(path))


def test_seed_experiment_matches_the_paper() -> None:
    document = yaml.safe_load((REPO / "scenarios/seed-experiment-campaign.yaml").read_text())
    execution = v1alpha1.parse_campaign(document).spec.execution
    assert (execution.batch_size, execution.max_simulators_per_node) == (9, 3)
    assert execution.timeout_seconds == 35
