"""Expanding ParameterValueDistribution files into concrete, reproducible runs.

A distribution file names a scenario and how to vary its global parameters. Deterministic
distributions (value sets, sets, ranges) are combined as a cartesian product; stochastic ones are
sampled ``numberOfTestRuns`` times with a local ``random.Random`` seeded from ``randomSeed`` (or the
caller's seed), so the same file always gives the same runs. Each run gets a stable id
``<stem>#<k>-<hash>``: its 1-based position and a short hash of its assignment.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
import random
import types
from collections.abc import Mapping
from pathlib import Path

from simtest_operator import xmlsafe
from simtest_operator.errors import ScenarioError, UnsupportedFeatureError
from simtest_operator.openscenario import headers, loading, parameters, reading
from simtest_operator.openscenario.catalogs import Catalogs
from simtest_operator.xmlsafe import Element

MAX_RUNS = 100_000
"""Refuse distributions that expand into more runs than this."""

_MAX_REJECTIONS = 10_000

Assignment = dict[str, str]


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class ConcreteRun:
    """One concrete scenario run of a distribution: which file, with which parameter values."""

    id: str
    """Stable id ``<distribution stem>#<k>-<8 hex digits of the assignment's hash>``."""
    scenario: Path
    """Absolute path of the scenario file to load."""
    overrides: Mapping[str, str]
    """Global parameter values to pass to ``load_scenario(..., overrides=...)`` (read-only)."""


@dataclasses.dataclass(frozen=True, slots=True, kw_only=True)
class Dimension:
    """One parameter a distribution varies, as a search space sees it: a range or a value set."""

    name: str
    low: float | None = None
    high: float | None = None
    step: float | None = None
    """The deterministic range's ``stepWidth``; None for stochastic ranges."""
    choices: tuple[str, ...] | None = None


def dimensions(path: Path) -> tuple[Path, list[Dimension]]:
    """The scenario a distribution file names and the parameters it varies, as ranges or sets.

    Ranges come from deterministic ranges, uniform distributions, histograms (the bins' hull)
    and normal/log-normal/Poisson distributions with a ``Range``; sets from value sets and
    probability sets. Multi-parameter value sets vary parameters jointly and unbounded
    distributions have no range, so both raise UnsupportedFeatureError. Names the scenario
    does not declare raise ScenarioError.
    """
    ctx, dist, scenario = _opened(path)
    found: list[Dimension] = []
    for block in (reading.child(dist, "Deterministic"), reading.child(dist, "Stochastic")):
        for node in reading.children(block) if block is not None else ():
            if node.tag == "DeterministicMultiParameterDistribution":
                raise UnsupportedFeatureError(
                    "a multi-parameter value set varies parameters jointly: not a search dimension",
                    file=ctx.file,
                    element=str(node.tag),
                    line=node.sourceline,
                )
            if node.tag in ("DeterministicSingleParameterDistribution", "StochasticDistribution"):
                found.append(_dimension(ctx.string(node, "parameterName"), ctx.choice(node), ctx))
    if not found:
        raise ctx.error(dist, "the distribution varies no parameter")
    unknown = sorted({d.name for d in found} - _declared_names(scenario))
    if unknown:
        raise ctx.error(dist, f"{scenario.name} declares no parameter(s) {', '.join(unknown)}")
    return scenario, found


def _dimension(name: str, el: Element, ctx: reading.Context) -> Dimension:
    tag = el.tag
    if tag in ("DistributionSet", "ProbabilityDistributionSet"):
        values = tuple(ctx.string(item, "value") for item in reading.all_children(el, "Element"))
        if not values:
            raise ctx.error(el, "distribution yields no values")
        return Dimension(name=name, choices=values)
    if tag == "DistributionRange":
        low, high = _range(ctx.require(el, "Range"), ctx)
        return Dimension(name=name, low=low, high=high, step=ctx.double(el, "stepWidth"))
    if tag == "Histogram":
        bins = [_range(ctx.require(b, "Range"), ctx) for b in reading.all_children(el, "Bin")]
        if not bins:
            raise ctx.error(el, "a histogram needs bins")
        return Dimension(name=name, low=min(b[0] for b in bins), high=max(b[1] for b in bins))
    bounds = reading.child(el, "Range")
    if bounds is None:
        raise UnsupportedFeatureError(
            f"{tag} without a Range is unbounded: not a search dimension",
            file=ctx.file,
            element=str(tag),
            line=el.sourceline,
        )
    low, high = _range(bounds, ctx)
    return Dimension(name=name, low=low, high=high)


def declared_parameters(root: Element) -> dict[str, str]:
    """The global parameters a parsed scenario declares: name -> raw value, in file order."""
    block = reading.child(root, "ParameterDeclarations")
    decls = reading.all_children(block, "ParameterDeclaration") if block is not None else []
    return {str(decl.get("name")): str(decl.get("value") or "") for decl in decls}


