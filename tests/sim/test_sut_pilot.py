"""The engine's external-SUT hook (the lockstep loop, without sockets): a pilot is asked once per
step while it drives the ego, sees the world as it was at t, gets the scenario's speed request,
and its order (speed) is what the ego does; the takeover policy still decides when it drives."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from simtest_operator.settings import SimulationSettings
from simtest_operator.sim import BackendChoice, SutConfig, Takeover, open_simulation
from simtest_operator.sim.sut import Order, PilotView

DATA = Path(__file__).parent / "data"


@dataclasses.dataclass
class RecordingPilot:
    """Holds a fixed speed and remembers what it was shown."""

    speed: float
    views: list[PilotView] = dataclasses.field(default_factory=list)

    def drive(self, view: PilotView) -> Order:
        self.views.append(view)
        return Order(speed=self.speed)


def simulate(takeover: Takeover, steps: int, pilot: RecordingPilot) -> list[float]:
    opened = open_simulation(
        DATA / "hard_braking_lead.xosc",
        sut=SutConfig(takeover=takeover),
        settings=SimulationSettings(),
        nets_dir=Path(),
        backend=BackendChoice.MEMORY,
    )
    simulation = opened.simulation
    simulation.attach_pilot(pilot)
    ego = simulation.ego
    assert ego is not None
    speeds = []
    try:
        snapshot = simulation.start()
        for _ in range(steps):
            snapshot = simulation.step()
            speeds.append(next(e.speed for e in snapshot.entities if e.name == ego))
    finally:
        simulation.close()
    return speeds


def test_the_pilot_drives_in_lockstep_from_the_takeover_and_sees_time_t() -> None:
    pilot = RecordingPilot(speed=7.0)
    speeds = simulate(Takeover.AFTER_INIT, 10, pilot)
    assert len(pilot.views) == 10  # one decision per step
    times = [view.snapshot.time for view in pilot.views]
    assert times == pytest.approx([0.05 * k for k in range(10)])  # the world at t, not t + dt
    assert speeds == [7.0] * 10  # the order is what the ego does
    assert pilot.views[0].set_speed > 0.0  # the scenario's speed for the ego, as a request
    ego_ids = {view.ego_id for view in pilot.views}
    assert len(ego_ids) == 1
    assert all(any(e.id == view.ego_id for e in view.snapshot.entities) for view in pilot.views)


def test_with_takeover_never_the_pilot_is_never_asked() -> None:
    pilot = RecordingPilot(speed=0.0)
    speeds = simulate(Takeover.NEVER, 10, pilot)
    assert pilot.views == []
    assert min(speeds) > 0.0
