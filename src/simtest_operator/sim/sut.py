"""The ego as the engine sees an external system under test.

A SUT outside the engine (another process speaking the OSI protocol of :mod:`simtest_operator.sut`)
plugs in as a :class:`Pilot`: the engine hands it the world as it was at t (:class:`PilotView`)
and applies the :class:`Order` it returns with its own vehicle model (speed along the lane, a
lateral displacement). The in-process driver model and the SUT configuration live in
:mod:`simtest_operator.drivermodel`.
"""

from __future__ import annotations

import dataclasses
from typing import Protocol

from simtest_operator.snapshots import WorldSnapshot


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class PilotView:
    """What the engine knows at t when an external SUT must decide the ego's next step."""

    snapshot: WorldSnapshot
    """Every entity (and background vehicle) at t."""
    ego_id: int
    set_speed: float
    """The scenario's current speed request to the ego (SpeedActions change it)."""
    dt: float


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Order:
    """An external SUT's decision for one step, in the engine's vehicle model."""

    speed: float
    """Ego speed (m/s) at t + dt, along its lane."""
    lateral: float = 0.0
    """Lateral displacement (m, left positive) to apply during the step."""


class Pilot(Protocol):
    """An external SUT as the engine sees it: one decision per step, in lockstep."""

    def drive(self, view: PilotView) -> Order:
        """The ego's order for the step from t to t + dt (raises SimtestError subclasses)."""
        ...