def _opened(path: Path) -> tuple[reading.Context, Element, Path]:
    """A distribution file's reading context, its ParameterValueDistribution element and the
    scenario file it names (which must exist)."""
    path = path.resolve()
    file = str(path)
    root = xmlsafe.parse_file(path)
    ctx = reading.Context(
        file=file,
        scope=parameters.EMPTY,
        catalogs=Catalogs.empty(scenario_file=file),
        findings=reading.Findings(),
    )
    dist = reading.child(root, "ParameterValueDistribution")
    if dist is None:
        raise ScenarioError("not a ParameterValueDistribution file", file=file)
    scenario_el = ctx.require(dist, "ScenarioFile")
    scenario = (path.parent / ctx.string(scenario_el, "filepath")).resolve()
    if not scenario.is_file():
        raise ctx.error(scenario_el, f"scenario file {scenario} not found")
    return ctx, dist, scenario


def is_distribution(path: Path) -> bool:
    """True when ``path`` is a ParameterValueDistribution file."""
    return loading.file_kind(path) is headers.FileKind.DISTRIBUTION


def expand_distribution(path: Path, *, seed: int | None = None) -> list[ConcreteRun]:
    """Expand the distribution file at ``path`` into concrete runs, in a stable order.

    ``seed`` is used for stochastic distributions that declare no ``randomSeed`` (default 0).
    Raises ScenarioError for malformed files or parameters the scenario does not declare, and
    UnsupportedFeatureError for user-defined distributions.
    """
    ctx, dist, scenario = _opened(path)
    declared = _declared_names(scenario)
    deterministic = reading.child(dist, "Deterministic")
    stochastic = reading.child(dist, "Stochastic")
    if deterministic is not None:
        assignments = _deterministic(deterministic, ctx)
    elif stochastic is not None:
        assignments = _stochastic(stochastic, ctx, seed)
    else:
        raise ctx.error(dist, "expected Deterministic or Stochastic")
    for assignment, where in assignments:
        unknown = sorted(set(assignment) - declared)
        if unknown:
            raise ctx.error(where, f"{scenario.name} declares no parameter(s) {', '.join(unknown)}")
    return [
        ConcreteRun(
            id=f"{path.resolve().stem}#{k}-{_digest(assignment)}",
            scenario=scenario,
            overrides=types.MappingProxyType(dict(assignment)),
        )
        for k, (assignment, _) in enumerate(assignments, start=1)
    ]


def _digest(assignment: Assignment) -> str:
    text = json.dumps(sorted(assignment.items()), separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:8]


def _declared_names(scenario: Path) -> set[str]:
    root = xmlsafe.parse_file(scenario)
    if loading.file_kind_of(root, file=str(scenario)) is not headers.FileKind.SCENARIO:
        raise ScenarioError("the distribution's ScenarioFile is not a scenario", file=str(scenario))
    return set(declared_parameters(root))


def _format(value: float) -> str:
    return parameters.to_text(round(value, 10))


def _deterministic(el: Element, ctx: reading.Context) -> list[tuple[Assignment, Element]]:
    dimensions: list[list[Assignment]] = []
    for node in reading.children(el):
        if node.tag == "DeterministicMultiParameterDistribution":
            sets = reading.all_children(
                ctx.require(node, "ValueSetDistribution"), "ParameterValueSet"
            )
            dimensions.append([_value_set(s, ctx) for s in sets])
        elif node.tag == "DeterministicSingleParameterDistribution":
            name = ctx.string(node, "parameterName")
            dimensions.append([{name: value} for value in _single(ctx.choice(node), ctx)])
        else:
            raise ctx.error(node, "unknown deterministic distribution")
        if not dimensions[-1]:
            raise ctx.error(node, "distribution yields no values")
    total = math.prod(len(d) for d in dimensions)
    if total > MAX_RUNS:
        raise ctx.error(el, f"distribution expands to {total} runs (limit {MAX_RUNS})")
    runs: list[tuple[Assignment, Element]] = []
    for combo in itertools.product(*dimensions):
        merged: Assignment = {}
        for part in combo:
            merged.update(part)
        runs.append((merged, el))
    return runs


def _value_set(el: Element, ctx: reading.Context) -> Assignment:
    out: Assignment = {}
    for assignment in reading.all_children(el, "ParameterAssignment"):
        name = (ctx.raw(assignment, "parameterRef") or "").strip().removeprefix("$")
        out[name] = ctx.string(assignment, "value")
    return out


