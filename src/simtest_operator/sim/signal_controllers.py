"""The RoadNetwork's traffic signal controllers, cycling through their phases.

A controller's first phase starts at t = 0, or, with a ``reference``, ``delay`` seconds after
the referenced controller's first phase (a chain of references adds up); it then cycles through
its phases in order for the whole run. A TrafficSignalControllerAction switches a controller to
a named phase at once, and it cycles on from there. Entering a phase writes the phase's states
into the world's signal states, so a TrafficSignalStateAction holds until the next phase that
sets the same signal.
"""

from __future__ import annotations

from collections.abc import Sequence

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import model


class SignalControllers:
    """The phase each controller is in, kept current as time goes on."""

    __slots__ = ("_anchors", "_controllers", "_current", "_signals")

    def __init__(
        self, controllers: Sequence[model.TrafficSignalController], signals: dict[str, str]
    ) -> None:
        self._controllers = {controller.name: controller for controller in controllers}
        self._signals = signals
        """The world's signal states, written when a controller enters a phase."""
        self._anchors = {name: self._offset(name) for name in self._controllers}
        """When each controller's first phase (of some cycle) starts, simulated seconds."""
        self._current: dict[str, int | None] = dict.fromkeys(self._controllers)

    def _offset(self, name: str) -> float:
        offset = 0.0
        controller = self._controllers[name]
        for _ in range(len(self._controllers)):  # the reader refused circles of references
            if controller.reference is None:
                break
            offset += controller.delay
            controller = self._controllers[controller.reference]
        return offset

    def update(self, time: float) -> None:
        """Enter the phase each controller is in at ``time`` (setting its signal states)."""
        for name, controller in self._controllers.items():
            index = _phase_at(controller, time - self._anchors[name])
            if index is not None and index != self._current[name]:
                self._current[name] = index
                self._signals.update(controller.phases[index].states)

    def switch(self, name: str, phase: str, time: float) -> None:
        """TrafficSignalControllerAction: ``name`` enters ``phase`` at ``time``."""
        controller = self._controller(name, "TrafficSignalControllerAction")
        names = [p.name for p in controller.phases]
        if phase not in names:
            raise ScenarioError(
                f"traffic signal controller {name!r} has no phase {phase!r} "
                f"(phases: {', '.join(names) or 'none'})",
                element="TrafficSignalControllerAction",
            )
        index = names.index(phase)
        self._anchors[name] = time - sum(p.duration for p in controller.phases[:index])
        self._current[name] = None
        self.update(time)

    def phase(self, name: str) -> str | None:
        """The phase controller ``name`` is in (None: it has no phases)."""
        controller = self._controller(name, "TrafficSignalControllerCondition")
        index = self._current[name]
        return None if index is None else controller.phases[index].name

    def _controller(self, name: str, element: str) -> model.TrafficSignalController:
        controller = self._controllers.get(name)
        if controller is None:
            raise ScenarioError(
                f"traffic signal controller {name!r} is not declared in the RoadNetwork",
                element=element,
            )
        return controller


def _phase_at(controller: model.TrafficSignalController, elapsed: float) -> int | None:
    """Index of the phase ``elapsed`` seconds after a first phase started (the cycle repeats
    both ways, so a controller delayed past t = 0 is already somewhere in its cycle)."""
    phases = controller.phases
    cycle = sum(phase.duration for phase in phases)
    if not phases:
        return None
    if cycle <= 0.0:
        return 0
    position = elapsed % cycle
    for index, phase in enumerate(phases):
        position -= phase.duration
        if position < 0.0:
            return index
    return len(phases) - 1
