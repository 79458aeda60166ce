"""The reading context: typed attribute access with parameter resolution and error locations.

Every reader function takes a :class:`Context`, which knows the file being read (catalog entries
come from other files), the parameter scope visible at the current element, the catalogs, and a
shared :class:`Findings` collector for unsupported and ignored elements and accepted deviations
(:meth:`Context.deviation`, see :mod:`~simtest_operator.openscenario.deviations`). Errors raised
through it name the file, the element and the line.
"""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Callable, Iterable, Iterator, Mapping
from typing import Protocol, TypeVar

from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import parameters
from simtest_operator.openscenario.deviations import Deviation, Deviations
from simtest_operator.openscenario.model.common import (
    ParameterDeclaration,
    ParameterValue,
    Unsupported,
)
from simtest_operator.xmlsafe import Element

E = TypeVar("E", bound=enum.StrEnum)

MAX_MAGNITUDE = 1e9
"""Largest magnitude of a double attribute. Every OpenSCENARIO double is an SI quantity (m, s,
m/s, rad, ...) or a factor; nothing real comes near 1e9 (the esmini corpus stays below 1e6),
while 1e308 speeds overflow the engine's arithmetic into inf and NaN."""
T = TypeVar("T")


@dataclasses.dataclass(slots=True)
class Findings:
    """Mutable collector shared by one load: unsupported nodes, ignored element kinds, notes
    and accepted deviations (``Findings(deviations=Deviations(strict=True))`` refuses them)."""

    unsupported: list[Unsupported] = dataclasses.field(default_factory=list)
    ignored: set[str] = dataclasses.field(default_factory=set)
    notes: list[str] = dataclasses.field(default_factory=list)
    deviations: Deviations = dataclasses.field(default_factory=Deviations)


def children(el: Element) -> Iterator[Element]:
    """Element children only (comments and processing instructions are stripped at parse)."""
    for node in el:
        if isinstance(node.tag, str):
            yield node


def child(el: Element, tag: str) -> Element | None:
    """The first child called ``tag``, or None."""
    for node in children(el):
        if node.tag == tag:
            return node
    return None


def all_children(el: Element, tag: str) -> list[Element]:
    """All children called ``tag``."""
    return [node for node in children(el) if node.tag == tag]


def first_child(el: Element) -> Element | None:
    """The first element child (the chosen branch of an XSD choice), or None."""
    return next(children(el), None)


class CatalogEntry(Protocol):
    """A catalog entry as readers use it (:class:`.catalogs.Entry`)."""

    @property
    def element(self) -> Element: ...

    @property
    def entry_name(self) -> str: ...


class CatalogLookup(Protocol):
    """What readers need of the scenario's catalogs.

    :class:`~simtest_operator.openscenario.catalogs.Catalogs` implements it. It is a protocol
    because the catalogs read their entries through a :class:`Context`: importing them here would
    make the two modules import each other.
    """

    def find(
        self, ref: Element, ctx: Context, expected: tuple[str, ...]
    ) -> tuple[CatalogEntry, Context]:
        """Resolve the CatalogReference ``ref`` to an entry whose tag is one of ``expected``."""
        ...