def _single(el: Element, ctx: reading.Context) -> list[str]:
    if el.tag == "DistributionSet":
        return [ctx.string(item, "value") for item in reading.all_children(el, "Element")]
    if el.tag == "DistributionRange":
        step = ctx.double(el, "stepWidth")
        low, high = _range(ctx.require(el, "Range"), ctx)
        if step <= 0:
            raise ctx.error(el, "stepWidth must be positive")
        count = math.floor((high - low) / step + 1e-9) + 1
        if count > MAX_RUNS:
            raise ctx.error(el, f"range yields {count} values (limit {MAX_RUNS})")
        return [_format(low + k * step) for k in range(count)]
    if el.tag == "UserDefinedDistribution":
        raise UnsupportedFeatureError(
            "user-defined distributions cannot be expanded",
            file=ctx.file,
            element="UserDefinedDistribution",
            line=el.sourceline,
        )
    raise ctx.error(el, "unknown single-parameter distribution")


def _range(el: Element, ctx: reading.Context) -> tuple[float, float]:
    low, high = ctx.double(el, "lowerLimit"), ctx.double(el, "upperLimit")
    if high < low:
        raise ctx.error(el, "upperLimit is below lowerLimit")
    return low, high


def _stochastic(
    el: Element, ctx: reading.Context, seed: int | None
) -> list[tuple[Assignment, Element]]:
    runs = ctx.integer(el, "numberOfTestRuns")
    if not 0 < runs <= MAX_RUNS:
        raise ctx.error(el, f"numberOfTestRuns must be between 1 and {MAX_RUNS}")
    declared_seed = ctx.opt_integer(el, "randomSeed")
    rng = random.Random(declared_seed if declared_seed is not None else (seed or 0))
    samplers = [
        (ctx.string(node, "parameterName"), ctx.choice(node))
        for node in reading.all_children(el, "StochasticDistribution")
    ]
    if not samplers:
        raise ctx.error(el, "a stochastic distribution needs at least one StochasticDistribution")
    return [({name: _sample(dist, ctx, rng) for name, dist in samplers}, el) for _ in range(runs)]


def _sample(el: Element, ctx: reading.Context, rng: random.Random) -> str:
    tag = el.tag
    bounds = reading.child(el, "Range")
    low, high = _range(bounds, ctx) if bounds is not None else (-math.inf, math.inf)
    if tag == "UniformDistribution":
        if bounds is None:
            raise ctx.error(el, "a uniform distribution needs a Range")
        return _format(rng.uniform(low, high))
    if tag == "ProbabilityDistributionSet":
        items = reading.all_children(el, "Element")
        weights = [ctx.double(item, "weight") for item in items]
        if not items or min(weights) < 0 or sum(weights) <= 0:
            raise ctx.error(el, "needs elements with non-negative weights summing above 0")
        return ctx.string(rng.choices(items, weights=weights)[0], "value")
    if tag == "Histogram":
        bins = reading.all_children(el, "Bin")
        weights = [ctx.double(b, "weight") for b in bins]
        if not bins or min(weights) < 0 or sum(weights) <= 0:
            raise ctx.error(el, "needs bins with non-negative weights summing above 0")
        chosen = rng.choices(bins, weights=weights)[0]
        return _format(rng.uniform(*_range(ctx.require(chosen, "Range"), ctx)))
    if tag in ("NormalDistribution", "LogNormalDistribution", "PoissonDistribution"):
        mean = ctx.double(el, "expectedValue")
        variance = 0.0 if tag == "PoissonDistribution" else ctx.double(el, "variance")
        if variance < 0:
            raise ctx.error(el, "variance must not be negative")
        for _ in range(_MAX_REJECTIONS):
            value = _draw(str(tag), mean, variance, rng, ctx, el)
            if low <= value <= high:
                return _format(value)
        raise ctx.error(el, "could not draw a value inside the Range")
    if tag == "UserDefinedDistribution":
        raise UnsupportedFeatureError(
            "user-defined distributions cannot be sampled",
            file=ctx.file,
            element="UserDefinedDistribution",
            line=el.sourceline,
        )
    raise ctx.error(el, "unknown stochastic distribution")


def _draw(
    tag: str, mean: float, variance: float, rng: random.Random, ctx: reading.Context, el: Element
) -> float:
    if tag == "NormalDistribution":
        return rng.gauss(mean, math.sqrt(variance))
    if tag == "LogNormalDistribution":
        # expectedValue and variance describe the log-normal variable itself.
        if mean <= 0:
            raise ctx.error(el, "a log-normal distribution needs a positive expectedValue")
        sigma2 = math.log(1.0 + variance / (mean * mean))
        return rng.lognormvariate(math.log(mean) - sigma2 / 2.0, math.sqrt(sigma2))
    if not 0 < mean <= 700:
        raise ctx.error(el, "Poisson expectedValue must be in (0, 700]")
    limit, k, product = math.exp(-mean), 0, rng.random()
    while product > limit:
        k += 1
        product *= rng.random()
    return float(k)
