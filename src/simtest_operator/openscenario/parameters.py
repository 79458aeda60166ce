"""Parameter scopes, typed parameter values and resolution of ``$name``/``${...}`` attribute text.

Parameters are resolved while the file is read: every attribute passes through
:func:`resolve` with the scope that is visible at that element (global declarations, then
story/maneuver/catalog-entry declarations nested inside). Values are typed by their declaration
(integer, double, string, unsignedInt, unsignedShort, boolean, dateTime).
"""

from __future__ import annotations

import dataclasses
import datetime
import math
from collections.abc import Callable, Mapping

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import expressions
from simtest_operator.openscenario.model.common import (
    ParameterDeclaration,
    ParameterType,
    ParameterValue,
)

_TRUE = ("true", "1")
_FALSE = ("false", "0")


@dataclasses.dataclass(frozen=True, slots=True)
class Scope:
    """An immutable chain of parameter declarations; inner scopes shadow outer ones."""

    values: Mapping[str, ParameterDeclaration]
    parent: Scope | None = None

    def lookup(self, name: str) -> ParameterDeclaration | None:
        """The declaration visible as ``name``, or None."""
        scope: Scope | None = self
        while scope is not None:
            found = scope.values.get(name)
            if found is not None:
                return found
            scope = scope.parent
        return None

    def child(self, declarations: tuple[ParameterDeclaration, ...]) -> Scope:
        """A nested scope holding ``declarations`` (self when there are none)."""
        if not declarations:
            return self
        return Scope({decl.name: decl for decl in declarations}, self)


EMPTY = Scope({})

TYPE_ALIASES: Mapping[str, ParameterType] = {
    "int": ParameterType.INTEGER,
    "bool": ParameterType.BOOLEAN,
}
"""Non-schema ``parameterType`` spellings that esmini and other players accept; readers map them
(reporting a deviation) before declaring."""


def parse_type(raw: str) -> ParameterType:
    """The ParameterType for ``parameterType`` text (raises ScenarioError when unknown)."""
    try:
        return ParameterType(raw)
    except ValueError:
        choices = ", ".join(t.value for t in ParameterType)
        raise ScenarioError(f"unknown parameterType {raw!r} (one of {choices})") from None


def to_float(value: ParameterValue | float) -> float:
    """Convert a resolved value to a double."""
    if isinstance(value, bool):
        raise ScenarioError(f"boolean {value!r} where a number is expected")
    if isinstance(value, int | float):
        result = float(value)
    else:
        try:
            result = float(value.strip())
        except ValueError:
            raise ScenarioError(f"{value!r} is not a number") from None
    if not math.isfinite(result):
        raise ScenarioError(f"{value!r} is not a finite number")
    return result


def to_int(value: ParameterValue | float) -> int:
    """Convert to an integer; non-integral numbers are rounded half away from zero."""
    if isinstance(value, bool):
        raise ScenarioError(f"boolean {value!r} where an integer is expected")
    if isinstance(value, int):
        return value
    if isinstance(value, str):
        text = value.strip()
        try:
            return int(text)
        except ValueError:
            pass
    number = to_float(value)
    return math.floor(abs(number) + 0.5) * (1 if number >= 0 else -1)


def to_bool(value: ParameterValue | float) -> bool:
    """Convert to a boolean (``true``/``false``, also ``1``/``0``)."""
    if isinstance(value, bool):
        return value
    text = str(value).strip().lower()
    if isinstance(value, int | float) and not isinstance(value, bool):
        text = "1" if value == 1 else "0" if value == 0 else text
    if text in _TRUE:
        return True
    if text in _FALSE:
        return False
    raise ScenarioError(f"{value!r} is not a boolean (true/false)")


def to_text(value: ParameterValue | float) -> str:
    """Convert to text the way a file would write it (integral doubles without ``.0``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return str(int(value)) if value.is_integer() and abs(value) < 1e15 else repr(value)
    return str(value)


def convert(value: ParameterValue | float, kind: ParameterType) -> ParameterValue:
    """Convert a resolved value to the Python type of ``kind``."""
    if kind is ParameterType.DOUBLE:
        return to_float(value)
    if kind is ParameterType.BOOLEAN:
        return to_bool(value)
    if kind in (ParameterType.INTEGER, ParameterType.UNSIGNED_INT, ParameterType.UNSIGNED_SHORT):
        number = to_int(value)
        upper = 65535 if kind is ParameterType.UNSIGNED_SHORT else None
        if kind is not ParameterType.INTEGER and (number < 0 or (upper and number > upper)):
            raise ScenarioError(f"{number} is out of range for {kind.value}")
        return number
    text = to_text(value)
    if kind is ParameterType.DATE_TIME:
        try:
            datetime.datetime.fromisoformat(text)
        except ValueError:
            raise ScenarioError(f"{text!r} is not an ISO 8601 dateTime") from None
    return text


def resolve(raw: str, scope: Scope) -> ParameterValue:
    """Resolve attribute text: ``$name`` gives the parameter's typed value, ``${...}`` the
    expression's value, anything else is returned as the literal text."""
    text = raw.strip()
    if expressions.is_expression(text):
        return expressions.evaluate(text[2:-1], lambda name: _value(name, scope))
    if text.startswith("$") and len(text) > 1:
        return _value(text[1:], scope)
    return raw


def _value(name: str, scope: Scope) -> ParameterValue:
    found = scope.lookup(name)
    if found is None:
        raise ScenarioError(f"parameter {name!r} is not declared")
    return found.value


def declare(
    entries: list[tuple[str, str, str, int | None]],
    scope: Scope,
    *,
    overrides: Mapping[str, str] | None = None,
    on_mistyped: Callable[[str], None] | None = None,
    strict_overrides: bool = True,
) -> tuple[Scope, tuple[ParameterDeclaration, ...]]:
    """Declare parameters ``(name, type, raw value, line)`` in order inside ``scope``.

    Each value may refer to parameters declared before it. ``overrides`` replace the raw value of
    the parameter with the same name (caller overrides, catalog ParameterAssignments). Returns the
    new scope and the declarations with their final typed values. Errors carry the entry's line
    but no file; the caller adds it.

    A literal value that does not fit its declared type (real files declare ``double`` with
    value ``time``) is an error unless ``on_mistyped`` is given: then the value is kept as text,
    ``on_mistyped`` receives a note, and any typed use of it fails where it is used. With
    ``strict_overrides`` (caller overrides) overridden values are always checked strictly;
    catalog ParameterAssignments pass False and get the same leniency as literals.
    """
    overrides = overrides or {}
    declared: dict[str, ParameterDeclaration] = {}
    current = scope
    for name, type_text, raw, line in entries:
        text = overrides.get(name, raw)
        try:
            kind = parse_type(type_text)
            resolved = resolve(text, current)
        except ScenarioError as exc:
            raise ScenarioError(f"parameter {name!r}: {exc.args[0]}", line=line) from exc
        value: ParameterValue
        try:
            value = convert(resolved, kind)
        except ScenarioError as exc:
            strict = strict_overrides and name in overrides
            if on_mistyped is None or strict or not isinstance(resolved, str):
                raise ScenarioError(f"parameter {name!r}: {exc.args[0]}", line=line) from exc
            on_mistyped(f"parameter {name!r} kept as text: {exc.args[0]}")
            value = resolved
        declared[name] = ParameterDeclaration(name=name, type=kind, value=value, line=line)
        current = scope.child(tuple(declared.values()))
    return current, tuple(declared.values())
