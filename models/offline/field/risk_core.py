"""The statistical core of the field risk fit: folds by crash, penalised fits, calibration.

- :func:`crash_folds`: every crash (year, psu, caseno) in one fold, so the
  occupants of one crash are never on both sides of a split.
- :func:`penalised_logistic`: L2-penalised logistic regression on standardised
  columns (intercept free), unweighted: the ranking fit. The survey over-samples
  severe crashes; an unweighted fit uses them all for ranking.
- :func:`weighted_recalibration`: ``logit P = a + b eta`` fitted with the
  national weights (``ratwgt``): the probability of such occupants in US
  towaway crashes.
- :class:`Fitted`: the two together, with :meth:`Fitted.probability`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from sklearn.linear_model import LogisticRegression

from models.arrays import FloatArray, IntArray

__all__ = [
    "CalibratedScore",
    "Fitted",
    "crash_folds",
    "expit",
    "fit_model",
    "logit",
    "penalised_logistic",
    "weighted_recalibration",
]

_EPS = 1e-9


def expit(x: FloatArray) -> FloatArray:
    """Logistic function (tanh form: no overflow)."""
    out: FloatArray = 0.5 * (1.0 + np.tanh(0.5 * np.asarray(x, dtype=np.float64)))
    return out


def logit(p: FloatArray) -> FloatArray:
    """``log(p / (1 - p))`` with p clipped to [1e-9, 1 - 1e-9]."""
    q = np.clip(np.asarray(p, dtype=np.float64), _EPS, 1.0 - _EPS)
    out: FloatArray = np.log(q / (1.0 - q))
    return out


def crash_folds(crash: IntArray, n_splits: int, seed: int) -> list[tuple[IntArray, IntArray]]:
    """Train/test row indices of `n_splits` folds, whole crashes to a fold.

    Parameters
    ----------
    crash : ndarray of int, shape (n,)
        Crash id per row.
    n_splits : int
    seed : int

    Returns
    -------
    list of (train, test) index arrays
    """
    ids = np.unique(crash)
    rng = np.random.default_rng(seed)
    fold_of = np.empty(ids.max() + 1, dtype=np.int64)
    fold_of[rng.permutation(ids)] = np.arange(ids.size) % n_splits
    f = fold_of[crash]
    return [(np.flatnonzero(f != k), np.flatnonzero(f == k)) for k in range(n_splits)]


def penalised_logistic(
    x: FloatArray, y: FloatArray, c: float | None, w: FloatArray | None = None
) -> FloatArray:
    """Logistic coefficients on the raw scale (column 0 the intercept, not penalised).

    Parameters
    ----------
    x : ndarray, shape (n, k)
        First column the intercept.
    y : ndarray, shape (n,)
    c : float or None
        Inverse L2 strength on the standardised columns; None unpenalised.
    w : ndarray, shape (n,), optional
        Case weights (normalised to mean 1).

    Returns
    -------
    ndarray, shape (k,)
    """
    mu = x[:, 1:].mean(axis=0)
    sd = x[:, 1:].std(axis=0)
    sd[sd == 0.0] = 1.0
    z = (x[:, 1:] - mu) / sd
    lr = LogisticRegression(
        C=np.inf if c is None else c, solver="newton-cholesky", max_iter=200, tol=1e-10
    )
    sw = None if w is None else w / w.mean()
    lr.fit(z, y, sample_weight=sw)
    slopes = lr.coef_[0] / sd
    intercept = float(lr.intercept_[0]) - float(slopes @ mu)
    return np.concatenate([[intercept], slopes])


def weighted_recalibration(eta: FloatArray, y: FloatArray, w: FloatArray) -> tuple[float, float]:
    """``(a, b)`` of ``logit P = a + b eta`` by weighted maximum likelihood.

    Parameters
    ----------
    eta : ndarray, shape (n,)
        Linear predictor of the ranking fit.
    y : ndarray, shape (n,)
    w : ndarray, shape (n,)
        National weights.
    """
    x = np.column_stack([np.ones_like(eta), eta])
    beta = penalised_logistic(x, y, None, w)
    return float(beta[0]), float(beta[1])


class CalibratedScore(ABC):
    """``logit P = a + b eta``: the calibrated logit and probability of a ranking score.

    Shared by the regression (:class:`Fitted`) and the bag of boosted trees
    (:class:`models.offline.field.risk_boosted.BoostedFitted`), which give
    ``eta`` and ``calibration``.
    """

    calibration: tuple[float, float]

    @abstractmethod
    def eta(self, x_all: FloatArray) -> FloatArray:
        """Ranking score of full design rows, shape (n,)."""

    def logit(self, x_all: FloatArray) -> FloatArray:
        """Calibrated logit, shape (n,)."""
        a, b = self.calibration
        out: FloatArray = a + b * self.eta(x_all)
        return out

    def probability(self, x_all: FloatArray) -> FloatArray:
        """Calibrated probability, shape (n,)."""
        return expit(self.logit(x_all))


@dataclass(frozen=True)
class Fitted(CalibratedScore):
    """A ranking fit and its weighted recalibration.

    Attributes
    ----------
    columns : tuple of int
        Indices of the design columns used.
    beta : ndarray, shape (len(columns),)
    calibration : (float, float)
        ``(a, b)``.
    """

    columns: tuple[int, ...]
    beta: FloatArray
    calibration: tuple[float, float]

    def eta(self, x_all: FloatArray) -> FloatArray:
        """Ranking linear predictor of full design rows, shape (n,)."""
        out: FloatArray = x_all[:, list(self.columns)] @ self.beta
        return out


def fit_model(
    x_all: FloatArray,
    y: FloatArray,
    w: FloatArray,
    columns: Sequence[int],
    c: float | None,
    calibrate_on: FloatArray | None = None,
) -> Fitted:
    """Ranking fit on `columns`, then the weighted recalibration.

    Parameters
    ----------
    x_all : ndarray, shape (n, K)
        Full design rows.
    y, w : ndarray, shape (n,)
    columns : sequence of int
        First must be the intercept.
    c : float or None
    calibrate_on : ndarray of bool, shape (n,), optional
        Rows the recalibration is fitted on (default all; all when those rows
        hold one outcome only, as a rare outcome's latest years may).
    """
    cols = tuple(columns)
    beta = penalised_logistic(x_all[:, list(cols)], y, c)
    eta = x_all[:, list(cols)] @ beta
    sel = np.ones(y.size, dtype=bool) if calibrate_on is None else calibrate_on
    if not (y[sel].min() < y[sel].max()):  # no positive (or negative) there: all rows
        sel = np.ones(y.size, dtype=bool)
    cal = weighted_recalibration(eta[sel], y[sel], w[sel])
    return Fitted(columns=cols, beta=beta, calibration=cal)
