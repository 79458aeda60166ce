"""spec.environment.sut.external: exactly one way to reach the SUT (image, endpoint or a
command), bounded fields, one-line errors; the CRD carries the same rules as CEL."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml
from pydantic import ValidationError

from simtest_operator.api import converting
from simtest_operator.api.v1alpha1 import environment, kinds
from simtest_operator.drivermodel import Launch

CRD = Path(__file__).resolve().parents[2] / "crds" / "simtest.dev_testcampaigns.yaml"


def sut(external: dict[str, Any]) -> environment.SutConfig:
    return environment.SutConfig.model_validate({"name": "acme", "external": external})


@pytest.mark.parametrize(
    ("external", "message"),
    [
        ({}, "needs an image, an endpoint or a command"),
        ({"image": "a:1", "endpoint": "h:1"}, "not both"),
        ({"endpoint": "no-port"}, "pattern"),
        ({"command": ["x"], "stepDeadlineMilliseconds": 0}, "greater than or equal to 1"),
        ({"command": ["x"], "env": {"1BAD": "v"}}, "env names must match"),
        ({"command": ["x"], "port": 80}, "greater than or equal to 1024"),
        ({"command": ["x"], "unknown": 1}, "Extra inputs"),
    ],
)
def test_bad_external_suts_are_refused(external: dict[str, Any], message: str) -> None:
    with pytest.raises(ValidationError, match=message):
        sut(external)


@pytest.mark.parametrize(
    ("external", "launch"),
    [
        ({"image": "ghcr.io/acme/sut:1"}, Launch.SIDECAR),
        ({"endpoint": "sut.acme.svc:7460"}, Launch.ENDPOINT),
        ({"command": ["{python}", "-m", "simtest_operator.sut.reference"]}, Launch.LOCAL),
    ],
)
def test_each_way_converts_to_its_launch(external: dict[str, Any], launch: Launch) -> None:
    domain = converting.sut(sut(external)).external
    assert domain is not None
    assert domain.launch is launch
    assert domain.step_deadline == pytest.approx(0.1)  # the 100 ms default


def test_in_process_stays_the_default() -> None:
    assert converting.sut(environment.SutConfig()).external is None


def test_the_crd_has_the_cel_rules_of_external() -> None:
    assert kinds.TEST_CAMPAIGN.kind == "TestCampaign"
    crd = yaml.safe_load(CRD.read_text(encoding="utf-8"))
    schema = crd["spec"]["versions"][0]["schema"]["openAPIV3Schema"]
    node = schema["properties"]["spec"]["properties"]["environment"]["properties"]["sut"]
    rules = node["properties"]["external"]["x-kubernetes-validations"]
    assert {rule["message"] for rule in rules} == {
        "set image (sidecar) or endpoint, not both",
        "an external SUT needs an image, an endpoint or a command",
    }
