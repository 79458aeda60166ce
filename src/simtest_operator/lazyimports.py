"""Package names that load their module on first use (PEP 562 module ``__getattr__``).

The simulator pod's start-up is on every scenario's critical path: a package that re-exports
many modules (the API models, the renderer, the evaluation) should cost only what a caller
uses, while ``from package import Name`` keeps working for everyone else.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def loader(package: str, modules: Mapping[str, str]) -> Callable[[str], Any]:
    """The ``__getattr__`` of ``package``: each name imports ``package.<modules[name]>``."""

    def load(name: str) -> Any:
        module = modules.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(f"{package}.{module}"), name)

    return load
