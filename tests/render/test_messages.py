"""The termination-message codec and the run spec.

Covers: single and multi-scenario round trips; a missing scenarioId filled from the default;
garbage is a MessageError; oversized outcomes shrink below 4096 bytes keeping id, verdict and the
key metrics; hundreds of scenarios still fit; run spec round trip and malformed run specs.
"""

from __future__ import annotations

import pytest

from simtest_operator.errors import RenderError
from simtest_operator.render import RunSpec, ScenarioRef, messages
from simtest_operator.verdicts import ScenarioOutcome, Verdict


def outcome(i: int = 0, **changes: object) -> ScenarioOutcome:
    base = {
        "scenario_id": f"suite/s{i}.xosc",
        "verdict": Verdict.FAILED,
        "reason": "minTTC 0.90 s < 1.50 s at t=12.3 s against car1",
        "metrics": {"minTTC": 0.9, "minTHW": 0.7, "maxDecel": 6.5},
        "simulated_seconds": 20.0,
        "wall_seconds": 1.25,
        "artifacts": {"recording": "pvc://a/b/recording.mcap", "result": "pvc://a/b/result.json"},
        "versions": {"simtest": "0.1.0"},
    }
    base.update(changes)
    return ScenarioOutcome(**base)  # type: ignore[arg-type]


def test_single_outcome_round_trip() -> None:
    text = messages.encode([outcome()])
    (back,) = messages.decode(text)
    assert back == outcome()


def test_several_outcomes_round_trip() -> None:
    items = [outcome(i) for i in range(3)]
    assert messages.decode(messages.encode(items)) == tuple(items)


def test_missing_id_and_garbage() -> None:
    (back,) = messages.decode('{"verdict": "Passed"}', default_id="x.xosc")
    assert back.scenario_id == "x.xosc" and back.verdict is Verdict.PASSED
    for bad in (
        "Traceback (most recent call last)",
        "[]",
        '{"reason": "x"}',
        '{"verdict": "Nope", "scenarioId": "a"}',
    ):
        with pytest.raises(messages.MessageError):
            messages.decode(bad)
    with pytest.raises(messages.MessageError):
        messages.decode('{"verdict": "Passed"}')


def test_large_outcome_shrinks_below_the_limit() -> None:
    big = outcome(
        reason="é" * 5000,
        metrics={f"m{i}": float(i) for i in range(300)} | {"minTTC": 0.9},
        artifacts={f"a{i}": "pvc://" + "x" * 100 for i in range(50)} | {"result": "pvc://r"},
        ignored_elements=tuple(f"Element{i}" for i in range(200)),
    )
    text = messages.encode([big])
    assert len(text.encode("utf-8")) <= messages.LIMIT_BYTES
    (back,) = messages.decode(text)
    assert back.scenario_id == big.scenario_id and back.verdict is Verdict.FAILED
    assert back.metrics["minTTC"] == 0.9
    assert back.artifacts == {"result": "pvc://r"}
    assert back.reason.startswith("éé") and back.reason.endswith("…")


def test_hundreds_of_scenarios_still_fit() -> None:
    text = messages.encode([outcome(i) for i in range(400)])
    assert len(text.encode("utf-8")) <= messages.LIMIT_BYTES
    decoded = messages.decode(text)
    assert decoded and all(o.verdict is Verdict.FAILED for o in decoded)


def test_run_spec_round_trip_and_errors() -> None:
    spec = RunSpec(
        campaign="c",
        environment="c-b00000-e000-a1",
        attempt=2,
        scenarios=(
            ScenarioRef(
                id="a.xosc", source="file:///a.xosc", sha256="0" * 64, overrides={"S": "1"}
            ),
        ),
        timeout_seconds=30,
        evaluation={"criteria": {"minTtc": 1.5}},
    )
    assert RunSpec.loads(spec.dumps()) == spec
    for bad in ("nope", "[]", '{"scenarios": []}', '{"version": 9, "scenarios": [{"id": 1}]}'):
        with pytest.raises(RenderError):
            RunSpec.loads(bad)
