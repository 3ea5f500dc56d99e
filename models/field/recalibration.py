"""Logistic recalibration of the field model's decided probability on local outcomes.

A site links outcomes (ISS 15+ or not) to the occupants the served model decided,
and refits, by weighted maximum likelihood, ::

    logit P_local = a + b logit P_served

``a`` (calibration in the large) and ``b`` (the slope; fixed at 1 when the outcomes
cannot pin it down). The served model's ranking is kept: the map is monotone
(``b > 0``), so an operating point's threshold maps through it too
(:func:`map_threshold`) and flags the same occupants, while the high tier's fixed
20 % applies to the recalibrated probability.

The minimum number of outcomes (:func:`precision_plan`)
-------------------------------------------------------
Precision required: the recalibrated observed/predicted ratio known to within a
factor of :data:`RATIO_FACTOR` (1.25) at 95 %, i.e. ``z95 SE(a) <= ln 1.25``, so
``SE(a) <= ln(1.25) / 1.96 = 0.114`` on the logit scale. The information on ``a``
is ``sum w p (1 - p)``; for a rare outcome (``p << 1``) with unit weights and a
calibrated fit (``sum p = sum y = D``) this is ``D``, the number of ISS 15+, so
``SE(a) = 1 / sqrt(D)`` and ::

    D >= (z95 / ln 1.25)^2 = 77.1,   i.e. D >= 78 linked ISS 15+ outcomes.

With unequal weights (survey weights) the sandwich variance of ``a`` is
``sum w^2 p (1-p) / (sum w p (1-p))^2``: ``D`` is replaced by the events'
effective number (Kish), ``D_eff = (sum_{y=1} w)^2 / sum_{y=1} w^2`` (equal to
``D`` for unit weights). Fewer than :data:`MIN_EFFECTIVE_EVENTS` is refused.

The slope is fitted only when it can be known to the same precision on the logit
scale, ``SE(b) <= 0.114``. Its information is about ``D_eff s^2`` with ``s^2`` the
variance of the served logit over the events (their spread is what pins the
slope), so the slope needs ``D_eff s^2 >= 77.1``; otherwise ``b = 1`` (intercept
only, an offset fit).

Checked by cross-validation by crash: folds of whole crashes (cases), each
fold's outcomes predicted by the recalibration fitted on the others.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
import numpy.typing as npt

from models.arrays import FloatArray
from models.constants import Z_95

__all__ = [
    "MIN_EFFECTIVE_EVENTS",
    "RATIO_FACTOR",
    "SE_LOGIT_REQUIRED",
    "CrossValidation",
    "PrecisionPlan",
    "Recalibration",
    "TooFewOutcomes",
    "apply_recalibration",
    "compose",
    "cross_validate",
    "fit_recalibration",
    "fold_of",
    "map_threshold",
    "precision_plan",
    "weighted_ratio",
]

#: Precision required of the recalibration: its observed/predicted ratio known within
#: this factor at 95 % (0.8-1.25, the issue's acceptance band for a recalibrated model).
RATIO_FACTOR: Final[float] = 1.25
#: Largest standard error of the intercept (and of the slope) on the logit scale:
#: ``ln(RATIO_FACTOR) / z95`` = 0.1138.
SE_LOGIT_REQUIRED: Final[float] = math.log(RATIO_FACTOR) / Z_95
#: Fewest (effective) linked ISS 15+ outcomes: ``ceil((z95 / ln 1.25)^2)`` = 78
#: (module docstring).
MIN_EFFECTIVE_EVENTS: Final[int] = math.ceil(SE_LOGIT_REQUIRED**-2)
#: Cross-validation folds (fewer when there are fewer crashes with an event).
FOLDS: Final[int] = 5
#: Newton iterations of the weighted fit; it converges in well under 20 on logit data.
_MAX_ITERATIONS: Final[int] = 50
#: Clip of probabilities before the logit (a decided probability is never 0 or 1).
_P_CLIP: Final[float] = 1e-12


class TooFewOutcomes(ValueError):
    """Too few (effective) linked ISS 15+ outcomes for the required precision."""


def _logit(p: FloatArray) -> FloatArray:
    q = np.clip(np.asarray(p, dtype=np.float64), _P_CLIP, 1.0 - _P_CLIP)
    out: FloatArray = np.log(q) - np.log1p(-q)
    return out


def _expit(x: FloatArray) -> FloatArray:
    out: FloatArray = 0.5 * (1.0 + np.tanh(0.5 * np.asarray(x, dtype=np.float64)))
    return out


@dataclass(frozen=True)
class PrecisionPlan:
    """What the outcomes allow.

    Attributes
    ----------
    events : int
        Linked ISS 15+ outcomes ``D``.
    effective_events : float
        ``D_eff``, Kish's effective number of the events' weights.
    logit_sd_events : float
        ``s``: weighted SD of the served logit over the events.
    intercept_se : float
        Expected ``SE(a) = 1 / sqrt(D_eff)``.
    slope_se : float
        Expected ``SE(b) = 1 / (s sqrt(D_eff))`` (inf when ``s`` is 0).
    method : str
        ``intercept_and_slope``, ``intercept`` or ``refused``.
    """

    events: int
    effective_events: float
    logit_sd_events: float
    intercept_se: float
    slope_se: float
    method: str

    @property
    def reason(self) -> str:
        """Why the method was chosen, with the derivation's figures."""
        need = (
            f"the required precision (observed/predicted within a factor {RATIO_FACTOR:g} at "
            f"95 %: SE(logit) <= {SE_LOGIT_REQUIRED:.3f}) needs at least "
            f"{MIN_EFFECTIVE_EVENTS} effective linked ISS 15+ outcomes"
        )
        have = f"{self.events} linked ISS 15+ ({self.effective_events:.1f} effective by weight)"
        if self.method == "refused":
            return f"too few outcomes: {have}; {need}"
        if self.method == "intercept":
            return (
                f"{have}: intercept only (the slope's expected SE {self.slope_se:.3f} exceeds "
                f"{SE_LOGIT_REQUIRED:.3f}; the events' logits spread too little)"
            )
        return f"{have}: intercept and slope (expected SEs {self.intercept_se:.3f}, " + (
            f"{self.slope_se:.3f})"
        )


