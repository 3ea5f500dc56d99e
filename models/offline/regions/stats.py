"""Figures of a score against a region outcome, with intervals from a bootstrap by crash.

NASS-CDS samples crashes, and the occupants of one crash share it: every
interval here resamples whole crashes (``year, psu, caseno``) with replacement
and keeps each row's survey weight (``ratwgt``) times the number of times its
crash was drawn. Percentile intervals. The AUC is scikit-learn's (ties count
half), survey-weighted unless said otherwise.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Final

import numpy as np
import pandas as pd
from sklearn.metrics import roc_auc_score

from models.arrays import FloatArray, IntArray

__all__ = [
    "BOOTSTRAP_REPLICATES",
    "BOOTSTRAP_SEED",
    "CrashBootstrap",
    "Interval",
    "crash_ids",
    "weighted_auc",
]

#: Crash resamples of every interval. [R] 200 keep the whole report to about a
#: minute on one core; the 95 % bounds of an AUC move by about 0.005 between
#: seeds at this size (measured on the head row, seeds 1-3).
BOOTSTRAP_REPLICATES: Final[int] = 200
#: Seed of the crash bootstrap, fixed so that the report is reproduced exactly.
BOOTSTRAP_SEED: Final[int] = 20261206


def crash_ids(frame: pd.DataFrame) -> IntArray:
    """An integer per crash (year, psu, caseno), the unit of resampling and of folds."""
    codes, _ = pd.factorize(
        frame["year"].astype(str)
        + ":"
        + frame["psu"].astype(str)
        + ":"
        + frame["caseno"].astype(str)
    )
    return np.asarray(codes, dtype=np.int64)


def weighted_auc(y: FloatArray, score: FloatArray, w: FloatArray | None) -> float:
    """AUC of `score` for the 0/1 outcome `y`; NaN when a class is absent or weightless."""
    yy = y > 0.5
    if w is not None:
        if not (w[yy].sum() > 0 and w[~yy].sum() > 0):
            return float("nan")
        keep = w > 0
        return float(roc_auc_score(yy[keep], score[keep], sample_weight=w[keep]))
    if yy.all() or not yy.any():
        return float("nan")
    return float(roc_auc_score(yy, score))


@dataclass(frozen=True)
class Interval:
    """A point estimate and its 95 % bootstrap interval."""

    value: float
    low: float
    high: float

    def text(self, fmt: str = "{:.3f}") -> str:
        """``value [low, high]``."""
        return f"{fmt.format(self.value)} [{fmt.format(self.low)}, {fmt.format(self.high)}]"


class CrashBootstrap:
    """Crash-resampled weights for a fixed set of rows.

    Parameters
    ----------
    crash : ndarray of int, shape (n,)
        Crash of each row.
    weight : ndarray, shape (n,)
        Survey weight of each row.
    replicates, seed : int
    """

    def __init__(
        self,
        crash: IntArray,
        weight: FloatArray,
        replicates: int = BOOTSTRAP_REPLICATES,
        seed: int = BOOTSTRAP_SEED,
    ) -> None:
        _, inverse = np.unique(crash, return_inverse=True)
        n_crash = int(inverse.max()) + 1
        rng = np.random.default_rng(seed)
        counts = rng.multinomial(n_crash, np.full(n_crash, 1.0 / n_crash), size=replicates)
        self._counts = counts[:, inverse].astype(np.float64)  # (replicates, n)
        self.weight = weight

    def weights(self, survey: bool = True) -> FloatArray:
        """Per replicate, each row's weight: shape (replicates, n)."""
        return self._counts * self.weight if survey else self._counts

    def interval(
        self,
        statistic: Callable[[FloatArray], float],
        survey: bool = True,
    ) -> Interval:
        """`statistic(w)` at the rows' weights and its percentile interval.

        Parameters
        ----------
        statistic : callable
            Of a weight vector, shape (n,).
        survey : bool
            Multiply by the survey weights (else each row weighs its draw count).
        """
        base = self.weight if survey else np.ones_like(self.weight)
        point = statistic(base)
        reps = np.array([statistic(w) for w in self.weights(survey)])
        reps = reps[np.isfinite(reps)]
        if reps.size == 0:
            return Interval(point, float("nan"), float("nan"))
        lo, hi = np.percentile(reps, [2.5, 97.5])
        return Interval(point, float(lo), float(hi))
