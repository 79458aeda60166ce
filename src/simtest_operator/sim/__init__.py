"""The SUMO-backed OpenSCENARIO simulator stand-in.

Public API: :func:`open_simulation` (scenario file -> ready :class:`Simulation`); the
:class:`Simulation` itself (``start()``, ``step()`` -> a WorldSnapshot, ``complete``,
``ignored``, ``off_road``, ``close()``); :class:`SutConfig` and :class:`Takeover` for the ego
driver model; :class:`BackendChoice`. Orchestration with evaluation and recording lives in
:mod:`simtest_operator.runner.execution`.

libsumo is a per-process singleton: one simulation per process at a time.
"""

from simtest_operator.sim.engine import Simulation
from simtest_operator.sim.session import BackendChoice, Opened, open_simulation
from simtest_operator.sim.sut import SutConfig, Takeover

__all__ = ["BackendChoice", "Opened", "Simulation", "SutConfig", "Takeover", "open_simulation"]
