"""The search space: the dimensions of a logical scenario and the unit cube strategies work in.

Every strategy proposes points of the unit cube ``[0, 1]^d``; the space turns them into parameter
values (snapped to ``step``, categorical dimensions split into equal bins) and back. Working in the
unit cube keeps distances comparable across dimensions (metres beside m/s), which the clustering
of failure regions and the boundary classifier rely on.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import numpy.typing as npt

from simtest_operator import xmlsafe
from simtest_operator.api.v1alpha1.search import SearchParameter, SearchSpec
from simtest_operator.errors import ScenarioError
from simtest_operator.openscenario import distributions, parameters

Value = float | str
Points = npt.NDArray[np.float64]
"""An ``(n, d)`` array of points in the unit cube."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Dimension:
    """One parameter: a range ``[low, high]`` (snapped to ``step`` when set) or choices."""

    name: str
    low: float = 0.0
    high: float = 1.0
    step: float | None = None
    choices: tuple[str, ...] | None = None

    @property
    def categorical(self) -> bool:
        """Whether the dimension is a set of choices."""
        return self.choices is not None

    @property
    def levels(self) -> int | None:
        """How many distinct values the dimension has (None for a continuous range)."""
        if self.choices is not None:
            return len(self.choices)
        if self.step is None:
            return None
        return math.floor((self.high - self.low) / self.step + 1e-9) + 1

    def decode(self, u: float) -> Value:
        """The parameter value at unit coordinate ``u``."""
        u = min(max(u, 0.0), 1.0)
        if self.choices is not None:
            return self.choices[min(int(u * len(self.choices)), len(self.choices) - 1)]
        value = self.low + u * (self.high - self.low)
        if self.step is not None:
            k = round((value - self.low) / self.step)
            value = min(self.low + k * self.step, self.high)
        return round(value, 10)

    def encode(self, value: Value) -> float:
        """The unit coordinate of ``value`` (a categorical value maps to its bin's centre)."""
        if self.choices is not None:
            if str(value) not in self.choices:
                raise ValueError(f"{value!r} is not one of {self.name}'s choices")
            return (self.choices.index(str(value)) + 0.5) / len(self.choices)
        return (float(value) - self.low) / (self.high - self.low)

    def grid(self, count: int) -> list[float]:
        """``count`` evenly spread unit coordinates (every level when the dimension has levels
        and ``count`` is at least that many)."""
        levels = self.levels
        if levels is not None and count >= levels:
            return [self.encode(self.decode_level(k)) for k in range(levels)]
        if self.choices is not None:
            return [(k + 0.5) / len(self.choices) for k in range(len(self.choices))][:count]
        if count == 1:
            return [0.5]
        return [k / (count - 1) for k in range(count)]

    def decode_level(self, k: int) -> Value:
        """The ``k``-th value of a dimension with levels."""
        if self.choices is not None:
            return self.choices[k]
        assert self.step is not None
        return round(min(self.low + k * self.step, self.high), 10)

    def text(self, value: Value) -> str:
        """The value as an OpenSCENARIO override."""
        return value if isinstance(value, str) else parameters.to_text(value)


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class SearchSpace:
    """The dimensions of one logical scenario and the concrete scenario file they apply to."""

    scenario: Path | None
    """The scenario file to run (a distribution's ScenarioFile); None when built from bytes."""
    dimensions: tuple[Dimension, ...]

    @property
    def names(self) -> tuple[str, ...]:
        """Parameter names, in dimension order."""
        return tuple(d.name for d in self.dimensions)

    @property
    def size(self) -> int:
        """Number of dimensions."""
        return len(self.dimensions)

    @classmethod
    def from_spec(cls, spec: SearchSpec, scenario: Path | bytes) -> SearchSpace:
        """The space of ``spec`` over ``scenario`` (a path, or a scenario file's content).

        A ParameterValueDistribution file contributes its ranges and sets; ``spec.parameters``
        narrow or replace the dimensions of the same name and add others. Raises ScenarioError
        when a parameter is not declared by the scenario, or when there is no dimension at all.
        """
        if isinstance(scenario, Path) and distributions.is_distribution(scenario):
            space = cls.from_distribution(scenario)
            declared = set(_declared(space.scenario or scenario))
            base = {d.name: d for d in space.dimensions}
            target = space.scenario
        else:
            declared = set(_declared(scenario))
            base, target = {}, scenario if isinstance(scenario, Path) else None
        for parameter in spec.parameters:
            base[parameter.name] = _dimension(parameter)
        unknown = sorted(set(base) - declared)
        if unknown:
            raise ScenarioError(
                f"the scenario declares no parameter(s) {', '.join(unknown)}",
                file=str(scenario) if isinstance(scenario, Path) else "",
            )
        if not base:
            raise ScenarioError("a search needs at least one parameter")
        return cls(scenario=target, dimensions=tuple(base.values()))

    @classmethod
    def from_distribution(cls, path: Path) -> SearchSpace:
        """The space a ParameterValueDistribution file spans (see
        :func:`.distributions.dimensions` for what maps to a dimension)."""
        scenario, found = distributions.dimensions(path)
        dims = []
        for d in found:
            if d.choices is not None:
                dims.append(Dimension(name=d.name, choices=d.choices))
            elif d.low is not None and d.high is not None and d.low < d.high:
                dims.append(Dimension(name=d.name, low=d.low, high=d.high, step=d.step))
            elif d.low is not None:
                # A single-value range is a constant: a one-choice dimension keeps it explicit.
                dims.append(Dimension(name=d.name, choices=(parameters.to_text(d.low),)))
        return cls(scenario=scenario, dimensions=tuple(dims))

    def decode(self, point: Sequence[float]) -> dict[str, Value]:
        """Parameter values at a point of the unit cube."""
        return {d.name: d.decode(float(u)) for d, u in zip(self.dimensions, point, strict=True)}

    def encode(self, values: Mapping[str, Value]) -> list[float]:
        """The unit-cube point of a parameter assignment."""
        return [d.encode(values[d.name]) for d in self.dimensions]

    def encode_all(self, assignments: Sequence[Mapping[str, Value]]) -> Points:
        """An ``(n, d)`` array of the unit-cube points of ``assignments``."""
        return np.array([self.encode(a) for a in assignments], dtype=np.float64).reshape(
            len(assignments), self.size
        )

    def grid(self, budget: int) -> list[dict[str, Value]]:
        """The values of :meth:`grid_points`."""
        return [self.decode(p) for p in self.grid_points(budget)]

    def grid_points(self, budget: int) -> Points:
        """The grid a budget affords: the same number of values per dimension (every level of
        a dimension with fewer levels), grown one dimension at a time while the product stays
        within ``budget``, in a fixed order; cut at ``budget`` when even two values per dimension
        exceed it."""
        per = max(int(budget ** (1.0 / self.size) + 1e-9), 1)
        axes = [d.grid(per) for d in self.dimensions]
        # Spend what an even split leaves on the continuous dimensions, one more value at a time.
        while True:
            grown = False
            for i, d in enumerate(self.dimensions):
                levels = d.levels
                if levels is not None and len(axes[i]) >= levels:
                    continue
                trial = [*axes[:i], d.grid(len(axes[i]) + 1), *axes[i + 1 :]]
                if math.prod(len(a) for a in trial) <= budget:
                    axes, grown = trial, True
            if not grown:
                break
        points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, self.size)
        result: Points = points[:budget]
        return result


def _dimension(parameter: SearchParameter) -> Dimension:
    if parameter.choices is not None:
        return Dimension(name=parameter.name, choices=tuple(parameter.choices))
    assert parameter.min is not None and parameter.max is not None
    return Dimension(
        name=parameter.name, low=parameter.min, high=parameter.max, step=parameter.step
    )


def _declared(scenario: Path | bytes) -> dict[str, str]:
    if isinstance(scenario, Path):
        root = xmlsafe.parse_file(scenario)
    else:
        root = xmlsafe.parse_bytes(scenario, source="<search scenario>")
    return distributions.declared_parameters(root)
