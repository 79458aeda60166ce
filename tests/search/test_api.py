"""The search section's validation: pydantic validators and the CEL rules state the same rules."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from simtest_operator.api.v1alpha1 import SearchSpec, SearchStrategy
from simtest_operator.api.v1alpha1.search import DEFAULT_STRATEGY, SearchParameter


def spec(**changes: object) -> dict[str, object]:
    base: dict[str, object] = {
        "scenario": "cut-in.xosc",
        "parameters": [{"name": "EgoSpeed", "min": 15, "max": 35}],
        "budget": 100,
    }
    return base | changes


def test_defaults_and_camel_case() -> None:
    parsed = SearchSpec.model_validate(spec())
    assert parsed.strategy is DEFAULT_STRATEGY
    assert parsed.seed == 0
    assert [o.metric for o in parsed.objectives] == ["verdict"]
    assert parsed.to_wire()["parameters"] == [{"name": "EgoSpeed", "min": 15.0, "max": 35.0}]
    assert SearchStrategy("tpe") is SearchStrategy.TPE


@pytest.mark.parametrize(
    "parameter",
    [
        {"name": "A"},
        {"name": "A", "min": 1},
        {"name": "A", "min": 1, "max": 2, "choices": ["x"]},
        {"name": "A", "choices": ["x"], "step": 1},
        {"name": "A", "min": 2, "max": 1},
        {"name": "A", "min": 1, "max": 2, "step": 0},
        {"name": "A", "min": 1, "max": float("inf")},
        {"name": "A", "choices": []},
    ],
)
def test_a_parameter_is_a_range_or_choices(parameter: dict[str, object]) -> None:
    with pytest.raises(ValidationError):
        SearchParameter.model_validate(parameter)


@pytest.mark.parametrize(
    "changes",
    [
        {"budget": 0},
        {"budget": 100_001},
        {"strategy": "annealing"},
        {"objectives": []},
        {"objectives": [{"metric": "min TTC"}]},
        {"parameters": [{"name": "A", "min": 0, "max": 1}, {"name": "A", "choices": ["x"]}]},
        {"extra": 1},
    ],
)
def test_bad_specs_are_refused(changes: dict[str, object]) -> None:
    with pytest.raises(ValidationError):
        SearchSpec.model_validate(spec(**changes))


def test_cel_rules_name_the_same_constraints() -> None:
    rules = " ".join(r["rule"] for r in SearchParameter.cel_rules)
    assert "has(self.choices)" in rules and "self.min < self.max" in rules
    assert "self.step > 0.0" in rules
    assert "exists_one" in SearchSpec.cel_rules[0]["rule"]
