"""api.converting: wire specs (as parsed from a manifest) to the domain values the runner uses.

Covers: every source kind and the selection fields, execution policy (window and barrier),
criteria with glob-matched overrides applied in order (last wins, unset fields untouched), the
SUT driver model, simulator settings, and frozen-list entries to and from the wire model.
"""

from __future__ import annotations

from typing import Any

import pytest

from simtest_operator.api import converting, v1alpha1
from simtest_operator.api.v1alpha1 import environment
from simtest_operator.evaluation import DEFAULT_TIME_LIMIT
from simtest_operator.scenarios import (
    ConfigMapSource,
    GitSource,
    GraphqlSource,
    HttpSource,
    PathSource,
    PinnedScenario,
    RestSource,
    SecretRef,
    StartPolicy,
)


def spec(**fields: Any) -> v1alpha1.TestCampaignSpec:
    base: dict[str, Any] = {"scenarios": {"sources": [{"path": "s"}]}}
    base.update(fields)
    return v1alpha1.TestCampaignSpec.model_validate(base)


def test_selection_and_sources() -> None:
    parsed = spec(scenarios={
        "sources": [
            {"path": "suite"},
            {"git": {"url": "https://h/r.git", "revision": "v1", "path": "x"}},
            {"http": {"url": "https://h/a.tgz", "sha256": "a" * 64}},
            {"graphql": {"endpoint": "https://h/g", "query": "{s}", "variables": {"c": "x"},
                         "secretRef": {"name": "db", "key": "token"}}},
            {"configMap": {"name": "cm", "keys": ["a.xosc"]}},
            {"rest": {"url": "https://h/api?x=1", "secretRef": {"name": "db", "key": "t"}}},
            {"rest": {"url": "http://h/plain"}},
        ],
        "include": ["cut-in/*.xosc"], "exclude": ["**/wip/*"],
        "selector": {"matchTags": ["day"], "matchLabels": {"category": "cut-in"}},
        "overrides": {"EgoSpeed": "30"},
    })  # fmt: skip
    selection = converting.selection(parsed.scenarios)
    assert selection.sources == (
        PathSource(path="suite"),
        GitSource(url="https://h/r.git", revision="v1", path="x"),
        HttpSource(url="https://h/a.tgz", sha256="a" * 64),
        GraphqlSource(endpoint="https://h/g", query="{s}", variables={"c": "x"},
                      secret=SecretRef(name="db", key="token")),
        ConfigMapSource(name="cm", keys=("a.xosc",)),
        RestSource(url="https://h/api?x=1", secret=SecretRef(name="db", key="t")),
        RestSource(url="http://h/plain"),
    )  # fmt: skip
    assert (selection.include, selection.exclude) == (("cut-in/*.xosc",), ("**/wip/*",))
    assert selection.selector.tags == ("day",)
    assert selection.selector.labels == {"category": "cut-in"}
    assert selection.overrides == {"EgoSpeed": "30"}
    plain = converting.selection(spec().scenarios)
    assert plain.include == ("**/*.xosc",) and plain.selector.empty


def test_execution_policy() -> None:
    window = converting.execution(spec(execution={"batchSize": 9, "timeoutSeconds": 35}).execution)
    assert (window.batch_size, window.policy, window.timeout_seconds, window.retries) == (
        9, StartPolicy.WINDOW, 35.0, 2,
    )  # fmt: skip
    barrier = converting.execution(
        spec(execution={"batchBarrier": True, "maxParallel": 20, "retries": 0}).execution
    )
    assert (barrier.policy, barrier.max_parallel, barrier.retries) == (StartPolicy.BARRIER, 20, 0)


def test_criteria_overrides_in_order() -> None:
    evaluation = spec(evaluation={
        "criteria": {"collision": "Forbidden", "minTtc": 1.5, "minThw": 0.5},
        "overrides": [
            {"scenarios": "hard-braking/*", "criteria": {"maxDeceleration": 10.0}},
            {"scenarios": "hard-braking/x*", "criteria": {"maxDeceleration": 12.0,
                                                          "collision": "Allowed"}},
            {"scenarios": "cut-in/**", "criteria": {"minTtc": 1.0, "completeWithin": 30}},
        ],
    }).evaluation  # fmt: skip
    base = converting.criteria(evaluation, "following/a.xosc")
    assert (base.collision, base.min_ttc, base.min_thw, base.max_decel, base.time_limit) == (
        True, 1.5, 0.5, None, DEFAULT_TIME_LIMIT,
    )  # fmt: skip
    hard = converting.criteria(evaluation, "hard-braking/x1.xosc")
    assert (hard.max_decel, hard.collision, hard.min_ttc) == (12.0, False, 1.5)
    assert converting.criteria(evaluation, "hard-braking/a.xosc").max_decel == 10.0
    cut = converting.criteria(evaluation, "cut-in/deep/c.xosc#1-abcd")
    assert (cut.min_ttc, cut.time_limit, cut.min_thw) == (1.0, 30.0, 0.5)


def test_sut_simulation_and_pins() -> None:
    environment = spec(environment={
        "sut": {"name": "acc", "version": "2.0", "driverModel": {
            "desiredSpeed": 30, "timeHeadway": 2.0, "acc": False, "trafficSignals": False,
            "aeb": {"enabled": False, "ttcThreshold": 2.5, "deceleration": 6}}},
        "simulator": {"stepLength": 0.1, "seed": 7, "recordHz": 20},
    }).environment  # fmt: skip
    sut = converting.sut(environment.sut)
    assert (sut.name, sut.version, sut.desired_speed, sut.time_headway, sut.acc) == (
        "acc", "2.0", 30.0, 2.0, False,
    )  # fmt: skip
    assert (sut.aeb, sut.aeb_ttc_threshold, sut.aeb_deceleration) == (False, 2.5, 6.0)
    assert sut.traffic_signals is False
    assert converting.sut(type(environment.sut).model_validate({})).traffic_signals is True
    simulation = converting.simulation(environment.simulator)
    assert (simulation.step_length, simulation.seed, simulation.record_hz) == (0.1, 7, 20.0)
    pinned = PinnedScenario(id="a#1", source="file:///a", sha256="b" * 64, overrides={"x": "1"})
    wire = converting.pinned_to_wire(pinned)
    assert wire.to_wire() == pinned.to_json()
    assert converting.pinned_from_wire(wire) == pinned


@pytest.mark.parametrize(
    ("wire", "domain"),
    [("OnController", "onController"), ("AfterInit", "afterInit"), ("Never", "never")],
)
def test_sut_takeover_and_ego_reach_the_driver_model(wire: str, domain: str) -> None:
    spec = environment.SutConfig.model_validate({"ego": "Hero", "takeover": wire})
    sut = converting.sut(spec)
    assert (sut.ego, sut.takeover.value) == ("Hero", domain)
