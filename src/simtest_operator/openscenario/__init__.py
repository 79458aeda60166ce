"""OpenSCENARIO 1.0-1.3 loading: safe XML in, a typed immutable scenario model out.

Public API (stable):

- :func:`load_scenario` -- load a scenario file (with optional global parameter overrides and
  :class:`LoadOptions`) into :class:`model.Scenario`.
- :class:`Deviation` -- an accepted deviation from the schema (``Scenario.deviations``); readers
  report them through ``Context.deviation`` (see :mod:`.deviations`), strict mode refuses them
  with :class:`StrictDeviationError`.
- :func:`expand_distribution` / :func:`is_distribution` -- expand ParameterValueDistribution
  files into :class:`ConcreteRun` s (id, scenario path, overrides).
- :func:`file_kind` -- tell scenario, catalog and distribution files apart.
- :mod:`model` -- the scenario model the engine executes.

Errors are :class:`simtest_operator.errors.ScenarioError` (and its subclass
``UnsupportedFeatureError``) carrying file, element and line. lxml stays inside this package.
"""

from __future__ import annotations

from simtest_operator.openscenario import model
from simtest_operator.openscenario.deviations import Deviation, StrictDeviationError
from simtest_operator.openscenario.distributions import (
    ConcreteRun,
    expand_distribution,
    is_distribution,
)
from simtest_operator.openscenario.headers import FileKind
from simtest_operator.openscenario.loading import LoadOptions, file_kind, load_scenario

__all__ = [
    "ConcreteRun",
    "Deviation",
    "FileKind",
    "LoadOptions",
    "StrictDeviationError",
    "expand_distribution",
    "file_kind",
    "is_distribution",
    "load_scenario",
    "model",
]
