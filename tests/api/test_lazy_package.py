"""``api.v1alpha1`` loads its models on first use, and builds their validators on first use.

Covers: every name in ``v1alpha1.__all__`` resolves to the object of the module it is listed
under; importing the package loads none of its modules, and the three wire models the simulator
pod validates load only their own modules (not the kinds, manifests or status); an unknown name
is an AttributeError; a model's validator is built when the model is first used, and it then
validates as before (camelCase, unknown fields rejected).
"""

from __future__ import annotations

import importlib
import json
import subprocess
import sys

import pydantic
import pytest

from simtest_operator.api import v1alpha1


def test_every_public_name_resolves_to_its_module() -> None:
    for name in v1alpha1.__all__:
        module = importlib.import_module(f"simtest_operator.api.v1alpha1.{v1alpha1._MODULES[name]}")
        assert getattr(v1alpha1, name) is getattr(module, name)
    assert set(v1alpha1.__all__) == set(v1alpha1._MODULES)


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'Campaign'"):
        _ = v1alpha1.Campaign


def _api_state(body: str) -> dict[str, object]:
    code = (
        f"import json, sys\n{body}\n"
        "from simtest_operator.api.v1alpha1.common import ApiModel\n"
        "built = sorted(c.__name__ for c in ApiModel.__subclasses__() if c.__pydantic_complete__)\n"
        "modules = sorted(m for m in sys.modules if m.startswith('simtest_operator.api.'))\n"
        "print(json.dumps({'modules': modules, 'built': built}))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    state: dict[str, object] = json.loads(done.stdout)
    return state


def test_the_pod_s_wire_models_load_only_their_modules() -> None:
    assert _api_state("import simtest_operator.api.v1alpha1")["modules"] == [
        "simtest_operator.api.v1alpha1",
        "simtest_operator.api.v1alpha1.common",  # the probe's own import
    ]
    state = _api_state(
        "from simtest_operator.api.v1alpha1 import EvaluationSpec, SimulatorSettings, SutConfig"
    )
    assert state["modules"] == [
        "simtest_operator.api.v1alpha1",
        "simtest_operator.api.v1alpha1.common",
        "simtest_operator.api.v1alpha1.environment",
        "simtest_operator.api.v1alpha1.evaluation",
    ]


def test_validators_are_built_on_first_use() -> None:
    state = _api_state(
        "from simtest_operator.api.v1alpha1 import EvaluationSpec, SutConfig\n"
        "SutConfig.model_validate({'name': 'lead-sut'})"
    )
    built = state["built"]
    assert isinstance(built, list)
    assert "SutConfig" in built
    assert "EvaluationSpec" not in built


def test_a_deferred_model_validates_as_before() -> None:
    sut = v1alpha1.SutConfig.model_validate({"name": "lead-sut", "version": "1.2"})
    assert (sut.name, sut.version) == ("lead-sut", "1.2")
    assert sut.to_wire()["name"] == "lead-sut"
    with pytest.raises(pydantic.ValidationError, match="Extra inputs"):
        v1alpha1.SutConfig.model_validate({"name": "lead-sut", "drivrModel": {}})
    with pytest.raises(pydantic.ValidationError, match="pattern"):
        v1alpha1.SutConfig.model_validate({"name": "Not_A_Label"})