@dataclasses.dataclass(frozen=True, slots=True)
class Context:
    """Where we are while reading: file, visible parameters, catalogs, findings."""

    file: str
    scope: parameters.Scope
    catalogs: CatalogLookup
    findings: Findings
    root_scope: parameters.Scope = parameters.EMPTY
    """The scenario's global parameters (catalog entries see these beneath their own)."""
    assignments: Mapping[str, str] | None = None
    """ParameterAssignments pending for the catalog entry about to be read."""
    depth: int = 0
    """How many catalog references deep we are."""
    carla_frame: bool = False
    """The file gives positions in CARLA's left-handed frame (FileHeader description starting
    with ``CARLA:``): y and headings are negated while reading."""
    right_offsets: bool = False
    """Lateral offsets from the road (``t``, ``dt``, ``offset``, LaneOffsetAction targets) are
    positive to the right, as ScenarioRunner places them whatever the header (its waypoint
    arithmetic runs in CARLA's frame): set for ``CARLA:`` files and files under ScenarioRunner's
    rules; they are negated while reading."""
    selections: Mapping[str, tuple[str, ...]] = dataclasses.field(default_factory=dict)
    """Members of each EntitySelection by its name (:mod:`.readers.selections`)."""

    def with_scope(self, scope: parameters.Scope) -> Context:
        """The same context with another parameter scope."""
        return dataclasses.replace(self, scope=scope)

    def entity_refs(self, names: Iterable[str]) -> tuple[str, ...]:
        """``names`` with each EntitySelection replaced by its members (no repeats): what a list
        of entities (triggering entities, actors) means."""
        out: list[str] = []
        for name in names:
            out.extend(self.selections.get(name, (name,)))
        return tuple(dict.fromkeys(out))

    def for_entry(self, file: str, assignments: Mapping[str, str]) -> Context:
        """A context for reading a catalog entry of ``file`` with its ParameterAssignments."""
        return dataclasses.replace(
            self,
            file=file,
            scope=self.root_scope,
            assignments=dict(assignments),
            depth=self.depth + 1,
        )

    def error(self, el: Element | None, message: str) -> ScenarioError:
        """A ScenarioError located at ``el``."""
        if el is None:
            return ScenarioError(message, file=self.file)
        return ScenarioError(message, file=self.file, element=str(el.tag), line=el.sourceline)

    # --- attributes ----------------------------------------------------------------------------

    def raw(self, el: Element, name: str) -> str | None:
        """The attribute text as written, or None."""
        value = el.get(name)
        return None if value is None else str(value)

    def _resolved(self, el: Element, name: str) -> ParameterValue | None:
        raw = self.raw(el, name)
        if raw is None:
            return None
        try:
            return parameters.resolve(raw, self.scope)
        except ScenarioError as exc:
            raise self.error(el, f"attribute {name!r}: {exc.args[0]}") from exc

    def _require(self, el: Element, name: str) -> ParameterValue:
        value = self._resolved(el, name)
        if value is None:
            raise self.error(el, f"missing required attribute {name!r}")
        return value

    def string(self, el: Element, name: str) -> str:
        """Required text attribute (names, references)."""
        raw = self.raw(el, name)
        if raw is not None and _lenient_name(raw):
            return self._lenient(el, name, raw)
        return self._convert(el, name, self._require(el, name), parameters.to_text)

    def opt_string(self, el: Element, name: str) -> str | None:
        """Optional text attribute."""
        return None if el.get(name) is None else self.string(el, name)

    def double(self, el: Element, name: str, *, minimum: float | None = None) -> float:
        """Required double attribute: finite, at most :data:`MAX_MAGNITUDE` in size and, with
        ``minimum``, not below it (the standard's ``[0..inf[`` ranges)."""
        number = self._convert(el, name, self._require(el, name), parameters.to_float)
        return self._bounded(el, name, number, minimum)

    def opt_double(
        self,
        el: Element,
        name: str,
        default: float | None = None,
        *,
        minimum: float | None = None,
    ) -> float | None:
        """Optional double attribute (``default`` when absent), bounded like :meth:`double`."""
        value = self._resolved(el, name)
        if value is None:
            return default
        number = self._convert(el, name, value, parameters.to_float)
        return self._bounded(el, name, number, minimum)

    def double_or(
        self, el: Element, name: str, default: float, *, minimum: float | None = None
    ) -> float:
        """Optional double attribute with a non-None default."""
        value = self.opt_double(el, name, default, minimum=minimum)
        return default if value is None else value

    def _bounded(self, el: Element, name: str, number: float, minimum: float | None) -> float:
        if abs(number) > MAX_MAGNITUDE:
            raise self.error(
                el,
                f"attribute {name!r}: {number:g} is out of range "
                f"(magnitude above {MAX_MAGNITUDE:g})",
            )
        if minimum is not None and number < minimum:
            raise self.error(el, f"attribute {name!r}: {number:g} is below its minimum {minimum:g}")
        return number

    def integer(self, el: Element, name: str) -> int:
        """Required integer attribute."""
        return self._convert(el, name, self._require(el, name), parameters.to_int)

    def opt_integer(self, el: Element, name: str, default: int | None = None) -> int | None:
        """Optional integer attribute."""
        value = self._resolved(el, name)
        return default if value is None else self._convert(el, name, value, parameters.to_int)

    def boolean(self, el: Element, name: str) -> bool:
        """Required boolean attribute."""
        return self._convert(el, name, self._require(el, name), parameters.to_bool)

    def opt_boolean(self, el: Element, name: str, default: bool | None = None) -> bool | None:
        """Optional boolean attribute."""
        value = self._resolved(el, name)
        return default if value is None else self._convert(el, name, value, parameters.to_bool)

    def enum(self, el: Element, name: str, kind: type[E], aliases: dict[str, E] | None = None) -> E:
        """Required enumeration attribute; ``aliases`` map deprecated spellings."""
        text = self.string(el, name)
        if aliases and text in aliases:
            return aliases[text]
        try:
            return kind(text)
        except ValueError:
            choices = ", ".join(member.value for member in kind)
            raise self.error(el, f"attribute {name!r}: {text!r} is not one of {choices}") from None

    def opt_enum(
        self, el: Element, name: str, kind: type[E], aliases: dict[str, E] | None = None
    ) -> E | None:
        """Optional enumeration attribute."""
        return None if el.get(name) is None else self.enum(el, name, kind, aliases)

    def _convert(
        self, el: Element, name: str, value: ParameterValue, fn: Callable[[ParameterValue], T]
    ) -> T:
        try:
            return fn(value)
        except ScenarioError as exc:
            raise self.error(el, f"attribute {name!r}: {exc.args[0]}") from exc

    def _lenient(self, el: Element, name: str, raw: str) -> str:
        # esmini builds names with non-standard string expressions such as
        # "${$entity_name + trajectory event}". Names only need to be consistent, so a name
        # expression that does not evaluate becomes its text with $parameters substituted.
        try:
            return parameters.to_text(parameters.resolve(raw, self.scope))
        except ScenarioError:
            return _substitute(raw, self.scope)

    # --- elements ------------------------------------------------------------------------------

    def require(self, el: Element, tag: str) -> Element:
        """The child ``tag`` of ``el``; ScenarioError when missing."""
        found = child(el, tag)
        if found is None:
            raise self.error(el, f"missing required element <{tag}>")
        return found

    def choice(self, el: Element) -> Element:
        """The single chosen child of an XSD choice element."""
        found = first_child(el)
        if found is None:
            raise self.error(el, "empty element; one child element is required")
        return found

    def unsupported(self, el: Element, reason: str, *, name: str | None = None) -> Unsupported:
        """Record and return an Unsupported node for ``el``."""
        node = Unsupported(
            element=str(el.tag), line=el.sourceline, reason=reason, file=self.file, name=name
        )
        self.findings.unsupported.append(node)
        return node

    def by_tag(
        self,
        el: Element,
        readers: Mapping[str, Callable[[Element, Context], T]],
        *,
        unknown: str,
        reasons: Mapping[str, str] | None = None,
    ) -> T | Unsupported:
        """Read ``el`` with the reader its tag maps to: the one place the readers choose by tag.

        Any other tag becomes an :class:`Unsupported` node, with its reason from ``reasons`` or
        else ``unknown`` followed by the tag.
        """
        read = readers.get(str(el.tag))
        if read is None:
            reason = (reasons or {}).get(str(el.tag), f"{unknown} {el.tag}")
            return self.unsupported(el, reason)
        return read(el, self)

    def ignore(self, kind: str) -> None:
        """Record an accepted-but-ignored element kind."""
        self.findings.ignored.add(kind)

    def declarations(self, el: Element) -> tuple[Context, tuple[ParameterDeclaration, ...]]:
        """Apply ``el``'s ParameterDeclarations (if any); return the inner context and them."""
        block = child(el, "ParameterDeclarations")
        pending = self.assignments
        inner = dataclasses.replace(self, assignments=None) if pending is not None else self
        if block is None:
            if pending:
                inner.ignore_assignments(el, pending)
            return inner, ()
        return inner.declare(block, pending, strict_overrides=False)

    def ignore_assignments(self, el: Element, names: Iterable[str]) -> None:
        """Report catalog ParameterAssignments to parameters the entry does not declare:
        esmini ignores them (catalogs shared between tools carry assignments only some entries
        declare), so the entry is read without them."""
        listed = ", ".join(names)
        self.deviation(
            el,
            "parameter-assignment-undeclared",
            f"assignment to parameters the entry does not declare ignored: {listed}",
        )

    def declare(
        self,
        block: Element,
        overrides: Mapping[str, str] | None = None,
        *,
        strict_overrides: bool = True,
    ) -> tuple[Context, tuple[ParameterDeclaration, ...]]:
        """Declare the ParameterDeclaration children of ``block`` with optional overrides.

        Every override must name a parameter declared in ``block``. Caller overrides are type
        checked strictly; catalog assignments (``strict_overrides=False``) may keep mistyped text
        like literals do (see :func:`parameters.declare`).
        """
        entries = [
            (
                self.declared_name(decl),
                self.parameter_type(decl, "parameterType"),
                self._plain(decl, "value"),
                decl.sourceline,
            )
            for decl in all_children(block, "ParameterDeclaration")
        ]
        unknown = sorted(set(overrides or {}) - {entry[0] for entry in entries})
        if unknown and strict_overrides:
            raise self.error(block, f"assigned parameters are not declared: {', '.join(unknown)}")
        if unknown:
            self.ignore_assignments(block, unknown)
            overrides = {k: v for k, v in (overrides or {}).items() if k not in unknown}
        try:
            scope, decls = parameters.declare(
                entries,
                self.scope,
                overrides=overrides,
                on_mistyped=self._note_at(block),
                strict_overrides=strict_overrides,
            )
        except ScenarioError as exc:
            message = str(exc.args[0]).removesuffix(f" (line {exc.line})")
            raise ScenarioError(
                message,
                file=self.file,
                element="ParameterDeclaration" if exc.line else str(block.tag),
                line=exc.line or block.sourceline,
            ) from exc
        return self.with_scope(scope), decls

    def declared_name(self, el: Element) -> str:
        """The ``name`` of a Parameter/VariableDeclaration. A name written with its reference
        prefix (``name="$owner"``) is read without it, as esmini does, and reported."""
        raw = self._plain(el, "name")
        if not raw.startswith("$") or len(raw) == 1 or raw.startswith("${"):
            return raw
        name = raw[1:]
        self.deviation(el, "parameter-name-with-prefix", f"name {raw!r} read as {name!r}")
        return name

    def parameter_type(self, el: Element, name: str) -> str:
        """The type attribute of a Parameter/VariableDeclaration, with accepted aliases
        (``int``, ``bool``) mapped to the schema's spelling and reported as deviations."""
        raw = self._plain(el, name)
        alias = parameters.TYPE_ALIASES.get(raw)
        if alias is None:
            return raw
        self.deviation(
            el, f"parameter-type-{raw}", f"{name} {raw!r} read as {alias.value!r} (schema spelling)"
        )
        return alias.value

    def deviation(self, el: Element, code: str, message: str) -> None:
        """Report an accepted deviation from the schema at ``el`` (raises under strict mode).

        See :mod:`simtest_operator.openscenario.deviations` for when to use it.
        """
        self.findings.deviations.report(
            Deviation(
                code=code, message=message, file=self.file, element=str(el.tag), line=el.sourceline
            )
        )

    def note(self, el: Element | None, message: str) -> None:
        """Record a non-fatal remark about the input (shown with the result)."""
        where = f"{self.file}:{el.sourceline}" if el is not None else self.file
        self.findings.notes.append(f"{message} ({where})")

    def _note_at(self, el: Element) -> Callable[[str], None]:
        return lambda message: self.note(el, message)

    def _plain(self, el: Element, name: str) -> str:
        raw = self.raw(el, name)
        if raw is None:
            raise self.error(el, f"missing required attribute {name!r}")
        return raw


def _lenient_name(raw: str) -> bool:
    return raw.strip().startswith("${")


def _substitute(raw: str, scope: parameters.Scope) -> str:
    out: list[str] = []
    pos = 0
    while pos < len(raw):
        if (
            raw[pos] == "$"
            and pos + 1 < len(raw)
            and (raw[pos + 1].isalpha() or raw[pos + 1] == "_")
        ):
            end = pos + 1
            while end < len(raw) and (raw[end].isalnum() or raw[end] == "_"):
                end += 1
            found = scope.lookup(raw[pos + 1 : end])
            out.append(parameters.to_text(found.value) if found else raw[pos:end])
            pos = end
        else:
            out.append(raw[pos])
            pos += 1
    return "".join(out)
