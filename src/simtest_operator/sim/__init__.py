"""The SUMO-backed OpenSCENARIO simulator stand-in.

Public API: :func:`open_simulation` (scenario file -> ready :class:`Simulation`); the
:class:`Simulation` itself (``start()``, ``step()`` -> a WorldSnapshot, ``complete``,
``ignored``, ``off_road``, ``close()``); :class:`SutConfig` and :class:`Takeover` for the ego
driver model; :class:`BackendChoice`. Orchestration with evaluation and recording lives in
:mod:`simtest_operator.runner.execution`.

libsumo is a per-process singleton: one simulation per process at a time.

The names are imported lazily (PEP 562): the operator and the API layer need only the plain
driver-model values of :mod:`.sut`, and importing this package must not load SUMO into them.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from simtest_operator.sim.engine import Simulation
    from simtest_operator.sim.session import BackendChoice, Opened, open_simulation
    from simtest_operator.sim.sut import SutConfig, Takeover

_HOMES = {
    "Simulation": "engine",
    "BackendChoice": "session",
    "Opened": "session",
    "open_simulation": "session",
    "SutConfig": "sut",
    "Takeover": "sut",
}

__all__ = ["BackendChoice", "Opened", "Simulation", "SutConfig", "Takeover", "open_simulation"]


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{home}"), name)
