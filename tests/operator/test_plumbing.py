"""The operator's small pure pieces.

Covers: expectations (present/absent/version, deadline); cache lookups by campaign; the frozen
list ConfigMap round trip, determinism and size limit; environment names parse back; operator
configuration from variables and flags; conditions keep their transition time while unchanged;
API error mapping; the applier reports creates refused for good; campaign phases for an invalid
spec, a resolution error and an empty list; counter-only campaign status writes are coalesced.
"""

from __future__ import annotations

import asyncio
import datetime
import hashlib
import itertools
import json
from typing import Any, cast

import pytest

from simtest_operator.errors import SourceError
from simtest_operator.operator import (
    client,
    names,
    observed,
    planning,
    resolving,
    scenariolists,
)
from simtest_operator.operator.actions import Create, Emit, Kind, PatchStatus, Plan
from simtest_operator.operator.applying import Applier
from simtest_operator.operator.caching import ALL_NODES, Cache
from simtest_operator.operator.expectations import Expectation, Expectations, Want
from simtest_operator.operator.metrics import Metrics
from simtest_operator.operator.status import conditions
from simtest_operator.scenarios import FrozenList, PinnedScenario
from simtest_operator.settings import InputSettings, OperatorSettings, PacingSettings, Settings
from tests.operator.fakecluster import REPO, T0, FakeCluster, campaign_body, frozen_list


def test_expectations_wait_for_the_cache() -> None:
    seen: dict[tuple[Kind, str], tuple[bool, str, bool]] = {}
    pending = Expectations(timeout=5)
    pending.expect(
        [
            Expectation(kind=Kind.ENVIRONMENT, name="e", want=Want.PRESENT),
            Expectation(kind=Kind.POD, name="p", want=Want.ABSENT),
            Expectation(kind=Kind.BATCH, name="b", want=Want.VERSION, version="10"),
        ],
        now=T0,
    )
    seen[(Kind.POD, "p")] = (True, "3", False)
    seen[(Kind.BATCH, "b")] = (True, "9", False)
    lookup = lambda kind, name: seen.get((kind, name))  # noqa: E731
    assert not pending.satisfied(lookup, now=T0)
    seen[(Kind.ENVIRONMENT, "e")] = (True, "1", False)
    seen[(Kind.POD, "p")] = (True, "4", True)  # deleting counts as gone
    seen[(Kind.BATCH, "b")] = (True, "11", False)  # a later write counts too
    assert pending.satisfied(lookup, now=T0)
    pending.expect([Expectation(kind=Kind.POD, name="never", want=Want.PRESENT)], now=T0)
    assert not pending.satisfied(lookup, now=T0 + datetime.timedelta(seconds=4))
    assert pending.satisfied(lookup, now=T0 + datetime.timedelta(seconds=5))


def test_cache_groups_by_campaign() -> None:
    cluster = FakeCluster()
    cluster.start_campaign(campaign_body(), frozen_list(3), batch_size=3)
    cluster.step()
    envs = [observed.environment_view(e) for e in cluster.of(Kind.ENVIRONMENT)]
    node = observed.node_view(
        {"metadata": {"name": "n"}, "status": {"allocatable": {"simtest.dev/simulator": "2"}}}
    )
    cache = Cache(
        campaigns={},
        batches={},
        environments={("tests", "camp"): envs},
        pods={},
        nodes={ALL_NODES: [node]},
    )
    assert cache.environments_of(("tests", "camp")) == envs
    assert cache.lookup(("tests", "camp"), Kind.ENVIRONMENT, envs[0].name) == (
        True,
        envs[0].resource_version,
        False,
    )
    assert cache.lookup(("tests", "camp"), Kind.POD, "x") is None
    assert cache.node_map() == {"n": node} and node.slots == 2


def test_frozen_list_config_map_round_trip() -> None:
    stored = scenariolists.StoredList(frozen=frozen_list(500), batch_size=7)
    owner = {"uid": "u"}
    body = scenariolists.config_map(stored, namespace="ns", campaign="c", owner=owner)
    assert body == scenariolists.config_map(stored, namespace="ns", campaign="c", owner=owner)
    assert body["immutable"] is True and body["data"]["count"] == "500"
    assert scenariolists.config_maps(stored, namespace="ns", campaign="c", owner=owner) == [body]
    assert scenariolists.read(json.loads(json.dumps(body))) == stored
    with pytest.raises(SourceError, match="not a frozen scenario list"):
        scenariolists.read({"metadata": {"name": "x"}, "binaryData": {}})


