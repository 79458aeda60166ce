"""Evaluation criteria: what a run must satisfy, with campaign defaults and per-scenario overrides.

A campaign states its criteria once; single scenarios may tighten or relax them (a cut-in test may
accept a shorter headway than a following test). Overrides are a flat mapping with the camelCase
names the campaign manifest uses, so the api layer passes them through without translation.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from simtest_operator.errors import ScenarioError

DEFAULT_TIME_LIMIT = 300.0
"""Simulated seconds a storyboard may take before the run ends as ``Timeout``."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Criteria:
    """Pass/fail rules applied to the system under test (the ego) during a run."""

    collision: bool = True
    """Fail when the ego's bounding box touches any other entity's box."""
    min_ttc: float | None = None
    """Fail when the ego's in-path time to collision drops below this many seconds."""
    min_thw: float | None = None
    """Fail when the ego's in-path time headway drops below this many seconds."""
    max_decel: float | None = None
    """Fail when the ego decelerates harder than this (m/s^2, positive number)."""
    off_road: bool = True
    """Fail when the ego's reference point leaves the drivable road surface."""
    time_limit: float = DEFAULT_TIME_LIMIT
    """Simulated seconds within which the storyboard must complete (else ``Timeout``)."""

    def with_overrides(self, overrides: Mapping[str, object]) -> Criteria:
        """A copy with the given camelCase fields replaced; unknown names are rejected."""
        changes: dict[str, object] = {}
        for key, value in overrides.items():
            field = _FIELD_BY_KEY.get(key)
            if field is None:
                raise ScenarioError(
                    f"unknown criterion {key!r}; known: {', '.join(sorted(_FIELD_BY_KEY))}"
                )
            changes[field] = _coerce(field, key, value)
        return dataclasses.replace(self, **changes)  # type: ignore[arg-type]


_FIELD_BY_KEY = {
    "collision": "collision",
    "minTTC": "min_ttc",
    "minTHW": "min_thw",
    "maxDecel": "max_decel",
    "offRoad": "off_road",
    "timeLimit": "time_limit",
}
_BOOL_FIELDS = frozenset({"collision", "off_road"})


def _coerce(field: str, key: str, value: object) -> object:
    if field in _BOOL_FIELDS:
        if isinstance(value, bool):
            return value
        raise ScenarioError(f"criterion {key!r} must be true or false, got {value!r}")
    if value is None and field != "time_limit":
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or value < 0:
        raise ScenarioError(f"criterion {key!r} must be a non-negative number, got {value!r}")
    return float(value)
