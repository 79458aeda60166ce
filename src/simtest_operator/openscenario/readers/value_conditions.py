"""Reading the value conditions of :mod:`..model.value_conditions`: TimeOfDayCondition and the
ignored UserDefinedValueCondition."""

from __future__ import annotations

from simtest_operator.openscenario import reading
from simtest_operator.openscenario.model import common as m
from simtest_operator.openscenario.model import value_conditions as v
from simtest_operator.xmlsafe import Element


def time_of_day(el: Element, ctx: reading.Context) -> v.TimeOfDayCondition:
    """Read ``<TimeOfDayCondition dateTime rule>``; a dateTime that is not ISO 8601 is an error."""
    text = ctx.string(el, "dateTime")
    try:
        v.parse_date_time(text)
    except ValueError:
        raise ctx.error(
            el, f"attribute 'dateTime': {text!r} is not an ISO 8601 date-time"
        ) from None
    return v.TimeOfDayCondition(
        date_time=text, rule=ctx.enum(el, "rule", m.Rule), line=el.sourceline
    )


def user_defined_value(el: Element, ctx: reading.Context) -> v.UserDefinedValueCondition:
    """Read ``<UserDefinedValueCondition>``: accepted and listed as ignored (never true)."""
    ctx.ignore("UserDefinedValueCondition")
    return v.UserDefinedValueCondition(
        name=ctx.string(el, "name"),
        value=ctx.string(el, "value"),
        rule=ctx.enum(el, "rule", m.Rule),
        line=el.sourceline,
    )
