"""Leader election over a Lease: the pure decisions, two electors against an in-memory Lease API
with an explicit clock, and the runtime's gating of campaign loops.

Covers: free/own/foreign/expired leases (expiry by the candidate's own observation, not the
record's timestamps); the written record (acquire time kept on renewal, transitions counted on a
change of holder, release empties the holder); one leader at a time, a follower takes over only
after the lease duration once the leader stops renewing, and a race of two candidates has exactly
one winner (409 for the other); a partitioned leader steps down after the renew deadline, before
anybody may take over; a released lease is taken at once; settings are checked; a follower starts
no loops and becoming the leader starts one per cached campaign; the leader gauge.
"""

from __future__ import annotations

import asyncio
import copy
import datetime
import json
from typing import Any

import pytest

from simtest_operator.errors import ClusterError
from simtest_operator.operator import leadership
from simtest_operator.operator.client import AlreadyExistsError, ConflictError, NotFoundError
from simtest_operator.operator.metrics import Metrics
from simtest_operator.operator.runtime import Runtime

T0 = datetime.datetime(2030, 1, 1, tzinfo=datetime.UTC)
PATH = "/apis/coordination.k8s.io/v1/namespaces/ops/leases"


class LeaseApi:
    """The API server's Lease semantics: create once, update only at the current version."""

    def __init__(self) -> None:
        self.body: dict[str, Any] | None = None
        self.version = 0
        self.down: set[str] = set()
        """Identities whose requests fail (a network partition)."""

    def client(self, identity: str) -> Any:
        api = self

        class _Client:
            async def request(
                self, method: str, path: str, *, body: Any = None, kind: str = "", **_: Any
            ) -> dict[str, Any]:
                await asyncio.sleep(0)  # let concurrent candidates interleave
                if identity in api.down:
                    raise ClusterError("connection refused")
                return api.handle(method, path, body)

        return _Client()

    def handle(self, method: str, path: str, body: Any) -> dict[str, Any]:
        if method == "GET":
            assert path == f"{PATH}/operator"
            if self.body is None:
                raise NotFoundError(404, "NotFound", "no lease")
            return copy.deepcopy(self.body)
        if method == "POST":
            assert path == PATH
            if self.body is not None:
                raise AlreadyExistsError(409, "AlreadyExists", "exists")
        elif method == "PUT":
            assert self.body is not None and path == f"{PATH}/operator"
            if body["metadata"]["resourceVersion"] != self.body["metadata"]["resourceVersion"]:
                raise ConflictError(409, "Conflict", "stale")
        self.version += 1
        self.body = json.loads(json.dumps(body))
        self.body["metadata"]["resourceVersion"] = str(self.version)
        return copy.deepcopy(self.body)

    @property
    def holder(self) -> str:
        return str((self.body or {}).get("spec", {}).get("holderIdentity", ""))


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _elector(api: LeaseApi, identity: str, clock: Clock, log: list[str]) -> leadership.Elector:
    async def stopped() -> None:
        log.append(f"{identity} stopped")

    return leadership.Elector(
        api.client(identity),
        leadership.LeaseSettings(name="operator", namespace="ops", identity=identity),
        on_started=lambda: log.append(f"{identity} started"),
        on_stopped=stopped,
        clock=clock,
        wall=lambda: T0 + datetime.timedelta(seconds=clock.now),
    )


def _record(holder: str, duration: float = 15.0) -> leadership.LeaseRecord:
    return leadership.LeaseRecord(
        holder=holder,
        lease_duration=duration,
        acquire_time="a",
        renew_time="r",
        transitions=3,
        resource_version="7",
    )


def test_decide() -> None:
    decide = leadership.decide
    kw: dict[str, Any] = {"identity": "me", "observed_at": 100.0, "lease_duration": 15.0}
    assert decide(None, now=100.0, **kw) is leadership.Decision.ACQUIRE
    assert decide(_record(""), now=100.0, **kw) is leadership.Decision.ACQUIRE
    assert decide(_record("me"), now=100.0, **kw) is leadership.Decision.RENEW
    assert decide(_record("other"), now=114.9, **kw) is leadership.Decision.WAIT
    assert decide(_record("other"), now=115.0, **kw) is leadership.Decision.ACQUIRE
    assert decide(_record("other", 30.0), now=120.0, **kw) is leadership.Decision.WAIT


def test_lease_body() -> None:
    settings = leadership.LeaseSettings(name="operator", namespace="ops", identity="me")
    fresh = leadership.lease_body(None, settings, now=T0)
    assert fresh["spec"] == {
        "holderIdentity": "me",
        "leaseDurationSeconds": 15,
        "acquireTime": "2030-01-01T00:00:00.000000Z",
        "renewTime": "2030-01-01T00:00:00.000000Z",
        "leaseTransitions": 0,
    }
    assert "resourceVersion" not in fresh["metadata"]
    renewed = leadership.lease_body(_record("me"), settings, now=T0)
    assert renewed["spec"]["acquireTime"] == "a" and renewed["spec"]["leaseTransitions"] == 3
    assert renewed["metadata"]["resourceVersion"] == "7"
    taken = leadership.lease_body(_record("other"), settings, now=T0)
    assert taken["spec"]["acquireTime"] != "a" and taken["spec"]["leaseTransitions"] == 4
    released = leadership.lease_body(_record("me"), settings, now=T0, release=True)
    assert released["spec"]["holderIdentity"] == ""
    assert released["spec"]["leaseDurationSeconds"] == 1
    with pytest.raises(ValueError, match="retryPeriod < renewDeadline < leaseDuration"):
        leadership.LeaseSettings(name="x", namespace="y", identity="me", renew_deadline=20)
    with pytest.raises(ValueError, match="identity"):
        leadership.LeaseSettings(name="x", namespace="y", identity="")


