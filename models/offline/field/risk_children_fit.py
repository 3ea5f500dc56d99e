"""The children's calibration of the decision, fitted and chosen held out by crash.

The served form is :mod:`models.field.children_calibration`: on a child's row,
``logit P = a + b * logit P_shared + c . z`` with ``z`` the age groups 5-9 and
10-15 (0-4 the reference) and the child seat, by weighted maximum likelihood
with the national weights. Here:

- **cross-fitted**: each fold's children are calibrated with the coefficients
  fitted on the other folds' children's held-out logits, so the children's
  held-out probability never saw its own outcome;
- **the choice** (the model card's "Children" table): three ways of modelling
  children, each calibrated alike (by age group and child seat, with the
  weights), compared on the children held out by the weighted log loss (the
  population the answer is for is the weighted one): the shared model with
  child terms (the decision), a regression of the same groups fitted on
  children alone, and the plain regression fitted on children; the shared
  model as fitted (the national recalibration only) is reported beside them;
- **served**: the coefficients fitted on every child's held-out logit of the
  shared model, and one set per refit of the decision, each on a resample of
  the children's crashes (the interval then carries the calibration's
  uncertainty).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from scipy.linalg import LinAlgWarning
from scipy.special import expit

from models.arrays import FloatArray, IntArray
from models.field.children_calibration import CHILDREN_CALIBRATION_TERMS, ChildrenCalibration
from models.field.risk_children import ALL_COLUMNS_3, CHILD_GROUPS
from models.offline.field.risk_core import fit_model, logit, penalised_logistic
from models.offline.field.risk_fit import AnyFitted, RiskConfig, RiskData, Spec, fit_spec
from models.offline.field.risk_metrics import crash_resamples, score

__all__ = [
    "ChildrenAware",
    "children_calibration_of",
    "children_stage",
    "weighted_log_loss",
]

_TERMS: Final[list[int]] = [ALL_COLUMNS_3.index(t) for t in CHILDREN_CALIBRATION_TERMS]
_AGE_GROUPS: Final[list[int]] = [
    ALL_COLUMNS_3.index(c) for c in ("age_0_4", "age_5_9", "age_10_15")
]

#: Seed offset of the resamples behind the served calibration's refits.
_BOOT_SEED: Final[int] = 47


def weighted_log_loss(y: FloatArray, p: FloatArray, w: FloatArray) -> float:
    """Weighted mean negative log likelihood (the national weights)."""
    q = np.clip(p, 1e-12, 1.0 - 1e-12)
    ll = -(y * np.log(q) + (1.0 - y) * np.log1p(-q))
    return float(np.sum(w * ll) / np.sum(w))


def _design(eta: FloatArray, x: FloatArray) -> FloatArray:
    return np.column_stack([np.ones_like(eta), eta, x[:, _TERMS]])


def _fit(eta: FloatArray, x: FloatArray, y: FloatArray, w: FloatArray) -> FloatArray:
    """``(a, b, c)`` by weighted maximum likelihood, unpenalised."""
    return penalised_logistic(_design(eta, x), y, None, w)


def _apply(coef: FloatArray, eta: FloatArray, x: FloatArray) -> FloatArray:
    out: FloatArray = _design(eta, x) @ coef
    return out


def _cross_fitted(
    eta: FloatArray,
    d: RiskData,
    y: FloatArray,
    child: np.ndarray,
    folds: Sequence[tuple[IntArray, IntArray]],
) -> tuple[FloatArray, list[FloatArray]]:
    """Calibrated held-out P of the children (NaN elsewhere) and each fold's coefficients."""
    p = np.full(y.size, np.nan)
    coefs = []
    for tr, te in folds:
        tr, te = tr[child[tr]], te[child[te]]
        coef = _fit(eta[tr], d.x[tr], y[tr], d.w[tr])
        p[te] = expit(_apply(coef, eta[te], d.x[te]))
        coefs.append(coef)
    return p, coefs


@dataclass(frozen=True)
class ChildrenAware:
    """A fitted decision with the children's calibration on its child rows (as served)."""

    fitted: AnyFitted
    coefficients: FloatArray

    def probability(self, x_all: FloatArray) -> FloatArray:
        """P(ISS 15+) of full design rows, shape (n,)."""
        p = self.fitted.probability(x_all)
        child = x_all[:, _AGE_GROUPS].sum(axis=1) > 0.5
        if child.any():
            p = p.copy()
            p[child] = expit(_apply(self.coefficients, logit(p[child]), x_all[child]))
        return p


def _oof_logit(
    fit: Callable[[IntArray], AnyFitted],
    d: RiskData,
    folds: Sequence[tuple[IntArray, IntArray]],
    child: np.ndarray,
    reference_year: Callable[[IntArray], float],
) -> FloatArray:
    """Held-out calibrated logit of the children of a model fitted on children alone."""
    year_col = ALL_COLUMNS_3.index("accident_year")
    eta = np.full(d.x.shape[0], np.nan)
    for tr, te in folds:
        trc, tec = tr[child[tr]], te[child[te]]
        f = fit(trc)
        x = d.x[tec].copy()
        x[:, year_col] = reference_year(tr)
        eta[tec] = logit(f.probability(x))
    return eta


