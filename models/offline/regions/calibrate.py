"""Does calibrated physics add? Field-fitted risk functions of the measures (issue 39, item 5).

For each region, a risk function from the occupant models' measure(s) to
P(region AIS 3+) is fitted on the field outcomes instead of the published
dummy curves: a survey-weighted logistic regression on log(1 + measure) with
one intercept per impact mode. Then it is asked whether the calibrated
measures add to a delta-V-based region model (the notification's fields:
delta-V and its interaction with the mode, belt, age, sex, frontal airbag
deployment, rollover, multiple impacts), and whether the measures add to the
same model of ISS 15+ (ISS >= 16, the decision's outcome).

Evaluation: 5 folds by crash (every occupant of a crash on one side; the fold
of a crash drawn with a fixed seed), out-of-fold predictions scored by the
weighted AUC; the paired difference "with physics - without" gets a 95 %
interval from the crash bootstrap (:mod:`models.offline.regions.stats`), and
also on the latest years held out (fitted on 1997-2009, scored on 2010-2014).
The physics "adds" where the cross-validated difference's interval lies above
zero and the held-out-years difference is positive.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
import pandas as pd
from sklearn.linear_model import LogisticRegression

from models.arrays import FloatArray, IntArray
from models.offline.regions.skill import REGION_SPECS, RegionSpec, outcome
from models.offline.regions.stats import CrashBootstrap, Interval, weighted_auc

__all__ = [
    "FOLDS",
    "HELD_OUT_FROM_YEAR",
    "AddedValue",
    "CalibratedCurve",
    "added_value",
    "base_design",
    "calibrated_curve",
    "crash_folds",
]

#: Folds of the cross-validation (by crash).
FOLDS: Final[int] = 5
#: Seed of the fold assignment.
FOLD_SEED: Final[int] = 39
#: First accident year of the held-out latest years.
HELD_OUT_FROM_YEAR: Final[int] = 2010
#: L2 penalty (inverse strength) of every logistic fit on standardised columns. [R]
#: Mild: the designs have at most 20 columns against thousands of events.
PENALTY_C: Final[float] = 1.0
#: The regions whose measures are tried, and the measures (physics-table columns).
PHYSICS_COLUMNS: Final[dict[str, tuple[str, ...]]] = {
    "head": ("hic15",),
    "neck": ("nij",),
    "spine (cervical spine is here in AIS 1990)": ("nij",),
    "thorax": ("chest_deflection_mm", "chest_vc_m_s", "chest_a3ms_g", "chest_cti"),
    "abdomen": ("abdomen_vc_m_s",),
}
#: Every measure, for the ISS 15+ model.
ALL_MEASURES: Final[tuple[str, ...]] = (
    "hic15",
    "nij",
    "chest_deflection_mm",
    "chest_vc_m_s",
    "chest_a3ms_g",
    "chest_cti",
    "abdomen_vc_m_s",
)
_MODES_NOT_FRONTAL: Final[tuple[str, ...]] = ("near_side", "far_side", "rear")
_MODES_ALL: Final[tuple[str, ...]] = ("frontal", *_MODES_NOT_FRONTAL)


def crash_folds(crash: IntArray, folds: int = FOLDS, seed: int = FOLD_SEED) -> IntArray:
    """A fold per row, the same for every row of a crash."""
    ids, inverse = np.unique(crash, return_inverse=True)
    rng = np.random.default_rng(seed)
    fold_of = rng.integers(0, folds, size=ids.size)
    return np.asarray(fold_of[inverse], dtype=np.int64)


def _mode_dummies(frame: pd.DataFrame) -> FloatArray:
    return np.column_stack([(frame["mode"] == m).to_numpy(float) for m in _MODES_NOT_FRONTAL])


def base_design(frame: pd.DataFrame) -> FloatArray:
    """The notification's fields: delta-V by mode, belt, age, sex, airbag, rollover, impacts."""
    dv = frame["delta_v_kmh"].to_numpy(float)
    modes = _mode_dummies(frame)
    female = frame["female"].fillna(0.0).to_numpy(float)
    return np.column_stack(
        [
            dv,
            modes * dv[:, None],
            modes,
            frame["belted"].to_numpy(float),
            frame["age_years"].to_numpy(float),
            female,
            (frame["frontal_airbag"] == "deployed").to_numpy(float),
            frame["rollover"].to_numpy(float),
            frame["multiple_impacts"].to_numpy(float),
        ]
    )


def physics_design(frame: pd.DataFrame, columns: Sequence[str]) -> FloatArray:
    """log(1 + measure) of each column (a missing measure is 0)."""
    return np.column_stack(
        [np.log1p(np.clip(frame[c].fillna(0.0).to_numpy(float), 0.0, None)) for c in columns]
    )


def _fit_predict(
    x_fit: FloatArray, y_fit: FloatArray, w_fit: FloatArray, x_new: FloatArray
) -> tuple[FloatArray, LogisticRegression, FloatArray, FloatArray]:
    mu, sd = x_fit.mean(axis=0), x_fit.std(axis=0)
    sd = np.where(sd > 0, sd, 1.0)
    model = LogisticRegression(C=PENALTY_C, max_iter=2000)
    model.fit((x_fit - mu) / sd, y_fit, sample_weight=w_fit / w_fit.mean())
    p = model.predict_proba((x_new - mu) / sd)[:, 1]
    return np.asarray(p, dtype=np.float64), model, mu, sd


