"""Held-out figures of a probability with bootstrap-by-crash intervals.

Every figure is computed on held-out predictions and given unweighted (the
NASS-CDS sample) and weighted by ``ratwgt`` (US towaway crashes). Intervals
are percentile intervals over resamples of whole crashes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.metrics import roc_auc_score

from models.arrays import FloatArray, IntArray
from models.offline.field.risk_core import logit, weighted_recalibration

__all__ = [
    "target_with_margin",
    "TIER_ORDER",
    "crash_resamples",
    "score",
    "threshold_figures",
    "tier_figures",
    "triage_figures",
]

#: The risk tiers, highest first (``models.tiers``).
TIER_ORDER = ("high", "moderate", "none")


def crash_resamples(crash: IntArray, n: int, seed: int) -> list[IntArray]:
    """Row indices of `n` resamples of whole crashes."""
    order = np.argsort(crash, kind="mergesort")
    ids, start, counts = np.unique(crash[order], return_index=True, return_counts=True)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        pick = rng.integers(0, ids.size, ids.size)
        s, c = start[pick], counts[pick]
        total = int(c.sum())
        offsets = np.repeat(s - np.concatenate([[0], np.cumsum(c)[:-1]]), c)
        out.append(order[np.arange(total) + offsets].astype(np.int32))
    return out


def _auc(y: FloatArray, p: FloatArray, w: FloatArray | None) -> float:
    if y.size == 0 or y.min() == y.max():
        return float("nan")
    return float(roc_auc_score(y, p, sample_weight=w))


def _slope(y: FloatArray, p: FloatArray, w: FloatArray) -> float:
    if y.size == 0 or y.min() == y.max():
        return float("nan")
    return weighted_recalibration(logit(p), y, w)[1]


def _ci(values: Sequence[float]) -> list[float]:
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return [float("nan"), float("nan")]
    lo, hi = np.percentile(v, [2.5, 97.5])
    return [float(lo), float(hi)]


def score(
    y: FloatArray,
    p: FloatArray,
    w: FloatArray,
    resamples: Sequence[IntArray] | None,
    mask: np.ndarray | None = None,
    calibration: bool = True,
) -> dict[str, Any]:
    """AUC (unweighted, weighted), predicted/observed and calibration slope, with CIs.

    Parameters
    ----------
    y, p, w : ndarray, shape (n,)
    resamples : sequence of index arrays, or None (no intervals)
    mask : ndarray of bool, shape (n,), optional
        A subgroup.
    calibration : bool
        Whether `p` is a probability of `y` (P/O and slope reported).
    """
    sel = np.ones(y.size, dtype=bool) if mask is None else mask

    def figures(ix: np.ndarray) -> dict[str, float]:
        yy, pp, ww = y[ix], p[ix], w[ix]
        if yy.size == 0:
            return {
                k: float("nan") for k in ("auc", "auc_weighted", "p_over_o_weighted", "p_over_o")
            }
        out = {"auc": _auc(yy, pp, None), "auc_weighted": _auc(yy, pp, ww)}
        if calibration:
            obs_w, obs = float((ww * yy).sum()), float(yy.sum())
            nan = float("nan")
            out["p_over_o_weighted"] = float((ww * pp).sum()) / obs_w if obs_w > 0 else nan
            out["p_over_o"] = float(pp.sum()) / obs if obs > 0 else nan
        return out

    point = figures(np.flatnonzero(sel))
    res: dict[str, Any] = {
        "n": int(sel.sum()),
        "positives": int(y[sel].sum()),
        "observed_weighted": float(np.average(y[sel], weights=w[sel])),
        **point,
    }
    if calibration:
        res["slope_weighted"] = _slope(y[sel], p[sel], w[sel])
        res["predicted_weighted"] = float(np.average(p[sel], weights=w[sel]))
    if resamples is not None:
        reps = [figures(ix[sel[ix]]) for ix in resamples]
        for k in point:
            res[f"{k}_ci95"] = _ci([r[k] for r in reps])
        if calibration:
            res["slope_weighted_ci95"] = _ci(
                [_slope(y[ix[sel[ix]]], p[ix[sel[ix]]], w[ix[sel[ix]]]) for ix in resamples[:50]]
            )
    return res


def triage_figures(
    y: FloatArray, flagged: np.ndarray, w: FloatArray, resamples: Sequence[IntArray] | None
) -> dict[str, Any]:
    """Sensitivity and flagged share, unweighted and weighted, with CIs."""

    def figures(ix: np.ndarray) -> dict[str, float]:
        yy, ff, ww = y[ix] > 0, flagged[ix], w[ix]
        return {
            "sensitivity": float(ff[yy].mean()),
            "sensitivity_weighted": float(ww[ff & yy].sum() / ww[yy].sum()),
            "flagged": float(ff.mean()),
            "flagged_weighted": float(ww[ff].sum() / ww.sum()),
            "ppv": float(yy[ff].mean()) if ff.any() else float("nan"),
        }

    out: dict[str, Any] = figures(np.arange(y.size))
    if resamples is not None:
        reps = [figures(ix) for ix in resamples]
        for k in list(out):
            out[f"{k}_ci95"] = _ci([r[k] for r in reps])
    return out


def _ratio(num: float, den: float) -> float:
    return num / den if den > 0 else float("nan")


def tier_figures(
    y: FloatArray,
    p: FloatArray,
    flagged: np.ndarray,
    w: FloatArray,
    high_threshold: float,
    resamples: Sequence[IntArray] | None,
) -> dict[str, Any]:
    """Held-out figures of each risk tier, unweighted (the sample) and weighted, with CIs.

    The tiers as served (``models.tiers.tier_of``): ``high`` = flagged at the operating
    point and ``p >= high_threshold``; ``moderate`` = flagged, below it; ``none`` = not
    flagged.

    Parameters
    ----------
    y, p, w : ndarray, shape (n,)
        Outcome (ISS 15+), held-out probability, survey weight.
    flagged : ndarray of bool, shape (n,)
        Held-out flags of the operating point.
    high_threshold : float
    resamples : sequence of index arrays, or None (no intervals)

    Returns
    -------
    dict
        Per tier: ``n`` and ``positives`` (the sample's counts); ``sensitivity`` and
        ``sensitivity_weighted``: the share of ISS 15+ occupants in the tier;
        ``sensitivity_at_or_above`` (and weighted): in the tier or a higher one;
        ``ppv``, ``ppv_weighted``: the share of the tier's occupants ISS 15+;
        ``flagged``, ``flagged_weighted``: the tier's share of all occupants (of the
        sample; weighted: of US towaway-crash occupants). Each with ``_ci95``.
    """
    flagged = np.asarray(flagged, dtype=bool)
    high = flagged & (p >= high_threshold)
    members = {"high": high, "moderate": flagged & ~high, "none": ~flagged}
    at_or_above = {"high": high, "moderate": flagged, "none": np.ones(y.size, dtype=bool)}

    def figures(ix: np.ndarray, tier: str) -> dict[str, float]:
        yy, ww = y[ix] > 0, w[ix]
        m, up = members[tier][ix], at_or_above[tier][ix]
        return {
            "sensitivity": _ratio(float((m & yy).sum()), float(yy.sum())),
            "sensitivity_weighted": _ratio(float(ww[m & yy].sum()), float(ww[yy].sum())),
            "sensitivity_at_or_above": _ratio(float((up & yy).sum()), float(yy.sum())),
            "sensitivity_at_or_above_weighted": _ratio(
                float(ww[up & yy].sum()), float(ww[yy].sum())
            ),
            "ppv": _ratio(float((m & yy).sum()), float(m.sum())),
            "ppv_weighted": _ratio(float(ww[m & yy].sum()), float(ww[m].sum())),
            "flagged": _ratio(float(m.sum()), float(m.size)),
            "flagged_weighted": _ratio(float(ww[m].sum()), float(ww.sum())),
        }

    everyone = np.arange(y.size)
    out: dict[str, Any] = {}
    for tier in TIER_ORDER:
        res: dict[str, Any] = {
            "n": int(members[tier].sum()),
            "positives": int((members[tier] & (y > 0)).sum()),
            **figures(everyone, tier),
        }
        if resamples is not None:
            reps = [figures(ix, tier) for ix in resamples]
            for k in list(res):
                if k not in ("n", "positives"):
                    res[f"{k}_ci95"] = _ci([r[k] for r in reps])
        out[tier] = res
    return out


def threshold_figures(
    y: FloatArray,
    p: FloatArray,
    w: FloatArray,
    threshold: float,
    resamples: Sequence[IntArray] | None,
) -> dict[str, Any]:
    """Sensitivity, specificity, PPV and flagged share of ``p >= threshold``, unweighted and
    weighted, with CIs (the vehicle answer at the CDC panel's 0.20, beside OnStar's ISP)."""
    flagged = p >= threshold

    def figures(ix: np.ndarray) -> dict[str, float]:
        yy, ff, ww = y[ix] > 0, flagged[ix], w[ix]
        return {
            "sensitivity": _ratio(float((ff & yy).sum()), float(yy.sum())),
            "sensitivity_weighted": _ratio(float(ww[ff & yy].sum()), float(ww[yy].sum())),
            "specificity": _ratio(float((~ff & ~yy).sum()), float((~yy).sum())),
            "specificity_weighted": _ratio(float(ww[~ff & ~yy].sum()), float(ww[~yy].sum())),
            "ppv": _ratio(float((ff & yy).sum()), float(ff.sum())),
            "ppv_weighted": _ratio(float(ww[ff & yy].sum()), float(ww[ff].sum())),
            "flagged_weighted": _ratio(float(ww[ff].sum()), float(ww.sum())),
        }

    out: dict[str, Any] = {
        "threshold": threshold,
        "n": int(y.size),
        "positives": int((y > 0).sum()),
        **figures(np.arange(y.size)),
    }
    if resamples is not None:
        reps = [figures(ix) for ix in resamples]
        for k in list(out):
            if k not in ("threshold", "n", "positives"):
                out[f"{k}_ci95"] = _ci([r[k] for r in reps])
    return out


def target_with_margin(requirement: float, positives: float) -> float:
    """Sensitivity a threshold is set for: the requirement plus one binomial standard error.

    [R] The requirement (e.g. >= 0.85) must hold on held-out occupants; a
    threshold set exactly at it on one sample misses it on another half of the
    time. The margin is one standard error of a sensitivity over `positives`
    occupants: those the held-out check counts (every positive of the fit, each
    held out once). Until 2026-12-06 it was one fold's positives (a fifth:
    a margin 2.2 times as wide, 0.864 instead of 0.856), wider than the check
    that the requirement is stated on; the model card gives the figures at both.
    """
    return requirement + math.sqrt(requirement * (1.0 - requirement) / positives)
