"""A pure-Python backend: holds engine-placed actors, no road network, no own traffic.

Two uses, one behaviour: unit tests run the real engine on it instead of SUMO, and scenarios
without a road network run on it in open space. The engine already integrates every entity's
kinematics, so for open space SUMO would only mirror states into an empty world at the cost of a
process-wide singleton and a dummy network; this backend is that mirror without the cost.
"""

from __future__ import annotations

from collections.abc import Mapping

from simtest_operator.errors import SimulationError
from simtest_operator.sim.backends import ActorSpec, ActorState, BackendConfig, TrafficHost


class MemoryBackend:
    """Backend protocol implementation that keeps actors in a dict."""

    __slots__ = ("_config", "_specs", "_states", "steps")

    def __init__(self) -> None:
        self._config: BackendConfig | None = None
        self._specs: dict[str, ActorSpec] = {}
        self._states: dict[str, ActorState] = {}
        self.steps = 0
        """Number of steps taken (tests check the engine steps the backend)."""

    def start(self, config: BackendConfig) -> None:
        if config.sumo_config is not None:
            raise SimulationError("the in-memory backend cannot run SUMO background traffic")
        self._config = config
        self._specs.clear()
        self._states.clear()
        self.steps = 0

    def add(self, spec: ActorSpec) -> None:
        if spec.name in self._specs:
            raise SimulationError(f"actor {spec.name!r} added twice")
        self._specs[spec.name] = spec

    def place(self, name: str, *, x: float, y: float, heading: float, speed: float) -> None:
        spec = self._specs.get(name)
        if spec is None:
            raise SimulationError(f"actor {name!r} placed before it was added")
        self._states[name] = spec.placed(x=x, y=y, heading=heading, speed=speed)

    def step(self) -> None:
        if self._config is None:
            raise SimulationError("backend stepped before start")
        self.steps += 1

    def states(self) -> Mapping[str, ActorState]:
        return dict(self._states)

    def close(self) -> None:
        self._config = None

    def traffic(self) -> TrafficHost | None:
        """None: nothing here drives vehicles of its own (traffic actions become Invalid)."""
        return None
