"""Held-out figures of a probability with bootstrap-by-crash intervals.

Every figure is computed on held-out predictions and given unweighted (the
NASS-CDS sample) and weighted by ``ratwgt`` (US towaway crashes). Intervals
are percentile intervals over resamples of whole crashes.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from sklearn.metrics import roc_auc_score

from models.arrays import FloatArray, IntArray
from models.offline.field.risk_core import logit, weighted_recalibration

__all__ = ["crash_resamples", "score", "triage_figures"]


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
