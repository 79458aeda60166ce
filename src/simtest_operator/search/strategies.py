"""How the next point is proposed: grid, random, optuna's TPE, boundary active learning, hybrid.

A strategy proposes one unit-cube point at a time from the proposal's index, the outcomes told so
far (in tell order) and the points asked but not yet told. Its randomness is seeded from the
search seed and the index alone, so a proposal is a pure function of (spec, seed, the sequence of
asks and tells) however the asks were batched, and a replay reproduces it.
"""

from __future__ import annotations

import dataclasses
import enum
import logging
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol

import numpy as np
import numpy.typing as npt

from simtest_operator.api.v1alpha1.search import SearchObjective, SearchSpec, SearchStrategy
from simtest_operator.search import boundaries
from simtest_operator.search.records import Outcome, criticality
from simtest_operator.search.spaces import Points, SearchSpace

if TYPE_CHECKING:
    import optuna

Point = tuple[float, ...]


@dataclasses.dataclass(frozen=True, slots=True)
class History:
    """What a strategy may look at when it proposes."""

    index: int
    told: Sequence[tuple[Point, Outcome]]
    """Points and their outcomes, in the order they were told."""
    pending: Sequence[Point]
    """Points asked and not told yet, in the order asked."""


class Strategy(Protocol):
    """Proposes the next unit-cube point."""

    @property
    def capacity(self) -> int | None:
        """How many points it can propose at most (None: unlimited)."""

    def propose(self, history: History) -> Point: ...


def create(spec: SearchSpec, space: SearchSpace) -> Strategy:
    """The strategy ``spec`` names, over ``space``."""
    match spec.strategy:
        case SearchStrategy.GRID:
            return Grid(space, spec.budget)
        case SearchStrategy.RANDOM:
            return Random(space, spec.seed)
        case SearchStrategy.TPE:
            return Tpe(space, spec.seed, spec.objectives[0])
        case SearchStrategy.BOUNDARY:
            return ActiveBoundary(space, spec.seed)
        case SearchStrategy.HYBRID:
            return Hybrid(space, spec.seed)


def _rng(seed: int, index: int) -> np.random.Generator:
    return np.random.default_rng([seed, index])


class Grid:
    """The grid the budget affords, in a fixed order (see :meth:`SearchSpace.grid_points`)."""

    def __init__(self, space: SearchSpace, budget: int) -> None:
        self._points = space.grid_points(budget)

    @property
    def capacity(self) -> int | None:
        """The grid's size: the largest even grid within the budget may have fewer points."""
        return len(self._points)

    def propose(self, history: History) -> Point:
        return tuple(float(u) for u in self._points[history.index])


class Random:
    """Independent uniform points."""

    def __init__(self, space: SearchSpace, seed: int) -> None:
        self._size = space.size
        self._seed = seed

    @property
    def capacity(self) -> int | None:
        """Unlimited."""
        return None

    def propose(self, history: History) -> Point:
        return tuple(float(u) for u in _rng(self._seed, history.index).random(self._size))


STARTUP_TRIALS = 10
"""Random points before TPE models anything (optuna's default)."""


class Tpe:
    """Optuna's multivariate TPE minimising the objective's criticality.

    Each proposal rebuilds an in-memory study from the told trials (runs that judged nothing are
    FAIL trials) and the pending ones (RUNNING: the constant liar keeps a batch from piling onto
    one point), then asks it once, with a sampler seeded from the seed and the index.
    """

    def __init__(self, space: SearchSpace, seed: int, objective: SearchObjective) -> None:
        # Imported on use: optuna (with SQLAlchemy) costs a second of start-up nobody else pays.
        import optuna

        self._optuna = optuna
        self._space = space
        self._seed = seed
        self._objective = objective
        # optuna announces every in-memory study at INFO; a search builds one per proposal.
        logging.getLogger("optuna").setLevel(logging.WARNING)
        self._distributions: dict[str, optuna.distributions.BaseDistribution] = {
            f"x{i}": optuna.distributions.FloatDistribution(0.0, 1.0) for i in range(space.size)
        }

    @property
    def capacity(self) -> int | None:
        """Unlimited."""
        return None

    def propose(self, history: History) -> Point:
        optuna = self._optuna
        sampler = optuna.samplers.TPESampler(
            seed=int(_rng(self._seed, history.index).integers(2**31)),
            n_startup_trials=STARTUP_TRIALS,
            multivariate=True,
            constant_liar=True,
        )
        study = optuna.create_study(sampler=sampler, direction="minimize")
        for point, outcome in history.told:
            score = criticality(outcome, self._objective)
            state = optuna.trial.TrialState.COMPLETE if score is not None else None
            study.add_trial(
                optuna.trial.create_trial(
                    params=self._params(point),
                    distributions=self._distributions,
                    value=score,
                    state=state or optuna.trial.TrialState.FAIL,
                )
            )
        for point in history.pending:
            study.add_trial(
                optuna.trial.create_trial(
                    params=self._params(point),
                    distributions=self._distributions,
                    state=optuna.trial.TrialState.RUNNING,
                )
            )
        trial = study.ask(self._distributions)
        return tuple(float(trial.params[f"x{i}"]) for i in range(self._space.size))

    def _params(self, point: Point) -> dict[str, float]:
        return {f"x{i}": min(max(u, 0.0), 1.0) for i, u in enumerate(point)}


