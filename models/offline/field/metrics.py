"""Figures of a risk score against real outcomes: AUC, calibration, triage rates, with CIs.

Used by the field model's fit (on cross-validated predictions) and by
``aacn-triage evaluate`` (on the service's answers to any labelled file), so
both report the same figures the same way. All functions take plain arrays:
``y`` (0/1 outcome, shape (n,)), ``p`` (probability, shape (n,)) and optional
``w`` (case weights, shape (n,); None: equal).

The AUC is scikit-learn's (ties count half), weighted when weights are given;
the calibration slope and intercept are statsmodels GLM fits; confidence
intervals are percentile intervals over bootstrap resamples of the rows,
stratified by outcome so that every resample has both classes.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import statsmodels.api as sm
from sklearn.metrics import roc_auc_score

from models.arrays import FloatArray, IntArray

__all__ = [
    "Calibration",
    "TriageRates",
    "auc",
    "bootstrap_ci",
    "calibration",
    "stratified_bootstrap_indices",
    "threshold_for_sensitivity",
    "triage_rates",
]


#: Probabilities are clipped to [EPS, 1 - EPS] before taking a logit.
_EPS = 1e-9


def auc(y: npt.ArrayLike, score: npt.ArrayLike, w: npt.ArrayLike | None = None) -> float:
    """Area under the ROC curve (scikit-learn), weighted when `w` is given.

    Parameters
    ----------
    y : array_like, shape (n,)
        0/1 outcome.
    score : array_like, shape (n,)
        Higher means more likely positive.
    w : array_like, shape (n,), optional
        Case weights.

    Returns
    -------
    float
        NaN when one class is absent.
    """
    yy = np.asarray(y, dtype=bool)
    if yy.all() or not yy.any():
        return float("nan")
    return float(roc_auc_score(yy, np.asarray(score, dtype=np.float64), sample_weight=w))


@dataclass(frozen=True)
class Calibration:
    """Calibration of probabilities against outcomes.

    Attributes
    ----------
    intercept : float
        Calibration in the large: ``a`` of ``logit P(y) = a + logit p`` (0 ideal).
    slope : float
        ``b`` of ``logit P(y) = a' + b logit p`` (1 ideal; < 1 too extreme).
    brier : float
        Mean squared error of `p`.
    observed : float
        Outcome rate.
    expected : float
        Mean of `p`.
    """

    intercept: float
    slope: float
    brier: float
    observed: float
    expected: float


def _logit(p: FloatArray) -> FloatArray:
    q = np.clip(p, _EPS, 1.0 - _EPS)
    return np.asarray(np.log(q / (1.0 - q)), dtype=np.float64)


def _logistic_fit(y: FloatArray, lp: FloatArray, w: FloatArray, slope_free: bool) -> float:
    """Maximum likelihood intercept (offset `lp`) or slope (on `lp`) of a logistic model."""
    if slope_free:
        x = np.column_stack([np.ones_like(lp), lp])
        fit = sm.GLM(y, x, family=sm.families.Binomial(), var_weights=w).fit()
        return float(fit.params[1])
    x = np.ones((lp.size, 1))
    fit = sm.GLM(y, x, family=sm.families.Binomial(), offset=lp, var_weights=w).fit()
    return float(fit.params[0])


def calibration(y: npt.ArrayLike, p: npt.ArrayLike, w: npt.ArrayLike | None = None) -> Calibration:
    """Calibration intercept, slope and Brier score (weighted when `w` is given)."""
    yy = np.asarray(y, dtype=np.float64)
    pp = np.asarray(p, dtype=np.float64)
    ww = np.ones_like(yy) if w is None else np.asarray(w, dtype=np.float64)
    lp = _logit(pp)
    a = _logistic_fit(yy, lp, ww, slope_free=False)
    b = _logistic_fit(yy, lp, ww, slope_free=True)
    return Calibration(
        intercept=a,
        slope=b,
        brier=float(np.average((pp - yy) ** 2, weights=ww)),
        observed=float(np.average(yy, weights=ww)),
        expected=float(np.average(pp, weights=ww)),
    )


@dataclass(frozen=True)
class TriageRates:
    """A decision rule against outcomes.

    Attributes
    ----------
    sensitivity : float
        Share of the positives flagged (1 - under-triage).
    flagged : float
        Share of all occupants flagged.
    ppv : float
        Share of the flagged that are positive (over-triage = 1 - PPV); NaN if
        none is flagged.
    specificity : float
    n : int
    positives : int
    """

    sensitivity: float
    flagged: float
    ppv: float
    specificity: float
    n: int
    positives: int

    @property
    def over_triage(self) -> float:
        """1 - PPV: share of the flagged that are not positive."""
        return 1.0 - self.ppv


def triage_rates(
    y: npt.ArrayLike, flagged: npt.ArrayLike, w: npt.ArrayLike | None = None
) -> TriageRates:
    """Sensitivity, flagged share, PPV and specificity of a 0/1 flag (weighted if `w`)."""
    yy = np.asarray(y, dtype=bool)
    ff = np.asarray(flagged, dtype=bool)
    ww = np.ones(yy.size) if w is None else np.asarray(w, dtype=np.float64)
    pos, neg = ww[yy].sum(), ww[~yy].sum()
    fl = ww[ff].sum()
    tp = ww[ff & yy].sum()
    return TriageRates(
        sensitivity=float(tp / pos) if pos > 0 else float("nan"),
        flagged=float(fl / ww.sum()) if ww.sum() > 0 else float("nan"),
        ppv=float(tp / fl) if fl > 0 else float("nan"),
        specificity=float(ww[~ff & ~yy].sum() / neg) if neg > 0 else float("nan"),
        n=int(yy.size),
        positives=int(yy.sum()),
    )


def threshold_for_sensitivity(
    y: npt.ArrayLike, p: npt.ArrayLike, target: float, w: npt.ArrayLike | None = None
) -> float:
    """The largest threshold t with sensitivity of ``p >= t`` at least `target`.

    The largest such t flags the fewest occupants among the thresholds that
    reach the target.

    Parameters
    ----------
    y, p : array_like, shape (n,)
    target : float
        Sensitivity to reach, in (0, 1].
    w : array_like, shape (n,), optional

    Returns
    -------
    float
        A probability of a positive row (flag ``p >= t``).

    Raises
    ------
    ValueError
        No positive rows.
    """
    yy = np.asarray(y, dtype=bool)
    pp = np.asarray(p, dtype=np.float64)
    ww = np.ones(yy.size) if w is None else np.asarray(w, dtype=np.float64)
    if not yy.any():
        raise ValueError("no positive rows: no threshold reaches a sensitivity")
    pos_p = pp[yy]
    pos_w = ww[yy]
    order = np.argsort(-pos_p, kind="mergesort")
    cum = np.cumsum(pos_w[order]) / pos_w.sum()
    k = int(np.searchsorted(cum, target - 1e-12))
    k = min(k, order.size - 1)
    return float(pos_p[order][k])


def stratified_bootstrap_indices(
    y: npt.ArrayLike, n_boot: int, seed: int, groups: npt.ArrayLike | None = None
) -> list[IntArray]:
    """Row indices of `n_boot` bootstrap resamples, stratified by outcome.

    Parameters
    ----------
    y : array_like, shape (n,)
    n_boot : int
    seed : int
    groups : array_like, shape (n,), optional
        Cluster ids: when given, whole clusters are resampled (no stratification).

    Returns
    -------
    list of ndarray
    """
    yy = np.asarray(y, dtype=bool)
    rng = np.random.default_rng(seed)
    out = []
    if groups is not None:
        g = np.asarray(groups)
        ids, inverse = np.unique(g, return_inverse=True)
        members = [np.flatnonzero(inverse == k) for k in range(ids.size)]
        for _ in range(n_boot):
            pick = rng.integers(0, ids.size, ids.size)
            out.append(np.concatenate([members[k] for k in pick]).astype(np.int64))
        return out
    pos, neg = np.flatnonzero(yy), np.flatnonzero(~yy)
    for _ in range(n_boot):
        out.append(
            np.concatenate(
                [rng.choice(pos, pos.size, replace=True), rng.choice(neg, neg.size, replace=True)]
            ).astype(np.int64)
        )
    return out


def bootstrap_ci(
    statistic: Callable[[IntArray], float],
    indices: Sequence[IntArray],
    level: float = 0.95,
) -> tuple[float, float]:
    """Percentile interval of `statistic` over bootstrap resamples (NaNs dropped).

    Parameters
    ----------
    statistic : callable
        Takes the row indices of one resample, returns a number.
    indices : sequence of ndarray
        From :func:`stratified_bootstrap_indices`.
    level : float
    """
    values = np.array([statistic(ix) for ix in indices], dtype=np.float64)
    values = values[np.isfinite(values)]
    if values.size == 0:
        return (float("nan"), float("nan"))
    lo, hi = np.percentile(values, [50.0 * (1.0 - level), 50.0 * (1.0 + level)])
    return (float(lo), float(hi))
