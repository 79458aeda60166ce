"""The ``${...}`` expression evaluator.

Covers: arithmetic with precedence and associativity, unary minus, parentheses, modulo,
comparisons, and/or/not (and their C-style spellings), every standard function, parameter
references (numeric, boolean, numeric strings), ``pi``, and rejection of malformed input, unknown
names, division by zero, undefined function values, overlong and deeply nested expressions.
"""

from __future__ import annotations

import math

import pytest

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import expressions
from simtest_operator.openscenario.model.common import ParameterValue

PARAMS: dict[str, ParameterValue] = {
    "Speed": 36.0,
    "Count": 3,
    "Flag": True,
    "Off": False,
    "Text": "abc",
    "Numeric": "50",
}


def lookup(name: str) -> ParameterValue:
    if name not in PARAMS:
        raise ScenarioError(f"parameter {name!r} is not declared")
    return PARAMS[name]


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("1 + 2 * 3", 7.0),
        ("(1 + 2) * 3", 9.0),
        ("10 - 4 - 3", 3.0),
        ("100 / 10 / 5", 2.0),
        ("7 % 3", 1.0),
        ("-7 % 3", -1.0),
        ("-2 * -3", 6.0),
        ("--2", 2.0),
        ("- (1 + 1)", -2.0),
        ("1.5e2 + .5", 150.5),
        ("$Speed / 3.6", 10.0),
        ("$Speed/3.6", 10.0),
        ("$Count * 2", 6.0),
        ("-$Speed", -36.0),
        ("$Numeric - 6", 44.0),
        ("round(2.5)", 3.0),
        ("round(-2.5)", -3.0),
        ("floor(-1.5)", -2.0),
        ("ceil(1.2)", 2.0),
        ("sqrt(16)", 4.0),
        ("sin(0)", 0.0),
        ("cos(0)", 1.0),
        ("tan(0)", 0.0),
        ("asin(1)", math.pi / 2),
        ("acos(1)", 0.0),
        ("atan(1)", math.pi / 4),
        ("sign(-3)", -1.0),
        ("sign(0)", 0.0),
        ("abs(-4)", 4.0),
        ("max(2, 5)", 5.0),
        ("min(2, 5)", 2.0),
        ("pow(2, 10)", 1024.0),
        ("max(min(1, 2), pow(2, 2)) + abs(-1)", 5.0),
        ("pi", math.pi),
        ("1 < 2", True),
        ("2 <= 2", True),
        ("3 > 4", False),
        ("3 >= 4", False),
        ("1 + 1 == 2", True),
        ("1 != 1", False),
        ("$Text == $Text", True),
        ("true and false", False),
        ("true or false", True),
        ("not false", True),
        ("not $Flag or $Off", False),
        ("not 1 > 2 and 2 > 1", True),
        ("$Flag && !$Off", True),
        ("$Off || $Flag", True),
        ("true or false and false", True),
        ("$Text", "abc"),
    ],
)
def test_evaluates(text: str, expected: float | bool | str) -> None:
    result = expressions.evaluate(text, lookup)
    if isinstance(expected, float):
        assert isinstance(result, float)
        assert result == pytest.approx(expected)
    else:
        assert result == expected
        assert type(result) is type(expected)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("1 +", "unexpected end"),
        ("(1 + 2", "expected ')'"),
        ("1 2", "unexpected '2'"),
        ("foo + 1", "unknown name 'foo'"),
        ("$Missing + 1", "not declared"),
        ("1 / 0", "division by zero"),
        ("1 % 0", "division by zero"),
        ("sqrt(-1)", "undefined"),
        ("asin(2)", "undefined"),
        ("max(1)", "takes 2 argument"),
        ("abs(1, 2)", "takes 1 argument"),
        ("true + 1", "not a number"),
        ("$Text * 2", "not a number"),
        ("1 and true", "not a boolean"),
        ("not 3", "not a boolean"),
        ("1 # 2", "unexpected character"),
        ("pow(10, 400)", "undefined"),
        ("__import__(os)", "unknown name"),
        ("'a' + 1", "unexpected character"),
    ],
)
def test_rejects(text: str, message: str) -> None:
    with pytest.raises(ScenarioError) as info:
        expressions.evaluate(text, lookup)
    assert message in str(info.value)


def test_rejects_overlong_and_deeply_nested() -> None:
    with pytest.raises(ScenarioError, match="longer than"):
        expressions.evaluate("1+" * 3000 + "1", lookup)
    with pytest.raises(ScenarioError, match="nested too deeply"):
        expressions.evaluate("(" * 200 + "1" + ")" * 200, lookup)
    with pytest.raises(ScenarioError, match="nested too deeply"):
        expressions.evaluate("-" * 500 + "1", lookup)


def test_is_expression() -> None:
    assert expressions.is_expression("${1 + 1}")
    assert expressions.is_expression("  ${$a}  ")
    assert not expressions.is_expression("$a")
    assert not expressions.is_expression("{1}")
