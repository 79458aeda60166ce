"""OpenSCENARIO 1.3 monitors: named booleans a scenario declares with an initial value and sets
with ``SetMonitorAction``; each one still false when the run ends fails it (the standard's way
for a scenario to state its own pass criteria)."""

from __future__ import annotations

import dataclasses


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class MonitorDeclaration:
    """A ``MonitorDeclaration``: the monitor ``name`` starts at ``value``."""

    name: str
    value: bool
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SetMonitorAction:
    """A ``SetMonitorAction`` (global): the monitor ``monitor_ref`` becomes ``value``."""

    monitor_ref: str
    value: bool
    line: int | None = None
