"""Evaluator for OpenSCENARIO ``${...}`` expressions (safe recursive descent, never ``eval``).

Grammar (OpenSCENARIO 1.1+ expressions, lowest precedence first)::

    expr       := or
    or         := and ("or" and)*
    and        := not ("and" not)*
    not        := "not" not | comparison
    comparison := sum (("==" | "!=" | "<" | "<=" | ">" | ">=") sum)?
    sum        := product (("+" | "-") product)*
    product    := unary (("*" | "/" | "%") unary)*
    unary      := "-" unary | primary
    primary    := NUMBER | "$" NAME | "true" | "false" | "pi"
                | FUNC "(" expr ("," expr)* ")" | "(" expr ")"

Numbers are evaluated as floats; ``and``/``or``/``not`` and comparisons give booleans. ``pi`` is
an esmini-compatible extension. The input length and nesting depth are bounded so a hostile file
cannot exhaust the stack.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable, Sequence

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario.model.common import ParameterValue

Value = float | bool | str
Lookup = Callable[[str], ParameterValue]

MAX_LENGTH = 4096
MAX_DEPTH = 64

_TOKEN = re.compile(
    r"\s*(?:"
    r"(?P<number>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
    r"|\$(?P<param>[A-Za-z_][A-Za-z0-9_]*)"
    r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*)"
    r"|(?P<op>==|!=|<=|>=|&&|\|\||[-+*/%(),<>!])"
    r")"
)

_UNARY: dict[str, Callable[[float], float]] = {
    "round": lambda x: float(math.floor(x + 0.5)) if x >= 0 else -float(math.floor(-x + 0.5)),
    "floor": lambda x: float(math.floor(x)),
    "ceil": lambda x: float(math.ceil(x)),
    "sqrt": math.sqrt,
    "sin": math.sin,
    "cos": math.cos,
    "tan": math.tan,
    "asin": math.asin,
    "acos": math.acos,
    "atan": math.atan,
    "sign": lambda x: float((x > 0) - (x < 0)),
    "abs": abs,
}
_BINARY: dict[str, Callable[[float, float], float]] = {
    "max": max,
    "min": min,
    "pow": math.pow,
}
_ALIASES = {"&&": "and", "||": "or", "!": "not"}


@dataclasses.dataclass(frozen=True, slots=True)
class _Token:
    kind: str
    text: str


def _tokenize(text: str) -> list[_Token]:
    tokens: list[_Token] = []
    pos = 0
    stripped = text.rstrip()
    while pos < len(stripped):
        match = _TOKEN.match(stripped, pos)
        if not match or match.end() == pos:
            raise ScenarioError(f"unexpected character {stripped[pos:].strip()[:1]!r} in {text!r}")
        pos = match.end()
        kind = match.lastgroup or "op"
        value = match.group(kind)
        if kind == "op" and value in _ALIASES:
            kind, value = "name", _ALIASES[value]
        tokens.append(_Token(kind, value))
    return tokens


class _Parser:
    """Recursive-descent evaluator over a token list (evaluates while parsing)."""

    def __init__(self, tokens: Sequence[_Token], lookup: Lookup, source: str) -> None:
        self._tokens = tokens
        self._pos = 0
        self._lookup = lookup
        self._source = source
        self._depth = 0

    def _peek(self) -> _Token | None:
        return self._tokens[self._pos] if self._pos < len(self._tokens) else None

    def _accept(self, *texts: str) -> str | None:
        token = self._peek()
        if token is not None and token.kind in ("op", "name") and token.text in texts:
            self._pos += 1
            return token.text
        return None

    def _expect(self, text: str) -> None:
        if self._accept(text) is None:
            found = self._peek()
            raise self._error(f"expected {text!r}, found {found.text if found else 'end'!r}")

    def _error(self, message: str) -> ScenarioError:
        return ScenarioError(f"invalid expression {self._source!r}: {message}")

    def parse(self) -> Value:
        value = self._or()
        if self._peek() is not None:
            raise self._error(f"unexpected {self._tokens[self._pos].text!r}")
        return value

    def _or(self) -> Value:
        self._depth += 1
        if self._depth > MAX_DEPTH:
            raise self._error("nested too deeply")
        value = self._and()
        while self._accept("or"):
            right = self._and()
            value = self._bool(value) or self._bool(right)
        self._depth -= 1
        return value

    def _and(self) -> Value:
        value = self._not()
        while self._accept("and"):
            right = self._not()
            value = self._bool(value) and self._bool(right)
        return value

    def _not(self) -> Value:
        if self._accept("not"):
            self._depth += 1
            if self._depth > MAX_DEPTH:
                raise self._error("nested too deeply")
            value = not self._bool(self._not())
            self._depth -= 1
            return value
        return self._comparison()

    def _comparison(self) -> Value:
        left = self._sum()
        op = self._accept("==", "!=", "<=", ">=", "<", ">")
        if op is None:
            return left
        right = self._sum()
        if op in ("==", "!="):
            if isinstance(left, str) or isinstance(right, str):
                equal = str(left) == str(right)
            else:
                equal = float(left) == float(right)
            return equal if op == "==" else not equal
        a, b = self._num(left), self._num(right)
        return {"<": a < b, "<=": a <= b, ">": a > b, ">=": a >= b}[op]

    def _sum(self) -> Value:
        value = self._product()
        while op := self._accept("+", "-"):
            right = self._num(self._product())
            value = self._num(value) + right if op == "+" else self._num(value) - right
        return value

    def _product(self) -> Value:
        value = self._unary()
        while op := self._accept("*", "/", "%"):
            left, right = self._num(value), self._num(self._unary())
            if op == "*":
                value = left * right
            elif right == 0:
                raise self._error("division by zero")
            else:
                value = left / right if op == "/" else math.fmod(left, right)
        return value

    def _unary(self) -> Value:
        if self._accept("-"):
            self._depth += 1
            if self._depth > MAX_DEPTH:
                raise self._error("nested too deeply")
            value = -self._num(self._unary())
            self._depth -= 1
            return value
        if self._accept("+"):
            return self._num(self._unary())
        return self._primary()

    def _primary(self) -> Value:
        token = self._peek()
        if token is None:
            raise self._error("unexpected end")
        self._pos += 1
        if token.kind == "number":
            return float(token.text)
        if token.kind == "param":
            return self._parameter(token.text)
        if token.kind == "op" and token.text == "(":
            value = self._or()
            self._expect(")")
            return value
        if token.kind == "name":
            return self._name(token.text)
        raise self._error(f"unexpected {token.text!r}")

    def _parameter(self, name: str) -> Value:
        value = self._lookup(name)
        return float(value) if isinstance(value, int) and not isinstance(value, bool) else value

    def _name(self, name: str) -> Value:
        if name == "true":
            return True
        if name == "false":
            return False
        if name == "pi":
            return math.pi
        if name in _UNARY or name in _BINARY:
            self._expect("(")
            args = [self._num(self._or())]
            while self._accept(","):
                args.append(self._num(self._or()))
            self._expect(")")
            return self._call(name, args)
        raise self._error(f"unknown name {name!r} (parameters are written $name)")

    def _call(self, name: str, args: list[float]) -> float:
        want = 1 if name in _UNARY else 2
        if len(args) != want:
            raise self._error(f"{name}() takes {want} argument(s), got {len(args)}")
        try:
            result = _UNARY[name](args[0]) if want == 1 else _BINARY[name](args[0], args[1])
        except (ValueError, OverflowError) as exc:
            raise self._error(f"{name}{tuple(args)} is undefined") from exc
        return float(result)

    def _num(self, value: Value) -> float:
        if isinstance(value, str):
            # A string parameter holding a number (e.g. value="50") is used as that number.
            try:
                number = float(value.strip())
            except ValueError:
                raise self._error(f"{value!r} is not a number") from None
            if math.isfinite(number):
                return number
        if isinstance(value, bool | str):
            raise self._error(f"{value!r} is not a number")
        return value

    def _bool(self, value: Value) -> bool:
        if not isinstance(value, bool):
            raise self._error(f"{value!r} is not a boolean")
        return value


def evaluate(text: str, lookup: Lookup) -> Value:
    """Evaluate the inside of ``${...}`` (without the braces) using ``lookup`` for ``$name``.

    ``lookup`` raises ScenarioError for unknown parameters. Results are float, bool or (only for a
    lone string parameter) str. Raises ScenarioError (without location; callers add it).
    """
    if len(text) > MAX_LENGTH:
        raise ScenarioError(f"expression longer than {MAX_LENGTH} characters")
    try:
        value = _Parser(_tokenize(text), lookup, text).parse()
    except (ArithmeticError, ValueError) as exc:  # e.g. fmod(inf, x), found by fuzzing
        raise ScenarioError(f"invalid expression {text!r}: {exc}") from exc
    if isinstance(value, float) and not math.isfinite(value):
        raise ScenarioError(f"invalid expression {text!r}: result is not finite")
    return value


def is_expression(raw: str) -> bool:
    """True when ``raw`` is a whole ``${...}`` expression."""
    stripped = raw.strip()
    return stripped.startswith("${") and stripped.endswith("}")
