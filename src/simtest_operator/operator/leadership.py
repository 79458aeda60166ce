"""Leader election over a ``coordination.k8s.io/v1`` Lease: several replicas, one acting.

Every replica watches and keeps its caches warm (so it is ready, and a takeover costs no relist);
only the holder of the Lease runs campaign loops. The protocol is client-go's
``tools/leaderelection``:

* a candidate takes the Lease when it is free or when its record has not changed for
  ``leaseDurationSeconds`` *as seen by the candidate's own clock* — clocks of different machines
  are never compared;
* the holder renews it every ``retryPeriod`` and stops leading when it could not renew for
  ``renewDeadline`` (shorter than the lease duration), so it has stopped acting before anybody
  else may take over;
* writes are optimistic: an update carries the ``resourceVersion`` it read, so of two candidates
  exactly one wins and the other gets ``409 Conflict``;
* a holder that shuts down cleanly releases the Lease (empty holder), so a rolling update hands
  over at once instead of after the lease duration.

Takeover after a crash is safe because the operator keeps no state of its own: the new leader
re-derives every campaign from its child objects (DESIGN §4, Restarts).

:func:`decide` and :func:`lease_body` are pure; :class:`Elector` is the asyncio task around them.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import datetime
import enum
import logging
import os
import socket
import time
from collections.abc import Awaitable, Callable, Mapping
from typing import Any

from simtest_operator.errors import ClusterError
from simtest_operator.operator.client import (
    AlreadyExistsError,
    Client,
    ConflictError,
    NotFoundError,
)

log = logging.getLogger(__name__)

API = "/apis/coordination.k8s.io/v1"


def default_identity() -> str:
    """``<hostname>_<pid>``: unique per process (in a pod the hostname is the pod name)."""
    return f"{socket.gethostname()}_{os.getpid()}"


def micro_time(moment: datetime.datetime) -> str:
    """Kubernetes ``MicroTime``: ``2030-01-01T00:00:00.000000Z``."""
    return moment.astimezone(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%S.%fZ")


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LeaseSettings:
    """Which Lease, who we are, and client-go's default timing."""

    name: str
    namespace: str
    identity: str
    lease_duration: float = 15.0
    """Seconds a candidate waits after the last observed change of the record before taking over."""
    renew_deadline: float = 10.0
    """Seconds the holder keeps acting without a successful renewal."""
    retry_period: float = 2.0
    """Seconds between two attempts to acquire or renew."""

    def __post_init__(self) -> None:
        if not self.retry_period < self.renew_deadline < self.lease_duration:
            raise ValueError(
                "leader election needs retryPeriod < renewDeadline < leaseDuration, got "
                f"{self.retry_period} / {self.renew_deadline} / {self.lease_duration}"
            )
        if not self.identity:
            raise ValueError("leader election needs a non-empty identity")


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class LeaseRecord:
    """The fields of a Lease that election reads."""

    holder: str
    lease_duration: float
    acquire_time: str | None
    renew_time: str | None
    transitions: int
    resource_version: str

    @property
    def fingerprint(self) -> tuple[str, float, str | None]:
        """What must change for a holder to count as alive."""
        return (self.holder, self.lease_duration, self.renew_time)


def lease_record(body: Mapping[str, Any]) -> LeaseRecord:
    """Parse a Lease body (lenient: a missing field reads as empty)."""
    spec = body.get("spec") or {}
    meta = body.get("metadata") or {}
    return LeaseRecord(
        holder=str(spec.get("holderIdentity") or ""),
        lease_duration=float(spec.get("leaseDurationSeconds") or 0),
        acquire_time=spec.get("acquireTime"),
        renew_time=spec.get("renewTime"),
        transitions=int(spec.get("leaseTransitions") or 0),
        resource_version=str(meta.get("resourceVersion", "")),
    )


class Decision(enum.StrEnum):
    """What a candidate does with the Lease it just read."""

    ACQUIRE = "Acquire"
    RENEW = "Renew"
    WAIT = "Wait"


def decide(
    record: LeaseRecord | None,
    *,
    identity: str,
    observed_at: float,
    now: float,
    lease_duration: float,
) -> Decision:
    """Acquire a free or expired Lease, renew our own, wait for anybody else's.

    ``observed_at`` is when (on our monotonic clock) we last saw the record change; the record's
    own duration counts if set, else ours."""
    if record is None or not record.holder:
        return Decision.ACQUIRE
    if record.holder == identity:
        return Decision.RENEW
    duration = record.lease_duration or lease_duration
    if now >= observed_at + duration:
        return Decision.ACQUIRE
    return Decision.WAIT