def precision_plan(
    probability: npt.ArrayLike, outcome: npt.ArrayLike, weight: npt.ArrayLike
) -> PrecisionPlan:
    """Decide the recalibration's form from the outcomes (module docstring).

    Parameters
    ----------
    probability : ndarray, shape (n,)
        Decided probabilities of the linked occupants.
    outcome : ndarray of bool, shape (n,)
        ISS 15+.
    weight : ndarray, shape (n,)
        Positive weights.
    """
    y = np.asarray(outcome, dtype=bool)
    w = np.asarray(weight, dtype=np.float64)[y]
    events = int(y.sum())
    d_eff = float(w.sum() ** 2 / np.sum(w * w)) if events else 0.0
    if events:
        eta = _logit(np.asarray(probability)[y])
        mean = float(np.sum(w * eta) / w.sum())
        s = float(np.sqrt(np.sum(w * (eta - mean) ** 2) / w.sum()))
    else:
        s = 0.0
    se_a = 1.0 / math.sqrt(d_eff) if d_eff > 0 else math.inf
    se_b = 1.0 / (s * math.sqrt(d_eff)) if s > 0 and d_eff > 0 else math.inf
    if d_eff < MIN_EFFECTIVE_EVENTS:
        method = "refused"
    elif se_b <= SE_LOGIT_REQUIRED:
        method = "intercept_and_slope"
    else:
        method = "intercept"
    return PrecisionPlan(events, d_eff, s, se_a, se_b, method)


@dataclass(frozen=True)
class Recalibration:
    """``logit P_local = intercept + slope logit P_served``.

    Attributes
    ----------
    intercept, slope : float
    intercept_se, slope_se : float
        Robust (sandwich) standard errors, clustered by crash; ``slope_se`` is 0 for
        an intercept-only fit (the slope fixed at 1).
    method : str
        ``intercept_and_slope`` or ``intercept``.
    """

    intercept: float
    slope: float
    intercept_se: float
    slope_se: float
    method: str


def _newton(
    eta: FloatArray, y: FloatArray, w: FloatArray, with_slope: bool
) -> tuple[FloatArray, FloatArray]:
    """Weighted logistic MLE of ``y`` on ``[1, eta]`` (offset ``eta`` when no slope):
    the coefficients and the design."""
    x = np.column_stack([np.ones_like(eta), eta]) if with_slope else np.ones((eta.size, 1))
    offset = np.zeros_like(eta) if with_slope else eta
    beta = np.zeros(x.shape[1]) if not with_slope else np.array([0.0, 1.0])
    for _ in range(_MAX_ITERATIONS):
        p = _expit(offset + x @ beta)
        grad = x.T @ (w * (y - p))
        info = (x * (w * p * (1.0 - p))[:, None]).T @ x
        step = np.linalg.solve(info, grad)
        beta = beta + step
        if float(np.max(np.abs(step))) < 1e-10:
            break
    return beta, x


