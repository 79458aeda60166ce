"""Action runs: one running instance of an action on one actor, stepped by the engine.

The storyboard only sees :attr:`Run.finished`, :attr:`Run.stopped` and :meth:`Run.cancel`; the
engine calls :meth:`Run.step` once per simulation step while the run is active. A run claims
control domains (longitudinal, lateral); starting another run on the same actor in an overlapping
domain cancels the older one, which is how OpenSCENARIO resolves conflicting actions.
"""

from __future__ import annotations

import math

from simtest_operator.openscenario import model
from simtest_operator.sim.actors import Actor, Domain
from simtest_operator.sim.world import World

NO_DOMAINS: frozenset[Domain] = frozenset()
LONGITUDINAL = frozenset({Domain.LONGITUDINAL})
LATERAL = frozenset({Domain.LATERAL})
BOTH = frozenset({Domain.LONGITUDINAL, Domain.LATERAL})


class Run:
    """Base class of action runs; subclasses override :meth:`step`."""

    __slots__ = ("actor", "domains", "finished", "stopped")

    def __init__(self, actor: Actor | None, domains: frozenset[Domain] = NO_DOMAINS) -> None:
        self.actor = actor
        self.domains = domains
        self.finished = False
        self.stopped = False

    def cancel(self) -> None:
        if not self.finished:
            self.finished = True
            self.stopped = True

    def step(self, world: World, dt: float) -> None:
        """Advance this action by ``dt`` (default: nothing to do, already finished)."""
        self.finished = True

    def after_motion(self, world: World) -> None:
        """Hook after every actor moved this step (for actions tied rigidly to another)."""


class Done(Run):
    """An action that completed when it started (teleport, parameter set, ...)."""

    __slots__ = ()

    def __init__(self, actor: Actor | None = None) -> None:
        super().__init__(actor)
        self.finished = True


def shape_fraction(shape: model.DynamicsShape, progress: float) -> float:
    """Fraction of a transition done at ``progress`` in [0, 1] for the given shape."""
    p = min(max(progress, 0.0), 1.0)
    if shape is model.DynamicsShape.STEP:
        return 1.0
    if shape is model.DynamicsShape.LINEAR:
        return p
    if shape is model.DynamicsShape.CUBIC:
        return p * p * (3.0 - 2.0 * p)
    return (1.0 - math.cos(math.pi * p)) / 2.0


def shape_slope(shape: model.DynamicsShape, progress: float) -> float:
    """Derivative of :func:`shape_fraction` with respect to progress at ``progress``."""
    p = min(max(progress, 0.0), 1.0)
    if shape is model.DynamicsShape.STEP:
        return 0.0
    if shape is model.DynamicsShape.LINEAR:
        return 1.0
    if shape is model.DynamicsShape.CUBIC:
        return 6.0 * p * (1.0 - p)
    return math.pi / 2.0 * math.sin(math.pi * p)


def peak_rate_factor(shape: model.DynamicsShape) -> float:
    """Peak rate of a unit transition over unit time, relative to the linear shape."""
    if shape is model.DynamicsShape.CUBIC:
        return 1.5
    if shape is model.DynamicsShape.SINUSOIDAL:
        return math.pi / 2.0
    return 1.0