def lease_body(
    record: LeaseRecord | None,
    settings: LeaseSettings,
    *,
    now: datetime.datetime,
    release: bool = False,
) -> dict[str, Any]:
    """The Lease we write: ours from now (or, with ``release``, nobody's)."""
    ours = record is not None and record.holder == settings.identity
    transitions = 0 if record is None else record.transitions + (0 if ours else 1)
    stamp = micro_time(now)
    spec: dict[str, Any] = {
        "holderIdentity": "" if release else settings.identity,
        "leaseDurationSeconds": 1 if release else max(int(settings.lease_duration), 1),
        "acquireTime": record.acquire_time if ours and record and record.acquire_time else stamp,
        "renewTime": stamp,
        "leaseTransitions": transitions,
    }
    metadata: dict[str, Any] = {"name": settings.name, "namespace": settings.namespace}
    if record is not None:
        metadata["resourceVersion"] = record.resource_version
    return {
        "apiVersion": "coordination.k8s.io/v1",
        "kind": "Lease",
        "metadata": metadata,
        "spec": spec,
    }


def utcnow() -> datetime.datetime:
    """The wall clock (only for the timestamps written into the Lease)."""
    return datetime.datetime.now(datetime.UTC)


class Elector:
    """The election task of one operator process."""

    def __init__(
        self,
        client: Client,
        settings: LeaseSettings,
        *,
        on_started: Callable[[], None],
        on_stopped: Callable[[], Awaitable[None]],
        clock: Callable[[], float] = time.monotonic,
        wall: Callable[[], datetime.datetime] = utcnow,
    ) -> None:
        self.client = client
        self.settings = settings
        self.on_started = on_started
        self.on_stopped = on_stopped
        self.clock = clock
        self.wall = wall
        self.leading = False
        self.last_renewal = 0.0
        self.record: LeaseRecord | None = None
        self._seen: tuple[str, float, str | None] | None = None
        self._seen_at = clock()
        self._path = f"{API}/namespaces/{settings.namespace}/leases"

    async def run(self) -> None:
        """Acquire, renew, step down and try again, every ``retryPeriod``, until cancelled."""
        while True:
            started = self.clock()
            await self.step()
            await asyncio.sleep(max(self.settings.retry_period - (self.clock() - started), 0.0))

    async def step(self) -> None:
        """One round: try to acquire or renew (never longer than a leader may go without a
        renewal), then start or stop leading accordingly."""
        started = self.clock()
        budget = self.settings.renew_deadline
        if self.leading:
            budget = max(self.last_renewal + self.settings.renew_deadline - started, 0.1)
        try:
            held = await asyncio.wait_for(self._attempt(), budget)
        except (TimeoutError, ClusterError) as exc:
            log.warning("lease %s: %s", self._name(), exc or "request timed out")
            held = False
        now = self.clock()
        if held:
            self.last_renewal = now
            if not self.leading:
                self._start()
        elif self.leading and now - self.last_renewal >= self.settings.renew_deadline:
            log.error(
                "lease %s: not renewed for %.0fs (renewDeadline); stopping the campaign loops",
                self._name(),
                now - self.last_renewal,
            )
            self.leading = False
            await self.on_stopped()

    async def release(self) -> None:
        """Give the Lease up (clean shutdown), so a follower takes over at once."""
        if not self.leading:
            return
        self.leading = False
        with contextlib.suppress(ClusterError, TimeoutError):
            path = f"{self._path}/{self.settings.name}"
            current = lease_record(await self.client.request("GET", path, kind="leases"))
            if current.holder == self.settings.identity:
                body = lease_body(current, self.settings, now=self.wall(), release=True)
                await asyncio.wait_for(
                    self.client.request("PUT", path, body=body, kind="leases"),
                    self.settings.retry_period,
                )
                log.info("lease %s released", self._name())

    def _name(self) -> str:
        return f"{self.settings.namespace}/{self.settings.name}"

    def _start(self) -> None:
        previous = self.record.holder if self.record is not None else ""
        self.leading = True
        took = (
            f", taking over from {previous}"
            if previous and previous != self.settings.identity
            else ""
        )
        log.info("lease %s acquired by %s%s: leading", self._name(), self.settings.identity, took)
        self.on_started()

    async def _attempt(self) -> bool:
        """One round: read the Lease, then acquire/renew it if due. True when we hold it."""
        path = f"{self._path}/{self.settings.name}"
        try:
            record: LeaseRecord | None = lease_record(
                await self.client.request("GET", path, kind="leases")
            )
        except NotFoundError:
            record = None
        now = self.clock()
        if record is not None and record.fingerprint != self._seen:
            self._seen, self._seen_at = record.fingerprint, now
            if record.holder != self.settings.identity and not self.leading:
                log.info("lease %s held by %s: following", self._name(), record.holder or "nobody")
        decision = decide(
            record,
            identity=self.settings.identity,
            observed_at=self._seen_at,
            now=now,
            lease_duration=self.settings.lease_duration,
        )
        if decision is Decision.WAIT:
            self.record = record
            return False
        body = lease_body(record, self.settings, now=self.wall())
        try:
            if record is None:
                await self.client.request("POST", self._path, body=body, kind="leases")
            else:
                await self.client.request("PUT", path, body=body, kind="leases")
        except (ConflictError, AlreadyExistsError):  # another candidate won the race
            return False
        if decision is Decision.ACQUIRE:
            self.record = record
        return True
