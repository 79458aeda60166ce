"""What a run tells an external SUT (HELLO) and records about it (identity, config hash,
round-trip statistics)."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import statistics
from collections.abc import Mapping, Sequence
from typing import Any

from simtest_operator.drivermodel import SutConfig
from simtest_operator.provenance import SUT_IMAGE_ID, UNKNOWN_IMAGE
from simtest_operator.sut.client import Identity
from simtest_operator.sut.messages import OSI_VERSION

_NOT_DRIVER = frozenset({"name", "version", "ego", "takeover", "external"})


def driver_model(sut: SutConfig) -> dict[str, Any]:
    """The driver-model parameters (SutConfig field names), for SUTs that want them."""
    return {
        field.name: getattr(sut, field.name)
        for field in dataclasses.fields(sut)
        if field.name not in _NOT_DRIVER
    }


def hello(
    sut: SutConfig, *, ego_id: int, step: float, scenario_id: str, seed: int
) -> dict[str, Any]:
    """The HELLO payload (besides ``protocol``)."""
    external = sut.external
    return {
        "osiVersion": ".".join(map(str, OSI_VERSION)),
        "egoId": ego_id,
        "step": step,
        "scenario": scenario_id,
        "seed": seed,
        "sut": {"name": sut.name, "version": sut.version},
        "config": dict(external.config) if external is not None else {},
        "driverModel": driver_model(sut),
        **(
            {"stepDeadlineMilliseconds": round(external.step_deadline * 1000, 3)}
            if external is not None
            else {}
        ),
    }


def config_hash(sut: SutConfig) -> str:
    """A short, stable hash of everything configurable about the SUT (to tell runs apart)."""
    external = sut.external
    data = {
        "driverModel": driver_model(sut),
        "config": dict(sorted(external.config.items())) if external is not None else {},
        "env": dict(sorted(external.env.items())) if external is not None else {},
        "command": list(external.command) if external is not None else [],
    }
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), default=str)
    return "sha256:" + hashlib.sha256(text.encode()).hexdigest()[:16]


def provenance(sut: SutConfig, identity: Identity | None) -> dict[str, str]:
    """Versions entries naming the SUT that produced a result (``identity`` None: it never
    answered READY, and the entries say what was configured, for the start-up error)."""
    external = sut.external
    out = {"sut.configHash": config_hash(sut)}
    if identity is not None:
        out["sut.reported"] = identity.describe()
    if external is not None:
        out["sut.launch"] = str(external.launch)
        if external.image:
            out["sut.image"] = external.image
            out[SUT_IMAGE_ID] = external.image_id or UNKNOWN_IMAGE
    if identity is not None and identity.digest:
        out["sut.digest"] = identity.digest
    return out


def round_trip_metrics(round_trips: Sequence[float]) -> Mapping[str, float]:
    """p50/p99/max round trip (ms) of the run's steps."""
    if not round_trips:
        return {}
    ms = sorted(value * 1000.0 for value in round_trips)
    p99 = ms[min(len(ms) - 1, round(0.99 * (len(ms) - 1)))]
    return {
        "sutSteps": float(len(ms)),
        "sutRoundTripP50Ms": round(statistics.median(ms), 4),
        "sutRoundTripP99Ms": round(p99, 4),
        "sutRoundTripMaxMs": round(ms[-1], 4),
    }
