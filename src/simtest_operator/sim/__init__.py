"""The SUMO-backed OpenSCENARIO simulator stand-in.

Public API: :func:`open_simulation` (scenario file -> ready :class:`Simulation`); the
:class:`Simulation` itself (``start()``, ``step()`` -> a WorldSnapshot, ``complete``,
``ignored``, ``off_road``, ``close()``); :class:`BackendChoice`. The ego's driver model it is
opened with (:class:`SutConfig`, :class:`Takeover`) lives in :mod:`simtest_operator.drivermodel`,
below this package, so the operator and the API layer never load the simulator. Orchestration
with evaluation and recording lives in :mod:`simtest_operator.runner`.

libsumo is a per-process singleton: one simulation per process at a time.
"""

from __future__ import annotations

from simtest_operator.drivermodel import SutConfig, Takeover
from simtest_operator.sim.engine import Simulation
from simtest_operator.sim.session import BackendChoice, Opened, open_simulation

__all__ = ["BackendChoice", "Opened", "Simulation", "SutConfig", "Takeover", "open_simulation"]