CANDIDATES = 2048
"""Random candidates scored per proposal of the boundary and hybrid strategies."""
EXPLORATION = 0.5
"""Weight of the distance to the nearest known point against the boundary's uncertainty: keeps
part of every batch on unexplored ground, where a small failure region may hide."""


@dataclasses.dataclass(frozen=True, slots=True)
class _Scene:
    """What a model-based proposal scores: candidates, their distance to the nearest told or
    pending point (relative to the spacing the points so far would have on a grid) and the
    margin model (None while the told runs hold one class)."""

    candidates: Points
    distance: npt.NDArray[np.float64]
    model: boundaries.Margin | None

    def pick(self, score: npt.NDArray[np.float64]) -> Point:
        return tuple(float(u) for u in self.candidates[int(np.argmax(score))])


class ActiveBoundary:
    """Active learning of the pass/fail boundary with a Gaussian process on the verdict margin.

    The first points are a scrambled Sobol design (``2^m >= max(10, 4 d)`` of them, seeded);
    while the told runs hold only one class the next point is the candidate farthest from every
    known point; then a candidate maximises the uncertainty ``1 - |2p - 1|`` of the failure
    probability ``p`` of :class:`.boundaries.Margin` plus ``EXPLORATION`` times its relative
    distance to the nearest told or pending point, so a batch spreads along the boundary
    instead of stacking where it is least certain. The model is refitted on the schedule of
    :func:`refit_point`, so one fit serves a whole batch and long searches stay cheap.
    """

    def __init__(self, space: SearchSpace, seed: int) -> None:
        self._size = space.size
        self._seed = seed
        from scipy.stats import qmc

        initial = max(10, 4 * space.size)
        sobol = qmc.Sobol(d=space.size, scramble=True, seed=seed)
        self._design: Points = sobol.random_base2(m=math.ceil(math.log2(initial)))
        self._fit: tuple[int, boundaries.Margin | None] | None = None

    @property
    def capacity(self) -> int | None:
        """Unlimited."""
        return None

    @property
    def design(self) -> int:
        """How many initial design points it proposes."""
        return len(self._design)

    def propose(self, history: History) -> Point:
        if history.index < len(self._design):
            return tuple(float(u) for u in self._design[history.index])
        scene = self.scene(history)
        if scene.model is None:
            return scene.pick(scene.distance)
        return self.refine(scene)

    def refine(self, scene: _Scene, target: float = 0.5) -> Point:
        """The candidate whose failure probability is nearest ``target`` (the boundary at 0.5),
        spread out."""
        assert scene.model is not None
        probability = scene.model.failure_probability(scene.candidates)
        uncertainty = 1.0 - np.abs(probability - target) / max(target, 1.0 - target)
        return scene.pick(uncertainty + EXPLORATION * np.minimum(scene.distance, 1.0))

    def scene(self, history: History, candidates: Points | None = None) -> _Scene:
        """The candidates of proposal ``history.index`` (random unless given), scored."""
        known = np.array(
            [p for p, _ in history.told] + list(history.pending), dtype=np.float64
        ).reshape(-1, self._size)
        if candidates is None:
            candidates = _rng(self._seed, history.index).random((CANDIDATES, self._size))
        spacing = max(len(known), 1) ** (-1.0 / self._size)
        return _Scene(candidates, _nearest(candidates, known) / spacing, self.model(history))

    def model(self, history: History) -> boundaries.Margin | None:
        """The margin model of the first told outcomes the refit schedule allows (None while
        they hold one class: a margin without a failure says nothing about where one is)."""
        told = refit_point(len(history.told))
        # The told sequence only grows: the last fit serves until the schedule moves on.
        if self._fit is None or self._fit[0] != told:
            judged = [(p, o) for p, o in history.told[:told] if o.judged]
            margins = np.array([margin(o) for _, o in judged], dtype=np.float64)
            labels = margins < 0
            fitted = None
            if labels.any() and not labels.all():
                points = np.array([p for p, _ in judged], dtype=np.float64)
                fitted = boundaries.fit_margin(points.reshape(-1, self._size), margins)
            self._fit = (told, fitted)
        return self._fit[1]


def margin(outcome: Outcome) -> float:
    """The verdict's continuous margin of a judged outcome: -1 for a failure, ``[0, 1)`` for a
    pass (see :func:`.criticality`), whatever the search's own objective is."""
    score = criticality(outcome, SearchObjective())
    assert score is not None
    return score