def test_one_leader_and_takeover_after_the_lease_duration() -> None:
    async def scenario() -> None:
        api, clock, log = LeaseApi(), Clock(), []
        a, b = _elector(api, "a", clock, log), _elector(api, "b", clock, log)
        await a.step()
        await b.step()
        assert (a.leading, b.leading, api.holder) == (True, False, "a")
        for _ in range(10):  # a renews every 2 s; b keeps following
            clock.now += 2
            await a.step()
            await b.step()
            assert (a.leading, b.leading) == (True, False)
        died = clock.now  # a stops renewing (killed)
        while not b.leading:
            clock.now += 2
            await b.step()
        assert 15 <= clock.now - died <= 17
        assert api.holder == "b" and api.body is not None
        assert api.body["spec"]["leaseTransitions"] == 1
        assert log == ["a started", "b started"]

    asyncio.run(scenario())


def test_race_of_two_candidates_has_one_winner() -> None:
    async def scenario() -> None:
        api, clock, log = LeaseApi(), Clock(), []
        api.handle("POST", PATH, leadership.lease_body(None, _settings("gone"), now=T0))
        a, b = _elector(api, "a", clock, log), _elector(api, "b", clock, log)
        await a.step()
        await b.step()
        clock.now += 16  # both see the lease as expired, read the same version, and write
        conflicts = api.version
        await asyncio.gather(a.step(), b.step())
        assert [a.leading, b.leading].count(True) == 1
        assert api.version == conflicts + 1  # the loser's update was refused (409)
        assert api.holder in ("a", "b")

    asyncio.run(scenario())


def _settings(identity: str) -> leadership.LeaseSettings:
    return leadership.LeaseSettings(name="operator", namespace="ops", identity=identity)


def test_partitioned_leader_steps_down_before_anyone_takes_over() -> None:
    async def scenario() -> None:
        api, clock, log = LeaseApi(), Clock(), []
        a, b = _elector(api, "a", clock, log), _elector(api, "b", clock, log)
        await a.step()
        await b.step()
        api.down.add("a")
        stopped_at = None
        while not b.leading:
            clock.now += 1
            await a.step()
            if not a.leading and stopped_at is None:
                stopped_at = clock.now
            await b.step()
        assert stopped_at is not None and stopped_at <= 10 < clock.now
        assert log == ["a started", "a stopped", "b started"]

    asyncio.run(scenario())


def test_released_lease_is_taken_at_once() -> None:
    async def scenario() -> None:
        api, clock, log = LeaseApi(), Clock(), []
        a, b = _elector(api, "a", clock, log), _elector(api, "b", clock, log)
        await a.step()
        await b.step()
        await a.release()
        assert api.holder == "" and not a.leading
        clock.now += 2
        await b.step()
        assert b.leading and api.holder == "b"

    asyncio.run(scenario())


class _Loops:
    def __init__(self) -> None:
        self.loops: dict[tuple[str, str], Any] = {}
        self.closed = 0

    def ensure(self, key: tuple[str, str]) -> None:
        self.loops[key] = object()

    async def close(self) -> None:
        self.closed += 1
        self.loops.clear()


class _Cache:
    def __init__(self, keys: list[tuple[str, str]]) -> None:
        self.campaigns = dict.fromkeys(keys, ())

    def campaign(self, key: tuple[str, str]) -> Any:
        class View:
            deleting = key[1] == "going"

        return View()


def test_runtime_runs_loops_only_while_leading() -> None:
    async def scenario() -> None:
        api, clock, log = LeaseApi(), Clock(), []
        metrics = Metrics()
        loops = _Loops()
        runtime = Runtime(
            config=None,  # type: ignore[arg-type]
            client=None,  # type: ignore[arg-type]
            metrics=metrics,
            loops=loops,  # type: ignore[arg-type]
            cache=_Cache([("ns", "one"), ("ns", "two"), ("ns", "going")]),  # type: ignore[arg-type]
        )
        runtime.elector = _elector(api, "me", clock, log)
        api.handle("POST", PATH, leadership.lease_body(None, _settings("other"), now=T0))
        await runtime.elector.step()
        runtime.ensure(("ns", "one"))
        assert not loops.loops and not runtime.leading
        runtime.started_leading()
        assert set(loops.loops) == {("ns", "one"), ("ns", "two")}
        assert b"simtest_operator_leader 1.0" in metrics.exposition()
        await runtime.stopped_leading()
        assert loops.closed == 1 and not loops.loops
        assert b"simtest_operator_leader 0.0" in metrics.exposition()

    asyncio.run(scenario())
