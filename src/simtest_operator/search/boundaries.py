"""The estimated pass/fail boundary over the unit cube: a classifier and a margin model.

The summary (which share of a reference set does the boundary get wrong?) uses a Gaussian
process classifier on the verdicts: an RBF kernel fits the smooth, few-dimensional boundaries
of driving scenarios well from a few hundred points. The strategies learn from more than the
verdict: a Gaussian process *regression* on the verdict's continuous margin (failures -1,
passes 0..1 by how close their criticality metrics came to failing, :func:`.criticality`), whose
mean and standard deviation give the probability that a point fails (margin below
``FAIL_LEVEL``). A pass that nearly failed then pulls the estimate towards failing, which a
classifier of verdicts alone cannot see.

Both fits are deterministic: seeded optimiser restarts, length scales capped at the unit cube's
size (an uncapped optimiser can stretch a length scale until the fit is flat: "everything
passes", a 0.18 misclassification on the cut-in once two restarts were missing).
"""

from __future__ import annotations

import dataclasses
import warnings
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt
from threadpoolctl import threadpool_limits

from simtest_operator.search.spaces import Points

if TYPE_CHECKING:
    from sklearn.gaussian_process import GaussianProcessClassifier, GaussianProcessRegressor

Labels = npt.NDArray[np.bool_]

INITIAL_LENGTH_SCALE = 0.2
"""Starting length scale in unit-cube units: a boundary that bends over a fifth of a range."""
LENGTH_SCALE_BOUNDS = (1e-2, 1.0)
"""A boundary bends within the cube: longer scales only flatten the fit into one class."""
RESTARTS = 2
"""Optimiser restarts from seeded random kernels, beside the fixed start: one start can settle
in the flat optimum."""
FAIL_LEVEL = -0.5
"""Margin below which a point counts as failing: midway between a failure (-1) and the most
critical pass (0)."""


@dataclasses.dataclass(frozen=True, slots=True)
class Boundary:
    """A fitted classifier: the probability that a point fails."""

    model: GaussianProcessClassifier | None
    constant: bool | None
    """The one label every training point had (the model is then None)."""

    def failure_probability(self, points: Points) -> npt.NDArray[np.float64]:
        """P(failure) at each row of ``points``."""
        if self.model is None:
            return np.full(len(points), 1.0 if self.constant else 0.0)
        with threadpool_limits(limits=1):
            proba: npt.NDArray[np.float64] = self.model.predict_proba(points)[:, 1]
        return proba

    def predict(self, points: Points) -> Labels:
        """Whether each row of ``points`` is predicted to fail."""
        return self.failure_probability(points) >= 0.5

    def misclassification(self, points: Points, failed: Labels) -> float:
        """The share of ``points`` whose predicted label differs from ``failed``."""
        if len(points) == 0:
            return 0.0
        return float(np.mean(self.predict(points) != failed))

    def balanced_accuracy(self, points: Points, failed: Labels) -> float:
        """Mean of the true-failure and true-pass rates on ``points`` (0.5 for a constant guess)."""
        predicted = self.predict(points)
        rates = [
            float(np.mean(predicted[failed == c] == c)) for c in (True, False) if any(failed == c)
        ]
        return float(np.mean(rates)) if rates else 1.0


def fit(points: Points, failed: Labels) -> Boundary | None:
    """The boundary of labelled unit-cube points; None without points."""
    if len(points) == 0:
        return None
    if bool(failed.all()) or not bool(failed.any()):
        return Boundary(None, bool(failed[0]))
    # Imported on use: scikit-learn costs start-up that only a fit needs.
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.gaussian_process import GaussianProcessClassifier
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel

    kernel = ConstantKernel(1.0, (1e-2, 1e3)) * RBF(INITIAL_LENGTH_SCALE, LENGTH_SCALE_BOUNDS)
    model = GaussianProcessClassifier(kernel=kernel, n_restarts_optimizer=RESTARTS, random_state=0)
    # One BLAS thread: the matrices are small, and on a busy node (simulators on every core)
    # a thread per core makes a 200-point fit twenty times slower, not faster.
    with warnings.catch_warnings(), threadpool_limits(limits=1):
        # A bound reached by the kernel optimiser is a property of the data, not an error.
        warnings.simplefilter("ignore", ConvergenceWarning)
        model.fit(points, failed.astype(int))
    return Boundary(model, None)


@dataclasses.dataclass(frozen=True, slots=True)
class Margin:
    """A fitted margin model: the estimated margin and its uncertainty, hence P(failure)."""

    model: GaussianProcessRegressor

    def predict(self, points: Points) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """Mean and standard deviation of the margin at each row of ``points``."""
        with threadpool_limits(limits=1):
            mean, std = self.model.predict(points, return_std=True)
        return np.asarray(mean, dtype=np.float64), np.maximum(std, 1e-9)

    def failure_probability(self, points: Points) -> npt.NDArray[np.float64]:
        """P(margin < ``FAIL_LEVEL``) at each row of ``points``."""
        from scipy.stats import norm

        mean, std = self.predict(points)
        result: npt.NDArray[np.float64] = norm.cdf((FAIL_LEVEL - mean) / std)
        return result


def fit_margin(points: Points, margins: npt.NDArray[np.float64]) -> Margin | None:
    """The margin model of unit-cube points and their margins (failures -1, passes in
    ``[0, 1)``); None without points."""
    if len(points) == 0:
        return None
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

    # The white noise term absorbs what the squashed metrics do not explain (a collision at
    # a near-miss's neighbour), instead of forcing the fit through every point.
    kernel = ConstantKernel(1.0, (1e-2, 1e2)) * RBF(
        INITIAL_LENGTH_SCALE, LENGTH_SCALE_BOUNDS
    ) + WhiteKernel(1e-2, (1e-5, 1e-1))
    model = GaussianProcessRegressor(
        kernel=kernel, normalize_y=True, n_restarts_optimizer=RESTARTS, random_state=0
    )
    with warnings.catch_warnings(), threadpool_limits(limits=1):
        warnings.simplefilter("ignore", ConvergenceWarning)
        model.fit(points, margins)
    return Margin(model)
