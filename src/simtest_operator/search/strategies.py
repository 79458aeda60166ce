"""How the next point is proposed: grid, random, optuna's TPE, boundary active learning, hybrid.

A strategy proposes one unit-cube point at a time from the proposal's index, the outcomes told so
far (in tell order) and the points asked but not yet told. Its randomness is seeded from the
search seed and the index alone, so a proposal is a pure function of (spec, seed, the sequence of
asks and tells) however the asks were batched, and a replay reproduces it.
"""

from __future__ import annotations

import dataclasses
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
            return Hybrid(space, spec.seed, spec.objectives[0])


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
"""Random candidates scored per proposal of the boundary strategy."""
EXPLORATION = 0.5
"""Weight of the distance to the nearest known point against the classifier's uncertainty: keeps
part of every batch on unexplored ground, where a small failure region may hide."""


class ActiveBoundary:
    """Active learning of the pass/fail boundary with a Gaussian process classifier.

    The first points are a scrambled Sobol design (``2^m >= max(10, 4 d)`` of them, seeded);
    while the told runs hold only one class the next point is the candidate farthest from every
    known point; then a candidate maximises the classifier's uncertainty ``1 - |2p - 1|`` plus
    ``EXPLORATION`` times its distance to the nearest told or pending point (relative to the
    spacing the points so far would have on a grid), so a batch spreads along the boundary
    instead of stacking where it is least certain. The classifier is refitted on the schedule
    of :func:`refit_point`, so one fit serves a whole batch and long searches stay cheap.
    """

    def __init__(self, space: SearchSpace, seed: int) -> None:
        self._size = space.size
        self._seed = seed
        from scipy.stats import qmc

        initial = max(10, 4 * space.size)
        sobol = qmc.Sobol(d=space.size, scramble=True, seed=seed)
        self._design: Points = sobol.random_base2(m=math.ceil(math.log2(initial)))
        self._fit: tuple[int, boundaries.Boundary | None] | None = None

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
        known = np.array(
            [p for p, _ in history.told] + list(history.pending), dtype=np.float64
        ).reshape(-1, self._size)
        candidates = _rng(self._seed, history.index).random((CANDIDATES, self._size))
        distance = _nearest(candidates, known)
        spacing = max(len(known), 1) ** (-1.0 / self._size)
        boundary = self.boundary(history)
        if boundary is None:
            return tuple(float(u) for u in candidates[int(np.argmax(distance))])
        probability = boundary.failure_probability(candidates)
        uncertainty = 1.0 - np.abs(2.0 * probability - 1.0)
        score = uncertainty + EXPLORATION * np.minimum(distance / spacing, 1.0)
        return tuple(float(u) for u in candidates[int(np.argmax(score))])

    def boundary(self, history: History) -> boundaries.Boundary | None:
        """The classifier of the first told outcomes the refit schedule allows (None while they
        hold one class)."""
        told = refit_point(len(history.told))
        judged = [(p, o.failed) for p, o in history.told[:told] if o.judged]
        # The told sequence only grows: the last fit serves until the schedule moves on.
        if self._fit is None or self._fit[0] != told:
            labels: npt.NDArray[np.bool_] = np.array([f for _, f in judged], dtype=bool)
            fitted = boundaries.fit(
                np.array([p for p, _ in judged], dtype=np.float64).reshape(-1, self._size), labels
            )
            self._fit = (told, fitted if fitted is not None and fitted.constant is None else None)
        return self._fit[1]


REFIT_ALWAYS = 100
"""Up to this many told outcomes the classifier is refitted on every proposal (a fit on 100
points takes a few hundredths of a second)."""
REFIT_GROWTH = 0.25
"""Beyond ``REFIT_ALWAYS`` the classifier is refitted once the told outcomes grew by this share:
a Gaussian process fit costs n³, so all fits of a search together cost about two of the last
(0.4 s at 400 points, 4 s at 800), and budgets in the thousands stay usable."""


def refit_point(told: int) -> int:
    """On how many of the first ``told`` outcomes the classifier is fitted: a function of the
    count alone, so a replay fits on the same outcomes."""
    point = 0
    while True:
        following = point + 1 if point < REFIT_ALWAYS else math.ceil(point * (1 + REFIT_GROWTH))
        if following > told:
            return point
        point = following


EXPLOITATION = 0.6
"""Share of the hybrid's proposals after the initial design that TPE makes."""


class Hybrid:
    """Boundary active learning for where the system fails, TPE for how often.

    After the boundary strategy's Sobol design, proposals alternate by index (``EXPLOITATION``
    of them, spread evenly) between optuna's TPE, which samples near the most critical runs so
    far, and the boundary strategy, which samples where the classifier is least certain and on
    unexplored ground. Each sees every told and pending point whoever proposed it: TPE
    exploits the failures the boundary runs discover (including a thin band random start-up
    trials would miss), the classifier learns from TPE's runs on the failing side.
    """

    def __init__(self, space: SearchSpace, seed: int, objective: SearchObjective) -> None:
        self._boundary = ActiveBoundary(space, seed)
        self._tpe = Tpe(space, seed, objective)

    @property
    def capacity(self) -> int | None:
        """Unlimited."""
        return None

    def propose(self, history: History) -> Point:
        if exploits(history.index - self._boundary.design):
            return self._tpe.propose(history)
        return self._boundary.propose(history)


def exploits(k: int) -> bool:
    """Whether the ``k``-th proposal after the design is TPE's: ``EXPLOITATION`` of them, evenly
    spread (the design itself, ``k < 0``, is never)."""
    return k >= 0 and math.floor((k + 1) * EXPLOITATION) > math.floor(k * EXPLOITATION)


def _nearest(candidates: Points, known: Points) -> npt.NDArray[np.float64]:
    if len(known) == 0:
        return np.ones(len(candidates))
    gaps = candidates[:, None, :] - known[None, :, :]
    result: npt.NDArray[np.float64] = np.sqrt((gaps**2).sum(axis=-1)).min(axis=1)
    return result
