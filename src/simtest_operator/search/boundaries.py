"""The estimated pass/fail boundary: a probabilistic classifier over the unit cube.

One implementation serves the boundary-seeking strategy (where is it most uncertain?) and the
summary (which share of a reference set does it get wrong?). A Gaussian process classifier with
an RBF kernel fits the smooth, few-dimensional boundaries of driving scenarios well from a few
hundred points, gives calibrated probabilities for uncertainty sampling, and is deterministic
(its optimiser starts from a fixed kernel, no restarts).
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
    from sklearn.gaussian_process import GaussianProcessClassifier

Labels = npt.NDArray[np.bool_]

INITIAL_LENGTH_SCALE = 0.2
"""Starting length scale in unit-cube units: a boundary that bends over a fifth of a range."""


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

    kernel = ConstantKernel(1.0, (1e-2, 1e3)) * RBF(INITIAL_LENGTH_SCALE, (1e-2, 10.0))
    model = GaussianProcessClassifier(kernel=kernel, n_restarts_optimizer=0, random_state=0)
    # One BLAS thread: the matrices are small, and on a busy node (simulators on every core)
    # a thread per core makes a 200-point fit twenty times slower, not faster.
    with warnings.catch_warnings(), threadpool_limits(limits=1):
        # A bound reached by the kernel optimiser is a property of the data, not an error.
        warnings.simplefilter("ignore", ConvergenceWarning)
        model.fit(points, failed.astype(int))
    return Boundary(model, None)
