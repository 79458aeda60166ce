"""Importing the operator (and with it the API layer's SUT conversion) does not load SUMO.

Covers: the driver-model values live in ``simtest_operator.drivermodel``, below ``sim``, so a
process that needs only them (the operator, ``simtest submit``) never imports the simulator,
libsumo or sumolib; ``simtest_operator.sim`` still exports its public names (the driver-model
types among them); an unknown name is an AttributeError.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

import simtest_operator.sim as sim
from simtest_operator import drivermodel


def test_operator_process_does_not_import_sumo() -> None:
    code = (
        "import sys\n"
        "import simtest_operator.operator.handlers, simtest_operator.api.converting\n"
        "sumo = ('libsumo', 'sumolib', 'traci')\n"
        "engine = ('simtest_operator.sim.engine', 'simtest_operator.sim.session')\n"
        "loaded = sorted(m for m in sys.modules if m.split('.')[0] in sumo or m in engine)\n"
        "print(','.join(loaded))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert done.stdout.strip() == ""


def test_public_names_resolve() -> None:
    assert sim.SutConfig is drivermodel.SutConfig
    assert callable(sim.open_simulation)


def test_unknown_name() -> None:
    with pytest.raises(AttributeError, match="no attribute 'Nope'"):
        _ = sim.Nope
