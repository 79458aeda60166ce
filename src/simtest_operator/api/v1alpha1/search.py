"""The ``search`` section: explore a logical scenario for failures instead of running a fixed list.

A search names one logical scenario (a scenario file with global parameters, or a
ParameterValueDistribution), the dimensions to vary, what counts as critical, the strategy that
proposes concrete scenarios, a budget of simulations and a seed. The rules are stated twice on
purpose, as in :mod:`simtest_operator.api.v1alpha1.sources`: as CEL rules in the CRD and as
pydantic validators, so ``kubectl apply`` and ``simtest run`` reject the same manifests.
"""

from __future__ import annotations

import enum
import math
from typing import Annotated, ClassVar, Literal

from pydantic import Field, StringConstraints, model_validator

from simtest_operator.api.v1alpha1.common import ApiModel, cel

MAX_BUDGET = 100_000
"""The same ceiling as a ParameterValueDistribution's expansion: a search is never bigger than
the largest fixed list the product runs."""
MAX_PARAMETERS = 32
"""Dimensions per search; beyond a few dozen no strategy here learns anything within a budget."""
MAX_CHOICES = 256
"""Values of one categorical dimension."""

ParameterName = Annotated[str, StringConstraints(min_length=1, max_length=256)]
Choice = Annotated[str, StringConstraints(min_length=1, max_length=1024)]
MetricName = Annotated[str, StringConstraints(pattern=r"^[A-Za-z][A-Za-z0-9_]*$", max_length=63)]


class SearchStrategy(enum.StrEnum):
    """How the next concrete scenarios are proposed."""

    GRID = "grid"
    """Every combination of evenly spaced values (``step`` or an even split per dimension), in a
    fixed order, truncated at the budget: the baseline."""
    RANDOM = "random"
    """Independent uniform samples: the other baseline."""
    TPE = "tpe"
    """Optuna's tree-structured Parzen estimator on a continuous criticality, batched with a
    constant liar: finds many failures quickly."""
    BOUNDARY = "boundary"
    """Active learning of the pass/fail boundary: where a Gaussian process on the verdict's
    margin is least sure, spread within each batch, after a quasi-random initial design."""
    HYBRID = "hybrid"
    """The boundary strategy's model, used to seek likely failures (early), refine the boundary
    (later) and explore the emptiest ground (throughout, for a small second failure region)."""


class SearchParameter(ApiModel):
    """One dimension of the logical scenario: a range or a set of choices, never both."""

    cel_rules: ClassVar[tuple[dict[str, str], ...]] = (
        cel(
            "(has(self.min) && has(self.max) && !has(self.choices))"
            " || (!has(self.min) && !has(self.max) && !has(self.step) && has(self.choices))",
            "set either min and max (optionally step) or choices",
        ),
        cel(
            "!has(self.min) || !has(self.max) || self.min < self.max",
            "min must be below max",
        ),
        cel("!has(self.step) || self.step > 0.0", "step must be positive"),
    )

    name: ParameterName
    """OpenSCENARIO global parameter name, declared in the scenario file."""
    min: float | None = None
    """Lower end of a continuous range."""
    max: float | None = None
    """Upper end of a continuous range."""
    step: float | None = None
    """Optional: values snap to ``min + k * step`` (also the grid spacing)."""
    choices: Annotated[list[Choice], Field(min_length=1, max_length=MAX_CHOICES)] | None = None
    """Values of a categorical dimension, passed to the scenario as written."""

    @model_validator(mode="after")
    def _range_or_choices(self) -> SearchParameter:
        is_range = self.min is not None and self.max is not None and self.choices is None
        is_set = self.min is None and self.max is None and self.step is None and bool(self.choices)
        if not (is_range or is_set):
            raise ValueError(
                f"parameter {self.name!r}: set either min and max (optionally step) or choices"
            )
        for bound in (self.min, self.max, self.step):
            if bound is not None and not math.isfinite(bound):
                raise ValueError(f"parameter {self.name!r}: bounds must be finite numbers")
        if self.min is not None and self.max is not None and not self.min < self.max:
            raise ValueError(f"parameter {self.name!r}: min must be below max")
        if self.step is not None and not self.step > 0:
            raise ValueError(f"parameter {self.name!r}: step must be positive")
        return self


class SearchObjective(ApiModel):
    """What makes a concrete scenario critical."""

    metric: MetricName = "verdict"
    """``verdict`` (Failed or Timeout is a failure) or a run metric: ``minTTC``, ``minDistance``,
    ``maxDecel``, ``minTHW``, ..."""
    goal: Literal["minimize", "maximize"] = "minimize"
    """Which direction is critical for a metric; ignored for ``verdict``."""


DEFAULT_STRATEGY = SearchStrategy.HYBRID
"""The strategy docs/search.md recommends from bench/search.py's measurements."""


class SearchSpec(ApiModel):
    """A search for failures over one logical scenario."""

    cel_rules: ClassVar[tuple[dict[str, str], ...]] = (
        cel(
            "self.parameters.all(p, self.parameters.exists_one(q, q.name == p.name))",
            "parameter names must be unique",
        ),
    )

    scenario: Annotated[str, StringConstraints(min_length=1, max_length=4096)]
    """The logical scenario: a file as the campaign's sources select it (the same id the frozen
    list uses); a ParameterValueDistribution's distributions become the parameters."""
    parameters: Annotated[list[SearchParameter], Field(max_length=MAX_PARAMETERS)] = Field(
        default_factory=list
    )
    """The dimensions; may be empty only when ``scenario`` is a ParameterValueDistribution."""
    objectives: Annotated[list[SearchObjective], Field(min_length=1, max_length=8)] = Field(
        default_factory=lambda: [SearchObjective()]
    )
    """What is critical; the first objective steers adaptive strategies."""
    strategy: SearchStrategy = DEFAULT_STRATEGY
    """How concrete scenarios are proposed: grid, random, tpe or boundary."""
    budget: Annotated[int, Field(ge=1, le=MAX_BUDGET)]
    """Simulations to run, at most 100000."""
    seed: Annotated[int, Field(ge=0, le=2**31 - 1)] = 0
    """Seed of every random choice: the same seed with the same results gives the same
    proposals."""

    @model_validator(mode="after")
    def _unique_names(self) -> SearchSpec:
        names = [p.name for p in self.parameters]
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise ValueError(f"parameter names must be unique (repeated: {', '.join(duplicates)})")
        return self