def _figures(
    y: FloatArray, p: FloatArray, w: FloatArray, groups: dict[str, np.ndarray]
) -> dict[str, Any]:
    child = groups["children"]
    out: dict[str, Any] = {
        "log_loss": float(np.mean(_ll(y[child], p[child]))),
        "log_loss_weighted": weighted_log_loss(y[child], p[child], w[child]),
        **score(y[child], p[child], w[child], None),
    }
    out["p_over_o_weighted_by_group"] = {
        name: float(np.sum(w[m] * p[m]) / np.sum(w[m] * y[m]))
        for name, m in groups.items()
        if name != "children" and np.sum(w[m] * y[m]) > 0
    }
    return out


def _ll(y: FloatArray, p: FloatArray) -> FloatArray:
    q = np.clip(p, 1e-12, 1.0 - 1e-12)
    out: FloatArray = -(y * np.log(q) + (1.0 - y) * np.log1p(-q))
    return out


def children_stage(
    d: RiskData,
    y: FloatArray,
    shared_oof: FloatArray,
    spec: Spec,
    folds: Sequence[tuple[IntArray, IntArray]],
    cfg: RiskConfig,
    plain_columns: Sequence[str],
    groups: dict[str, np.ndarray],
) -> dict[str, Any]:
    """The children's calibration, its cross-fitted held-out P and the choice (module docstring).

    Parameters
    ----------
    d : RiskData
    y : ndarray, shape (n,)
        ISS 15+.
    shared_oof : ndarray, shape (n,)
        The decision's held-out P (each fold's model), as fitted.
    spec : Spec
        The decision's.
    folds : sequence of (train, test)
    cfg : RiskConfig
    plain_columns : sequence of str
        The plain regression's columns (the children's plain one adds the child
        columns).
    groups : dict of str to ndarray of bool, shape (n,)
        ``children`` and its subgroups (the figures' P/O by group).

    Returns
    -------
    dict
        ``oof`` (n,): the decision's held-out P with the children's rows
        cross-fitted; ``fold_coefficients`` (one (2 + T,) per fold);
        ``coefficients`` (2 + T,) and ``bootstrap_coefficients`` (B, 2 + T) served;
        ``choice``: the figures of each way and the chosen one.
    """
    child = groups["children"]
    eta = logit(shared_oof)
    calibrated, coefs = _cross_fitted(eta, d, y, child, folds)
    oof = shared_oof.copy()
    oof[child] = calibrated[child]

    def year(tr: IntArray) -> float:
        return float(d.year[tr].max())

    logistic = spec.part("logistic") if spec.kind == "blend" else spec
    if logistic.kind != "logistic":
        logistic = Spec(spec.groups, spec.c, spec.drift)
    separate = _oof_logit(lambda tr: fit_spec(d, y, tr, logistic, cfg), d, folds, child, year)
    child_cols = [
        ALL_COLUMNS_3.index(c)
        for c in (*plain_columns, *(c for cols in CHILD_GROUPS.values() for c in cols))
    ]

    def plain_fit(tr: IntArray) -> AnyFitted:
        # columns constant among the training children (the clamped age) are dropped
        cols = [c for c in child_cols if c == 0 or np.ptp(d.x[tr, c]) > 0]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", LinAlgWarning)
            return fit_model(d.x[tr], y[tr], d.w[tr], cols, None)

    plain = _oof_logit(plain_fit, d, folds, child, year)
    ways = {
        "shared_with_child_terms": oof,
        "separate_regression": _cross_fitted(separate, d, y, child, folds)[0],
        "plain_regression_on_children": _cross_fitted(plain, d, y, child, folds)[0],
    }
    choice: dict[str, Any] = {k: _figures(y, p, d.w, groups) for k, p in ways.items()}
    choice["shared_as_fitted"] = _figures(y, shared_oof, d.w, groups)
    choice["plain_regression_on_children_as_fitted"] = _figures(y, expit(plain), d.w, groups)
    choice["chosen"] = min(ways, key=lambda k: choice[k]["log_loss_weighted"])
    choice["criterion"] = "log_loss_weighted"
    choice["calibration"] = "by age group and child seat, with the national weights"
    rows = np.flatnonzero(child)
    coef = _fit(eta[rows], d.x[rows], y[rows], d.w[rows])
    n_boot = cfg.boost_members if spec.kind in ("boosted", "blend") else cfg.n_bootstrap
    boot = [
        _fit(eta[rows[ix]], d.x[rows[ix]], y[rows[ix]], d.w[rows[ix]])
        for ix in crash_resamples(d.crash[rows], n_boot, cfg.seed + _BOOT_SEED)
    ]
    return {
        "oof": oof,
        "fold_coefficients": coefs,
        "coefficients": coef,
        "bootstrap_coefficients": np.stack(boot),
        "choice": choice,
    }


def children_calibration_of(stage: dict[str, Any]) -> ChildrenCalibration:
    """The served calibration of :func:`children_stage`'s result."""
    return ChildrenCalibration(
        coefficients=np.asarray(stage["coefficients"], dtype=np.float64),
        bootstrap_coefficients=np.asarray(stage["bootstrap_coefficients"], dtype=np.float64),
        columns=tuple(_TERMS),
        age_group_columns=tuple(_AGE_GROUPS),
    )