def _oof(x: FloatArray, y: FloatArray, w: FloatArray, fold: IntArray) -> FloatArray:
    p = np.empty_like(y)
    for k in np.unique(fold):
        test = fold == k
        p[test] = _fit_predict(x[~test], y[~test], w[~test], x[test])[0]
    return p


@dataclass(frozen=True)
class CalibratedCurve:
    """A field-fitted risk function of one measure, and its skill."""

    region: str
    measure: str
    #: out-of-fold weighted AUC of the calibrated function alone (measure + mode)
    auc_cv: float
    #: weighted mean out-of-fold P / weighted observed rate
    observed: float
    expected: float
    #: coefficient of log(1 + measure) (per unit of it, not standardised) and the
    #: intercept of each mode in which the occupant model gives the measure
    slope: float
    intercepts: dict[str, float]


def calibrated_curve(
    frame: pd.DataFrame, spec: RegionSpec, measure: str, fold: IntArray
) -> CalibratedCurve:
    """Fit P(region AIS >= level) = expit(a_mode + b log(1 + measure)) and score it.

    Over the occupants whose occupant model gives the measure (the rear model
    has no chest measures, the frontal one no CTI or abdominal VC).
    """
    has = frame[measure].notna().to_numpy()
    sub, fold = frame[has], fold[has]
    y = outcome(sub, spec)
    w = sub["ratwgt"].to_numpy(float)
    modes = [m for m in _MODES_ALL if (sub["mode"] == m).any()]
    dummies = np.column_stack([(sub["mode"] == m).to_numpy(float) for m in modes])
    x = np.column_stack([physics_design(sub, [measure]), dummies[:, 1:]])
    p = _oof(x, y, w, fold)
    _, model, mu, sd = _fit_predict(x, y, w, x)
    coef = model.coef_[0] / sd
    icpt = float(model.intercept_[0] - np.sum(model.coef_[0] * mu / sd))
    intercepts = {modes[0]: icpt}
    for i, m in enumerate(modes[1:]):
        intercepts[m] = icpt + float(coef[1 + i])
    return CalibratedCurve(
        region=spec.name,
        measure=measure,
        auc_cv=weighted_auc(y, p, w),
        observed=float(np.average(y, weights=w)),
        expected=float(np.average(p, weights=w)),
        slope=float(coef[0]),
        intercepts=intercepts,
    )


@dataclass(frozen=True)
class AddedValue:
    """Out-of-fold skill of the delta-V-based model with and without the measures."""

    outcome: str
    measures: tuple[str, ...]
    positives: int
    auc_base: float
    auc_physics: float
    difference: Interval
    calibration_base: float
    calibration_physics: float
    #: the same difference, fitted on 1997-2009 and scored on 2010-2014 (weighted)
    held_out_years: float

    @property
    def adds(self) -> bool:
        """The cross-validated interval lies above zero and the latest years agree."""
        return self.difference.low > 0.0 and self.held_out_years > 0.0


def added_value(
    frame: pd.DataFrame, y: FloatArray, label: str, measures: Sequence[str], fold: IntArray
) -> AddedValue:
    """Cross-validated AUC of the base model and of the base model + log(1 + measures)."""
    w = frame["ratwgt"].to_numpy(float)
    xb = base_design(frame)
    xp = np.column_stack([xb, physics_design(frame, measures)])
    pb, pp = _oof(xb, y, w, fold), _oof(xp, y, w, fold)
    boot = CrashBootstrap(frame["crash"].to_numpy(), w)
    diff = boot.interval(lambda ww: weighted_auc(y, pp, ww) - weighted_auc(y, pb, ww))
    late = (frame["year"] >= HELD_OUT_FROM_YEAR).to_numpy()
    held = float("nan")
    if y[late].sum() >= 5 and y[~late].sum() >= 5:
        qb = _fit_predict(xb[~late], y[~late], w[~late], xb[late])[0]
        qp = _fit_predict(xp[~late], y[~late], w[~late], xp[late])[0]
        held = weighted_auc(y[late], qp, w[late]) - weighted_auc(y[late], qb, w[late])
    obs = float(np.average(y, weights=w))
    return AddedValue(
        outcome=label,
        measures=tuple(measures),
        positives=int(y.sum()),
        auc_base=weighted_auc(y, pb, w),
        auc_physics=weighted_auc(y, pp, w),
        difference=diff,
        calibration_base=float(np.average(pb, weights=w)) / obs,
        calibration_physics=float(np.average(pp, weights=w)) / obs,
        held_out_years=held,
    )


def item_five(
    frame: pd.DataFrame,
) -> tuple[list[CalibratedCurve], list[AddedValue]]:
    """Every region's calibrated curves and added value, and the ISS 15+ model's."""
    fold = crash_folds(frame["crash"].to_numpy())
    curves: list[CalibratedCurve] = []
    added: list[AddedValue] = []
    for spec in REGION_SPECS:
        measures = PHYSICS_COLUMNS.get(spec.name)
        if not measures:
            continue
        curves.extend(calibrated_curve(frame, spec, m, fold) for m in measures)
        label = f"{spec.name} AIS {spec.level}+"
        added.append(added_value(frame, outcome(frame, spec), label, measures, fold))
    iss15 = (frame["iss"].to_numpy(float) >= 16).astype(np.float64)
    added.append(added_value(frame, iss15, "ISS 15+ (the decision)", ALL_MEASURES, fold))
    return curves, added
