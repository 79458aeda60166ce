"""Loading libsumo's bindings without paying for its traci façade.

``import libsumo`` runs a package init that imports traci for compatibility shims, and traci
imports the whole of sumolib, which imports numpy, pyproj and lxml: about 0.3 s of a runner's
start-up, none of which the SUMO backend uses. The backend needs only the SWIG bindings
(``libsumo.libsumo`` over ``libsumo._libsumo``, the simulator itself). :func:`bindings` loads
those under their real names with the package's init deferred, not skipped: the package module
completes itself (runs its real ``__init__``) the first time anyone asks it for a name the
bindings alone do not define, so other code that does ``import libsumo`` still gets all of it,
and there is only ever one copy of the bindings (one exception class, one simulation).

What the package init would have done up front and SUMO needs before it starts is done here:
``SUMO_HOME`` and ``PROJ_LIB`` point into the installed SUMO data (importing the ``sumo`` wheel
package sets them, as libsumo's init falls back to doing).
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from types import ModuleType
from typing import Any

from simtest_operator.errors import SimulationError

PACKAGE = "libsumo"
BINDINGS = "libsumo.libsumo"
_SUBMODULES = frozenset({"libsumo", "_libsumo"})
"""The bindings' modules: the SWIG wrapper and the extension it wraps."""


def bindings() -> ModuleType:
    """libsumo's SWIG module (``libsumo.libsumo``), loaded once per process."""
    loaded = sys.modules.get(BINDINGS)
    if loaded is not None:
        return loaded
    if PACKAGE not in sys.modules:
        _register_deferred_package()
    try:
        return importlib.import_module(BINDINGS)
    except ImportError as exc:
        raise SimulationError(f"libsumo cannot be loaded: {exc}") from exc


def loaded() -> ModuleType | None:
    """The bindings if this process loaded them, else None (never loads them)."""
    return sys.modules.get(BINDINGS)


def _register_deferred_package() -> None:
    """Put the ``libsumo`` package into ``sys.modules`` with its init not yet run."""
    import sumo  # noqa: F401  (sets SUMO_HOME and PROJ_LIB, as libsumo's init would)

    spec = importlib.util.find_spec(PACKAGE)
    if spec is None or spec.loader is None or spec.submodule_search_locations is None:
        raise SimulationError("libsumo is not installed (pip install libsumo)")
    package = importlib.util.module_from_spec(spec)
    loader = spec.loader

    def complete(name: str) -> Any:
        # PEP 562: called only for names the module does not have yet. The import system asks
        # for the two submodules before it imports them: not ours to answer. Any other name runs
        # the real init once; it finds the bindings already imported and adds traci's shims.
        if name in _SUBMODULES:
            raise AttributeError(f"module {PACKAGE!r} has no attribute {name!r}")
        package.__dict__.pop("__getattr__", None)
        loader.exec_module(package)
        return getattr(package, name)

    package.__dict__["__getattr__"] = complete
    sys.modules[PACKAGE] = package