def fit_recalibration(
    probability: FloatArray,
    outcome: FloatArray,
    weight: FloatArray,
    crash: Sequence[str],
    method: str,
) -> Recalibration:
    """Weighted maximum-likelihood recalibration (deterministic: Newton from ``a=0, b=1``).

    Parameters
    ----------
    probability : ndarray, shape (n,)
        The served decided probabilities.
    outcome : ndarray, shape (n,)
        1 ISS 15+, else 0.
    weight : ndarray, shape (n,)
    crash : sequence of str, length n
        Each occupant's crash (case) id: the clusters of the robust SEs.
    method : str
        ``intercept_and_slope`` or ``intercept`` (:func:`precision_plan`).
    """
    if method not in ("intercept_and_slope", "intercept"):
        raise ValueError(f"method must be intercept_and_slope or intercept, not {method!r}")
    eta = _logit(probability)
    y = np.asarray(outcome, dtype=np.float64)
    w = np.asarray(weight, dtype=np.float64)
    with_slope = method == "intercept_and_slope"
    beta, x = _newton(eta, y, w, with_slope)
    offset = np.zeros_like(eta) if with_slope else eta
    p = _expit(offset + x @ beta)
    bread = np.linalg.inv((x * (w * p * (1.0 - p))[:, None]).T @ x)
    scores = x * (w * (y - p))[:, None]
    _, cluster = np.unique(np.asarray(crash, dtype=object).astype(str), return_inverse=True)
    summed = np.zeros((int(cluster.max()) + 1 if cluster.size else 0, x.shape[1]))
    np.add.at(summed, cluster, scores)
    cov = bread @ (summed.T @ summed) @ bread
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    if with_slope:
        return Recalibration(float(beta[0]), float(beta[1]), float(se[0]), float(se[1]), method)
    return Recalibration(float(beta[0]), 1.0, float(se[0]), 0.0, method)


def apply_recalibration(probability: FloatArray, intercept: float, slope: float) -> FloatArray:
    """``expit(intercept + slope logit p)`` of probabilities of any shape."""
    return _expit(intercept + slope * _logit(probability))


def map_threshold(threshold: float, intercept: float, slope: float) -> float:
    """An operating threshold on the served probability mapped onto the recalibrated one.

    The map is increasing (``slope > 0``), so ``p >= t`` exactly when
    ``recal(p) >= recal(t)``: the operating point flags the same occupants and keeps
    its promise (a sensitivity found on held-out national data, ranking-based).
    """
    return float(apply_recalibration(np.array(threshold), intercept, slope))


def compose(first: tuple[float, float], then: tuple[float, float]) -> tuple[float, float]:
    """``then`` applied after ``first`` as one map: ``(a2 + b2 a1, b2 b1)``."""
    a1, b1 = first
    a2, b2 = then
    return a2 + b2 * a1, b2 * b1


def weighted_ratio(probability: FloatArray, outcome: FloatArray, weight: FloatArray) -> float:
    """Weighted predicted / observed ISS 15+ (inf with no event)."""
    w = np.asarray(weight, dtype=np.float64)
    observed = float(np.sum(w * np.asarray(outcome, dtype=np.float64)))
    predicted = float(np.sum(w * np.asarray(probability, dtype=np.float64)))
    return predicted / observed if observed > 0 else math.inf


def fold_of(crash_id: str, folds: int) -> int:
    """A crash's fold: its id's SHA-256 modulo `folds` (deterministic, no seed)."""
    return int(hashlib.sha256(crash_id.encode()).hexdigest(), 16) % folds


@dataclass(frozen=True)
class CrossValidation:
    """Held-out figures of the recalibration, folds by crash.

    Attributes
    ----------
    folds : int
    served_ratio, recalibrated_ratio : float
        Weighted predicted/observed over the held-out predictions.
    served_log_loss, recalibrated_log_loss : float
        Weighted mean log loss, nats.
    """

    folds: int
    served_ratio: float
    recalibrated_ratio: float
    served_log_loss: float
    recalibrated_log_loss: float

    @property
    def improves(self) -> bool:
        """The recalibration's held-out log loss is lower than the served model's."""
        return self.recalibrated_log_loss < self.served_log_loss


def _log_loss(p: FloatArray, y: FloatArray, w: FloatArray) -> float:
    q = np.clip(p, _P_CLIP, 1.0 - _P_CLIP)
    return float(-np.sum(w * (y * np.log(q) + (1.0 - y) * np.log1p(-q))) / np.sum(w))


def cross_validate(
    probability: FloatArray,
    outcome: FloatArray,
    weight: FloatArray,
    crash: Sequence[str],
    method: str,
    folds: int = FOLDS,
) -> CrossValidation:
    """Held-out predictions of the recalibration, `folds` folds of whole crashes.

    A fold with no event in its training part keeps the served probabilities (none
    is fitted there). Raises ValueError with fewer than 2 crashes.
    """
    p = np.asarray(probability, dtype=np.float64)
    y = np.asarray(outcome, dtype=np.float64)
    w = np.asarray(weight, dtype=np.float64)
    k = min(folds, len(set(crash)))
    if k < 2:
        raise ValueError("cross-validation needs at least 2 crashes")
    fold = np.array([fold_of(c, k) for c in crash])
    held = p.copy()
    for f in range(k):
        test, train = fold == f, fold != f
        if not test.any() or y[train].sum() == 0:
            continue
        r = fit_recalibration(
            p[train],
            y[train],
            w[train],
            [c for c, t in zip(crash, train, strict=True) if t],
            method,
        )
        held[test] = apply_recalibration(p[test], r.intercept, r.slope)
    return CrossValidation(
        folds=k,
        served_ratio=weighted_ratio(p, y, w),
        recalibrated_ratio=weighted_ratio(held, y, w),
        served_log_loss=_log_loss(p, y, w),
        recalibrated_log_loss=_log_loss(held, y, w),
    )