def test_a_long_frozen_list_is_cut_into_chunks_below_the_object_limit(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    huge = FrozenList(
        campaign="c",
        scenarios=tuple(
            PinnedScenario(
                id=hashlib.sha512(b"id%d" % i).hexdigest() * 2,
                source="https://h/" + hashlib.sha512(b"src%d" % i).hexdigest(),
                sha256=hashlib.sha256(b"%d" % i).hexdigest(),
            )
            for i in range(8000)
        ),
    )
    stored = scenariolists.StoredList(frozen=huge, batch_size=10)
    bodies = scenariolists.config_maps(stored, namespace="n", campaign="c", owner={})
    *chunks, head = bodies
    assert len(chunks) >= 1 and head["metadata"]["name"] == "c-scenarios"  # the head last
    assert scenariolists.chunk_names(head) == tuple(c["metadata"]["name"] for c in chunks)
    for body in bodies:
        assert len(json.dumps(body)) < scenariolists.MAX_BYTES + 4096  # the object, as sent
    assert scenariolists.read(head, chunks) == stored
    assert head["data"]["count"] == "8000"
    with pytest.raises(SourceError, match="chunks named"):
        scenariolists.read(head, chunks[1:])
    monkeypatch.setattr(scenariolists, "MAX_CHUNKS", 1)
    with pytest.raises(SourceError, match="split the campaign"):
        scenariolists.config_maps(stored, namespace="n", campaign="c", owner={})


class _ConfigMaps:
    """A client that serves GETs of a few ConfigMaps."""

    def __init__(self, bodies: list[dict[str, Any]]) -> None:
        self.bodies = {b["metadata"]["name"]: b for b in bodies}

    async def get(self, kind: Kind | str, namespace: str | None, name: str) -> dict[str, Any]:
        if name not in self.bodies:
            raise client.NotFoundError(404, "NotFound", name)
        return self.bodies[name]


def test_a_restarted_operator_loads_a_chunked_list(monkeypatch: pytest.MonkeyPatch) -> None:
    stored = scenariolists.StoredList(frozen=frozen_list(500), batch_size=7)
    bodies = scenariolists.config_maps(stored, namespace="tests", campaign="camp", owner={})
    monkeypatch.setattr(scenariolists, "MAX_BYTES", 1024)  # 500 entries then need chunks
    chunked = scenariolists.config_maps(stored, namespace="tests", campaign="camp", owner={})
    assert len(bodies) == 1 and len(chunked) > 1
    campaign = observed.campaign_view(
        {**campaign_body(), "metadata": {"name": "camp", "namespace": "tests"}}
    )
    for served in (bodies, chunked):
        fake = cast(client.Client, _ConfigMaps(served))
        assert asyncio.run(resolving.load(fake, campaign)) == stored
    assert asyncio.run(resolving.load(cast(client.Client, _ConfigMaps([])), campaign)) is None


def test_names() -> None:
    name = names.environment("c", 42, 7, 3)
    assert name == "c-b00042-e007-a3"
    parsed = names.parse_environment(name)
    assert parsed is not None and (
        parsed.batch,
        parsed.batch_index,
        parsed.first,
        parsed.attempt,
    ) == ("c-b00042", 42, 7, 3)
    assert names.parse_environment("something-else") is None
    assert len(names.environment("x" * 50, 99999, 999, 9)) <= 253
    wide = names.parse_environment(names.environment("c", 123_456, 0, 1))
    assert wide is not None and (wide.batch, wide.batch_index) == ("c-b123456", 123_456)
    longest = names.environment_labels("x" * 50, names.batch("x" * 50, 9_999_999), 9)
    assert all(len(value) <= 63 for value in longest.values())  # label values


def test_configuration_from_variables_and_flags(tmp_path: object) -> None:
    config = Settings.from_env(
        {
            "SIMTEST_OPERATOR_STATUS_INTERVAL": "2.5",
            "SIMTEST_OPERATOR_KEEP_ENVIRONMENTS": "true",
            "SIMTEST_OPERATOR_SCENARIO_CLAIM": "scen",
            "SIMTEST_OPERATOR_METRICS_PORT": "9000",
        },
        operator_flags={"metrics_port": 0, "inputs.templates_dir": None},
    ).operator
    assert config.pacing.status_interval == 2.5 and config.keep_finished_environments
    assert config.inputs.scenario_claim == "scen"
    assert config.metrics_port == 0
    assert str(config.inputs.templates_dir) == "helm-templates"


def test_conditions_keep_transition_time() -> None:
    first = conditions.merge(
        None, [conditions.Desired(type="Complete", status=False, reason="InProgress")], now=T0
    )
    later = T0 + datetime.timedelta(minutes=1)
    same = conditions.merge(
        first,
        [conditions.Desired(type="Complete", status=False, reason="InProgress", message="x")],
        now=later,
    )
    assert same[0]["lastTransitionTime"] == first[0]["lastTransitionTime"]
    flipped = conditions.merge(
        same, [conditions.Desired(type="Complete", status=True, reason="Succeeded")], now=later
    )
    assert flipped[0]["lastTransitionTime"] == conditions.rfc3339(later)


@pytest.mark.parametrize(
    ("status", "reason", "expected"),
    [
        (404, "NotFound", client.NotFoundError),
        (409, "AlreadyExists", client.AlreadyExistsError),
        (409, "Conflict", client.ConflictError),
        (422, "Invalid", client.ApiError),
    ],
)
def test_api_errors_are_mapped(status: int, reason: str, expected: type[Exception]) -> None:
    error = client._error(status, json.dumps({"reason": reason, "message": "m"}))
    assert type(error) is expected and error.status == status


class _Answering:
    """An API client that creates what it has no answer for, and raises the answer otherwise."""

    def __init__(self, answers: dict[str, client.ApiError]) -> None:
        self.answers = answers

    async def create(self, kind: Kind, namespace: str, body: dict[str, Any]) -> dict[str, Any]:
        answer = self.answers.get(body["metadata"]["name"])
        if answer is not None:
            raise answer
        return body


def test_the_applier_reports_creates_refused_for_good() -> None:
    """400/403/422 come back by kind and name with the server's words, for the planner to word
    (the evaluation Job); a transient answer is only a failure, an existing object is done."""
    answers = {
        "forbidden": client.ApiError(403, "Forbidden", "jobs.batch is forbidden"),
        "invalid": client.ApiError(422, "Invalid", "spec.template: Required value"),
        "busy": client.ApiError(503, "ServiceUnavailable", "try again"),
        "there": client.AlreadyExistsError(409, "AlreadyExists", "exists"),
    }
    applier = Applier(
        client=cast(client.Client, _Answering(answers)),
        namespace="tests",
        campaign="camp",
        campaign_uid=lambda: "u",
        metrics=Metrics(),
        event_interval=10.0,
    )
    creates = tuple(
        Create(kind=Kind.JOB, body={"metadata": {"name": name}}) for name in [*answers, "new"]
    )
    applied = asyncio.run(applier.apply(Plan(actions=creates), now=T0))
    assert applied.refused == {
        (Kind.JOB, "forbidden"): "403 Forbidden: jobs.batch is forbidden",
        (Kind.JOB, "invalid"): "422 Invalid: spec.template: Required value",
    }
    assert applied.failures == 3
    assert {e.name for e in applied.expectations} == {"there", "new"}


def _halted(body: dict[str, object], **inputs: object) -> Plan:
    view = observed.campaign_view(body)
    return planning.plan(
        planning.Inputs(campaign=view, now=T0, **inputs),  # type: ignore[arg-type]
        config=OperatorSettings(inputs=InputSettings(templates_dir=REPO / "helm-templates")),
        render=lambda request: pytest.fail("nothing may render"),  # type: ignore[arg-type,return-value]
    )


def test_invalid_spec_resolution_error_and_resolving() -> None:
    bad = campaign_body()
    bad["spec"]["execution"] = {"batchSize": 0}  # type: ignore[index]
    plan = _halted(bad, stored=None)
    patch = next(a for a in plan.actions if isinstance(a, PatchStatus)).patch
    assert patch["phase"] == "Error" and "batchSize" in json.dumps(patch["conditions"])
    assert any(isinstance(a, Emit) and a.terminal for a in plan.actions)
    plan = _halted(campaign_body(), stored=None, resolution_error="git: no such revision")
    patch = next(a for a in plan.actions if isinstance(a, PatchStatus)).patch
    resolved = conditions.get(patch["conditions"], "Resolved")
    assert (
        patch["phase"] == "Error"
        and resolved is not None
        and resolved["reason"] == "ResolutionFailed"
    )
    plan = _halted(campaign_body(), stored=None)
    assert next(a for a in plan.actions if isinstance(a, PatchStatus)).patch["phase"] == "Resolving"


def test_empty_selection_is_an_error() -> None:
    cluster = FakeCluster()
    cluster.start_campaign(campaign_body(), frozen_list(0), batch_size=5)
    cluster.step()
    status = cluster.status()
    assert status["phase"] == "Error" and status["total"] == 0
    assert conditions.get(status["conditions"], "Complete")["status"] == "True"  # type: ignore[index]


def test_counter_only_status_writes_are_coalesced() -> None:
    cluster = FakeCluster(
        config=OperatorSettings(
            inputs=InputSettings(templates_dir=REPO / "helm-templates"),
            pacing=PacingSettings(status_interval=10.0),
        )
    )
    cluster.start_campaign(
        campaign_body(batchSize=10, maxParallel=1), frozen_list(4), batch_size=10
    )
    writes = []
    for _ in range(80):
        before = cluster.status().get("progress")
        cluster.step(0.5)
        if cluster.status().get("progress") != before:
            writes.append(cluster.now)
    assert cluster.status()["phase"] == "Succeeded"
    gaps = [(b - a).total_seconds() for a, b in itertools.pairwise(writes)]
    assert all(gap >= 10.0 for gap in gaps[:-1]), gaps  # the final (phase) write is immediate