REFIT_ALWAYS = 100
"""Up to this many told outcomes the model is refitted on every proposal (a fit on 100
points takes a few hundredths of a second)."""
REFIT_GROWTH = 0.25
"""Beyond ``REFIT_ALWAYS`` the model is refitted once the told outcomes grew by this share:
a Gaussian process fit costs n³, so all fits of a search together cost about two of the last
(0.4 s at 400 points, 4 s at 800), and budgets in the thousands stay usable."""


def refit_point(told: int) -> int:
    """On how many of the first ``told`` outcomes the model is fitted: a function of the
    count alone, so a replay fits on the same outcomes."""
    point = 0
    while True:
        following = point + 1 if point < REFIT_ALWAYS else math.ceil(point * (1 + REFIT_GROWTH))
        if following > told:
            return point
        point = following


class Role(enum.Enum):
    """What one hybrid proposal is for."""

    SEEK = "seek"
    """The candidate most likely to fail, away from the points so far: failures."""
    REFINE = "refine"
    """The boundary strategy's proposal: where the boundary is least certain."""
    EXPLORE = "explore"
    """The candidate farthest from every point so far: a small region nobody has hit yet."""


EXPLORE_SHARE = 0.15
"""Share of the hybrid's proposals after the design that explore, throughout."""
SEEK_SHARE = (0.9, 0.65)
"""Share that seeks failures: at the first proposal after the design, and from
``SCHEDULE_RUNS`` proposals on (linearly in between); the rest refine the boundary."""
SCHEDULE_RUNS = 150
"""Proposals after the design over which the hybrid moves from seeking failures to refining."""
SEEK_SPREAD = 1.0
"""Relative distance to the nearest known point from which a seeking candidate counts fully
(one spacing of the points so far on a grid): closer ones are discounted, so seeking covers
the failing side evenly instead of creeping from the first failure; on a thin failure band that
coverage is what the boundary classifier's recall needs."""
REFINE_TARGET = 0.7
"""Failure probability a refining proposal aims at: just inside the failing side of the
boundary, where a run pins the boundary as well as one just outside does and fails more often
(0.5 is the boundary strategy's own symmetric target)."""


def role(k: int) -> Role:
    """The role of the ``k``-th proposal after the design: a function of ``k`` alone (not of
    the budget, so a longer search starts as a shorter one does), the shares of
    ``EXPLORE_SHARE`` and ``SEEK_SHARE`` evenly spread by a golden-ratio sequence."""
    u = math.fmod((k + 1) * _GOLDEN, 1.0)
    if u < EXPLORE_SHARE:
        return Role.EXPLORE
    progress = min(max(k, 0) / SCHEDULE_RUNS, 1.0)
    seek = SEEK_SHARE[0] + (SEEK_SHARE[1] - SEEK_SHARE[0]) * progress
    return Role.SEEK if u < EXPLORE_SHARE + (1.0 - EXPLORE_SHARE) * seek else Role.REFINE


_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


class Hybrid:
    """Failures first, then the boundary, with a share of exploration throughout.

    After the boundary strategy's Sobol design every proposal has a :func:`role`: *seek* takes
    the candidate the margin model gives the highest failure probability, discounted close to
    known points (``SEEK_SPREAD``); *refine* is the boundary strategy's proposal aimed at
    ``REFINE_TARGET`` (just inside the failing side); *explore* takes the point of a Sobol pool
    farthest from every told and pending point (maximin), so a small failure region apart from
    the first one gets hit, after which seeking and refining work on it too. Seeking dominates,
    most early (failures for the budget); refining's share grows later (the boundary's
    accuracy). All roles share one model and see every told and pending point.
    """

    def __init__(self, space: SearchSpace, seed: int) -> None:
        self._boundary = ActiveBoundary(space, seed)
        self._size = space.size
        self._seed = seed

    @property
    def capacity(self) -> int | None:
        """Unlimited."""
        return None

    def propose(self, history: History) -> Point:
        k = history.index - self._boundary.design
        if k < 0:
            return self._boundary.propose(history)
        match role(k):
            case Role.EXPLORE:
                from scipy.stats import qmc

                pool = qmc.Sobol(
                    d=self._size, scramble=True, seed=_rng(self._seed, history.index)
                ).random(CANDIDATES)
                scene = self._boundary.scene(history, pool)
                return scene.pick(scene.distance)
            case Role.REFINE:
                scene = self._boundary.scene(history)
                if scene.model is None:
                    return scene.pick(scene.distance)
                return self._boundary.refine(scene, REFINE_TARGET)
            case Role.SEEK:
                scene = self._boundary.scene(history)
                if scene.model is None:
                    return scene.pick(scene.distance)
                probability = scene.model.failure_probability(scene.candidates)
                spread = np.minimum(scene.distance / SEEK_SPREAD, 1.0)
                return scene.pick(probability * spread)


def _nearest(candidates: Points, known: Points) -> npt.NDArray[np.float64]:
    if len(known) == 0:
        return np.ones(len(candidates))
    gaps = candidates[:, None, :] - known[None, :, :]
    result: npt.NDArray[np.float64] = np.sqrt((gaps**2).sum(axis=-1)).min(axis=1)
    return result
