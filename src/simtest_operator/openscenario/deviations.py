"""Accepted deviations from the OpenSCENARIO schema: report them, collect them, or refuse them.

Real files break the schema in ways the reference players (esmini, CARLA ScenarioRunner) accept
and whose meaning is unambiguous: ``parameterType="int"``, a heading in degrees, a 0.9 catalog
header. Refusing them makes whole suites ``Invalid``; accepting them silently hides the problem
from the author. So a reader that accepts one *reports* it, and the load collects the reports:

API for readers (every reader has a :class:`~simtest_operator.openscenario.reading.Context`)::

    ctx.deviation(el, "parameter-type-int", "parameterType 'int' read as 'integer'")

- ``code`` is a short, stable kebab-case id of the kind of deviation (tests and users filter on
  it; reuse a code for the same kind); ``message`` says what was written and how it was read.
- Default mode: the :class:`Deviation` (code, message, file, element, line) is recorded and the
  reader carries on with the standard's meaning. The loaded scenario lists them in document
  order in ``Scenario.deviations``; ``simtest scenario check``/``run`` print them beside the
  verdict, the run log and result.json carry them.
- Strict mode (``load_scenario(..., options=LoadOptions(strict=True))``, ``--strict`` on the
  CLI, for authors): the call raises :class:`StrictDeviationError`, a ScenarioError located at
  the element, so the scenario is ``Invalid`` with the deviation as its reason.

Only report what you then handle *correctly*; something that cannot be given a clear meaning is
an error (``ctx.error``) or unsupported (``ctx.unsupported``), not a deviation.
"""

from __future__ import annotations

import dataclasses
import re

from simtest_operator.errors import ScenarioError

_CODE = re.compile(r"^[a-z0-9]+(-[a-z0-9]+)*$")


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Deviation:
    """One accepted deviation from the schema, where it was written."""

    code: str
    """Kind of deviation, kebab-case (``parameter-type-int``, ``heading-in-degrees``, ...)."""
    message: str
    """What was written and how it was read."""
    file: str
    element: str
    line: int | None

    def describe(self) -> str:
        """One line for reports: ``message [code] (file:line <element>)``."""
        line = self.line if self.line is not None else "?"
        return f"{self.message} [{self.code}] ({self.file}:{line} <{self.element}>)"


class StrictDeviationError(ScenarioError):
    """A deviation met under strict mode: the file must follow the schema."""

    def __init__(self, deviation: Deviation) -> None:
        super().__init__(
            f"not schema-conformant (strict mode): {deviation.message} [{deviation.code}]",
            file=deviation.file,
            element=deviation.element,
            line=deviation.line,
        )
        self.deviation = deviation


@dataclasses.dataclass(slots=True)
class Deviations:
    """The deviations of one load (shared by every reader of it)."""

    strict: bool = False
    found: list[Deviation] = dataclasses.field(default_factory=list)

    def report(self, deviation: Deviation) -> None:
        """Record ``deviation``; raise StrictDeviationError under strict mode."""
        if not _CODE.match(deviation.code):
            raise ValueError(f"deviation code {deviation.code!r} is not kebab-case")
        if self.strict:
            raise StrictDeviationError(deviation)
        self.found.append(deviation)
