"""The scenario's time of day, which ``TimeOfDayCondition`` reads (:mod:`.condition_checks`).

It is the ``TimeOfDay`` of the last environment an ``EnvironmentAction`` set
(``world.environments``); with ``animation="true"`` it runs on with simulation time from the
moment it was set, as the standard describes (the sun moves), else it stands still. Before any
environment set one, there is no time of day and a ``TimeOfDayCondition`` is false.
"""

from __future__ import annotations

import datetime

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario.model import value_conditions
from simtest_operator.sim.world import World


def current(world: World) -> datetime.datetime | None:
    """The scenario's date and time now, or None when no environment gave one."""
    for set_at, environment in reversed(world.environments):
        settings = dict(environment.settings)
        text = settings.get("TimeOfDay.dateTime")
        if text is None:
            continue
        try:
            moment = value_conditions.parse_date_time(text)
        except ValueError:
            raise ScenarioError(
                f"TimeOfDay dateTime {text!r} is not an ISO 8601 date-time",
                element="TimeOfDay",
                line=environment.line,
            ) from None
        if settings.get("TimeOfDay.animation", "false").strip().lower() in ("true", "1"):
            moment += datetime.timedelta(seconds=world.time - set_at)
        return moment
    return None


def seconds_past(date_time: str, world: World) -> float | None:
    """How many seconds the time of day is past ``date_time`` (negative: before it), or None
    without a time of day."""
    now = current(world)
    if now is None:
        return None
    return (now - value_conditions.parse_date_time(date_time)).total_seconds()
