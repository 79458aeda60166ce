"""Value conditions beyond the engine's core ones: time of day and user-defined values.

Kept apart from :mod:`.trigger_conditions` (which lists them in its ``ValueCondition`` union) so
the OpenSCENARIO coverage additions stay in one place.
"""

from __future__ import annotations

import dataclasses
import datetime

from simtest_operator.openscenario.model.common import Rule


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class TimeOfDayCondition:
    """The scenario's time of day (the environment's ``TimeOfDay``, animated with simulation time
    when its ``animation`` is true) compared with ``date_time`` by ``rule``."""

    date_time: str
    """ISO 8601 text as written (``2026-06-01T12:00:00``, optionally with a zone offset)."""
    rule: Rule
    line: int | None = None


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class UserDefinedValueCondition:
    """A value a user's tool provides (``name``): nothing in the stand-in does, so it is never
    true; the run lists it among its ignored elements."""

    name: str
    value: str
    rule: Rule
    line: int | None = None


def parse_date_time(text: str) -> datetime.datetime:
    """An OpenSCENARIO ``DateTime`` (``xsd:dateTime``) as a datetime; a zone offset is turned
    into UTC and dropped, so times with and without one compare (one without is taken as UTC).
    ValueError for anything else."""
    value = datetime.datetime.fromisoformat(text.strip().replace("Z", "+00:00"))
    if value.tzinfo is not None:
        value = value.astimezone(datetime.UTC).replace(tzinfo=None)
    return value
