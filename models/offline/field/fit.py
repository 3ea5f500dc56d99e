"""Fit the field risk model on real crashes and measure it by cross-validation.

``aacn-triage fit-field`` (:mod:`.command`) runs :func:`fit_field`:

1. **Rows.** The NASS-CDS 2000-2014 MAIS calibration file (4,856 adults, 140
   MAIS 3+, all crash modes; ``data/PROVENANCE.md``) is turned into the
   notifications a call center would have sent (:mod:`.rows`), and each is sent
   through the engine (:mod:`.evidence`, cached): the field model's inputs are
   built by the same code the service runs, and the occupant models' answers
   (their P(ISS >= 15)) come with them.
2. **Models compared**, on the same repeated stratified folds (5 folds x 10
   repeats): delta-V alone; a plain (unpenalised) logistic regression on the
   telematics fields; the field model (telematics only); the field model plus
   physics features (the occupant model's logit P(ISS >= 15) where it runs and
   an indicator of it); and the occupant models' P as the service decided on it
   before (no fit). The penalty of the field models is chosen inside each
   training part (inner 5-fold CV log loss), so the held-out figures are
   honest. AUC, calibration and their differences get 95 % intervals from a
   stratified bootstrap of the rows (the repeat-averaged out-of-fold
   predictions).
3. **Decision.** Operating points are set on out-of-fold predictions: the
   default ``sens80`` flags the fewest occupants at a sensitivity of at least
   0.80 (one threshold on the calibrated probability for every mode: with
   calibrated probabilities that is the smallest flagged share for a given
   overall sensitivity); ``sens80_per_mode`` reaches 0.80 within each mode
   that has enough positives (the others pooled); ``bahouth`` is the published
   0.10 frontal / 0.05 side rule. Their held-out sensitivity, flagged share and
   PPV are measured with the threshold chosen inside each training part.
4. **Borrowing strength.** All modes are fitted in one model with a mode
   intercept each and shared slopes, under an L2 penalty that shrinks the mode
   effects of the sparse modes (rear: 3 positives) toward the pooled fit. The
   file has no sex: the female log odds ratio is borrowed from NASS-CDS
   1997-2000 (survey-weighted logistic regression of police-reported A+K injury
   on delta-V band, belt, age, sex, airbag fitted and deployed, frontal) as an
   offset centred on the weighted share of women. Airbag state is not a field
   model input: the MAIS file has no airbag column, and in the 1997-2000 file
   deployment within a delta-V band marks a harder crash (it raises the
   police-reported risk), not a transportable airbag effect at a given delta-V.
5. **Uncertainty.** 200 bootstrap refits (calibration rows resampled within
   outcome; the 1997-2000 rows resampled for the sex offset) are stored; the
   service's 95 % interval is the refits' logit spread.
6. **Outputs.** The artifact ``models/field/artifacts/field_mais3.json`` (its
   content checksum and the feature code checksum inside), and the model card
   with its plots under ``docs/field/`` (or ``--out``).
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, fields
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, Final

import numpy as np
import numpy.typing as npt
import statsmodels.api as sm
from sklearn.linear_model import LogisticRegression
from sklearn.model_selection import RepeatedStratifiedKFold, StratifiedKFold
from tqdm import tqdm

from models.arrays import BoolArray, FloatArray
from models.field.features import (
    FEATURE_NAMES,
    FieldInputs,
    FieldMode,
    Imputation,
    design_matrix,
)
from models.field.model import (
    ARTIFACT_SCHEMA,
    OUTCOME,
    canonical_content_sha256,
    default_artifact_path,
    feature_code_sha256,
)
from models.injury.measures import InjuryMeasures
from models.notification import Sex
from models.offline.baseline.fit import DELTA_V_BAND_MIDPOINTS_KMH
from models.offline.baseline.fit import default_data_path as police_data_path
from models.offline.field.evidence import RowEvidence, evidence_for
from models.offline.field.metrics import (
    auc,
    bootstrap_ci,
    calibration,
    stratified_bootstrap_indices,
    threshold_for_sensitivity,
    triage_rates,
)
from models.offline.field.rows import (
    CALIBRATION_CSV,
    CalibrationRow,
    load_calibration_rows,
    police_notification,
    row_notification,
)
from models.offline.field_check import FieldCase, field_cases
from models.triage import notification_field_inputs

__all__ = [
    "BAHOUTH_THRESHOLDS",
    "CalibrationDesign",
    "calibration_design",
    "penalised_fit",
    "FitConfig",
    "FieldFit",
    "ModelScores",
    "fit_field",
]


MODEL_NAME: Final[str] = "field_mais3"
#: 2.0.0 (2026-12-05): refitted on the corrected delta-V in km/h. 1.0.0 was fitted
#: on an mph column labelled km/h (data/PROVENANCE-mais-2000-2014.md, "Units
#: correction") and read every notification at 1.6 times its delta-V; it is kept
#: beside the shipped artifact for recall reports (`aacn-triage cases rescore`).
MODEL_VERSION: Final[str] = "2.0.0"

#: Published thresholds on a field-calibrated probability: 0.10 frontal, 0.05
#: side (Bahouth, Digges & Schulman; crash-data-and-triage.md section 1) [V].
#: Rear takes the frontal value and rollover the side value [R] (the paper sets
#: neither; rollover is a high-risk criterion of the CDC panel, so the more
#: sensitive one).
BAHOUTH_THRESHOLDS: Final[dict[FieldMode, float]] = {
    FieldMode.FRONTAL: 0.10,
    FieldMode.REAR: 0.10,
    FieldMode.NEAR_SIDE: 0.05,
    FieldMode.FAR_SIDE: 0.05,
    FieldMode.ROLLOVER: 0.05,
}

#: The operating point the service decides at unless `AACN_OPERATING_POINT` says
#: otherwise. [R] (2.0.0) ``sens80_per_mode``: it reaches a sensitivity of 0.80
#: within frontal and near-side crashes, the modes with enough positives to set
#: a threshold, where the one pooled threshold of ``sens80`` leaves frontal
#: crashes (two thirds of the occupants) at 0.77 and near-side ones at 0.90;
#: held out, it also flags fewer occupants overall (16.8 % against 17.0 % at a
#: sensitivity of 0.805 against 0.808; model card, "operating points").
DEFAULT_OPERATING_POINT: Final[str] = "sens80_per_mode"

#: Columns of the plain logistic regression on the telematics fields (the
#: reference the field model must match): delta-V, belt, mode indicators, age,
#: multiple impacts, body mass index, unpenalised.
_PLAIN_COLUMNS: Final[tuple[str, ...]] = (
    "intercept",
    "delta_v_kmh",
    "belted",
    "near_side",
    "far_side",
    "rear",
    "rollover",
    "age_years",
    "multiple_impacts",
    "bmi",
)


@dataclass(frozen=True)
class FitConfig:
    """Settings of a fit (recorded in the artifact).

    Attributes
    ----------
    c_grid : tuple of float
        Inverse L2 penalty strengths tried (features standardised).
    n_splits, n_repeats : int
        Outer repeated stratified folds.
    inner_splits : int
        Folds of the inner CV that picks the penalty and the thresholds.
    seed : int
    n_bootstrap : int
        Bootstrap refits stored in the artifact.
    n_metric_bootstrap : int
        Resamples for the confidence intervals of the figures.
    sensitivity_target : float
        Of the default operating point.
    min_mode_positives : int
        A mode with fewer positives shares the pooled threshold of
        ``sens80_per_mode``.
    """

    c_grid: tuple[float, ...] = (0.01, 0.03, 0.1, 0.3, 1.0, 3.0)
    n_splits: int = 5
    n_repeats: int = 10
    inner_splits: int = 5
    seed: int = 20261204
    n_bootstrap: int = 200
    n_metric_bootstrap: int = 2000
    sensitivity_target: float = 0.80
    min_mode_positives: int = 20


# --------------------------------------------------------------------- fitting


def _standardise(x: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Mean and scale of each non-intercept column (scale 1 for constant columns)."""
    mu = x[:, 1:].mean(axis=0)
    sd = x[:, 1:].std(axis=0)
    sd[sd == 0.0] = 1.0
    return mu, sd


def penalised_fit(x: FloatArray, y: FloatArray, c: float | None) -> FloatArray:
    """Logistic regression coefficients on the raw scale (column 0 the intercept).

    Parameters
    ----------
    x : ndarray, shape (n, k)
        Design matrix whose first column is the intercept.
    y : ndarray, shape (n,)
    c : float or None
        scikit-learn's inverse L2 strength on the standardised non-intercept
        columns (the intercept is not penalised); None: unpenalised.

    Returns
    -------
    ndarray, shape (k,)
    """
    mu, sd = _standardise(x)
    z = (x[:, 1:] - mu) / sd
    # L2 (l1_ratio 0); C = inf is the unpenalised fit (scikit-learn >= 1.8)
    lr = LogisticRegression(C=np.inf if c is None else c, l1_ratio=0.0, max_iter=10_000, tol=1e-10)
    lr.fit(z, y)
    slopes = lr.coef_[0] / sd
    intercept = float(lr.intercept_[0]) - float(slopes @ mu)
    return np.concatenate([[intercept], slopes])


def _expit(eta: FloatArray) -> FloatArray:
    out: FloatArray = 0.5 * (1.0 + np.tanh(0.5 * eta))
    return out


def _inner_oof(
    x: FloatArray, y: FloatArray, grid: Sequence[float], splits: int, seed: int
) -> tuple[float, FloatArray]:
    """The penalty with the smallest inner-CV log loss, and its out-of-fold probabilities."""
    folds = list(StratifiedKFold(splits, shuffle=True, random_state=seed).split(x, y))
    best: tuple[float, float, FloatArray] | None = None
    for c in grid:
        oof = np.empty(y.size)
        for tr, te in folds:
            oof[te] = _expit(x[te] @ penalised_fit(x[tr], y[tr], c))
        q = np.clip(oof, 1e-12, 1.0 - 1e-12)
        loss = float(-np.mean(y * np.log(q) + (1.0 - y) * np.log(1.0 - q)))
        if best is None or loss < best[0]:
            best = (loss, c, oof)
    assert best is not None
    return best[1], best[2]


def _per_mode_thresholds(
    y: FloatArray,
    p: FloatArray,
    modes: Sequence[FieldMode],
    config: FitConfig,
    copies: int = 1,
) -> dict[FieldMode, float]:
    """Thresholds reaching the sensitivity target within each mode with enough positives.

    Modes with fewer than ``min_mode_positives`` positives take the threshold
    that reaches the target over all rows (too few positives to set their own).
    `copies` is the number of times each occupant appears in the rows (the
    repeats of a repeated cross-validation), so positives are counted once.
    """
    mode_arr = np.array([m.value for m in modes])
    pooled = threshold_for_sensitivity(y, p, config.sensitivity_target)
    out: dict[FieldMode, float] = {}
    for m in FieldMode:
        sel = mode_arr == m.value
        if y[sel].sum() / copies >= config.min_mode_positives:
            out[m] = threshold_for_sensitivity(y[sel], p[sel], config.sensitivity_target)
        else:
            out[m] = pooled
    return out


def _flags(
    p: FloatArray, modes: Sequence[FieldMode], thresholds: dict[FieldMode, float]
) -> BoolArray:
    t = np.array([thresholds[m] for m in modes])
    return np.asarray(p >= t)


# ------------------------------------------------------------------ the results


@dataclass(frozen=True)
class ModelScores:
    """Cross-validated figures of one model on one data set.

    Attributes
    ----------
    name, description : str
    auc : float
        Mean over repeats of the AUC of the out-of-fold predictions.
    auc_ci95 : (float, float)
        Bootstrap interval of the AUC of the repeat-averaged predictions.
    auc_by_mode : dict of str to (float, (float, float))
    calibration : dict of str to float
        Intercept, slope, Brier of the repeat-averaged predictions (None for
        scores that are not probabilities of the outcome).
    difference_to_field : (float, (float, float)) or None
        AUC of the field model minus this model's, with its bootstrap interval.
    """

    name: str
    description: str
    auc: float
    auc_ci95: tuple[float, float]
    auc_by_mode: dict[str, tuple[float, tuple[float, float]]]
    calibration: dict[str, float] | None
    difference_to_field: tuple[float, tuple[float, float]] | None = None


@dataclass
class FieldFit:
    """Everything a fit produced (the artifact document and the report's figures)."""

    artifact: dict[str, Any]
    scores: list[ModelScores]
    operating_points: dict[str, dict[str, Any]]
    police: dict[str, Any]
    coefficients: dict[str, float]
    physics_kept: bool
    physics_verdict: str
    oof: dict[str, FloatArray] = field(repr=False)
    y: FloatArray = field(repr=False)
    modes: list[FieldMode] = field(repr=False)
    reliability: dict[str, Any] = field(default_factory=dict)
    inputs: tuple[FieldInputs, ...] = field(default=(), repr=False)


# ------------------------------------------------------------ the physics feature


def _physics_columns(evidence: Sequence[RowEvidence]) -> FloatArray:
    """``[in_lpm, in_lpm * logit(p_lpm_uncorrected)]`` per row, shape (n, 2)."""
    out = np.zeros((len(evidence), 2))
    for i, ev in enumerate(evidence):
        if ev.in_lpm and ev.p_lpm_uncorrected is not None:
            q = min(max(ev.p_lpm_uncorrected, 1e-6), 1.0 - 1e-6)
            out[i] = (1.0, math.log(q / (1.0 - q)))
    return out


#: The occupant model's injury measures offered to the field model as features
#: (names with units, :class:`models.injury.measures.InjuryMeasures`), each as
#: ``log1p(value)`` where the occupant model gives it and 0 elsewhere. [R] log1p:
#: the measures span orders of magnitude (HIC15 1-5,000) and risk curves of
#: them are logistic in the log (Mertz/Prasad HIC curve).
PHYSICS_MEASURES: Final[tuple[str, ...]] = tuple(f.name for f in fields(InjuryMeasures))


def _measure_columns(evidence: Sequence[RowEvidence]) -> FloatArray:
    """``[in_lpm, log1p(measure) ...]`` per row, shape (n, 1 + len(PHYSICS_MEASURES))."""
    out = np.zeros((len(evidence), 1 + len(PHYSICS_MEASURES)))
    for i, ev in enumerate(evidence):
        if not ev.in_lpm or ev.measures is None:
            continue
        out[i, 0] = 1.0
        for j, name in enumerate(PHYSICS_MEASURES, start=1):
            value = ev.measures.get(name)
            if value is not None and math.isfinite(value) and value >= 0.0:
                out[i, j] = math.log1p(value)
    return out


# ------------------------------------------------------------ the sex offset


@dataclass(frozen=True)
class _SexOffset:
    log_odds_ratio: float
    standard_error: float
    female_share: float
    bootstrap: FloatArray


def _police_design(cases: Sequence[FieldCase]) -> FloatArray:
    bands = [b for b in DELTA_V_BAND_MIDPOINTS_KMH if b != "1-9km/h"]
    cols = [np.ones(len(cases))]
    cols += [np.array([c.band == b for c in cases], dtype=float) for b in bands]
    cols += [
        np.array([c.belted for c in cases], dtype=float),
        np.array([c.age_years for c in cases]),
        np.array([not c.male for c in cases], dtype=float),
        np.array([c.frontal_airbag.value == "deployed" for c in cases], dtype=float),
        np.array([c.frontal_airbag.value != "absent" for c in cases], dtype=float),
    ]
    return np.column_stack(cols)


_FEMALE_COLUMN: Final[int] = 1 + 4 + 2  # intercept, 4 band dummies, belted, age


def _female_log_or(x: FloatArray, y: FloatArray, w: FloatArray) -> tuple[float, float]:
    fit = sm.GLM(y, x, family=sm.families.Binomial(), var_weights=w / w.mean()).fit()
    return float(fit.params[_FEMALE_COLUMN]), float(fit.bse[_FEMALE_COLUMN])


def _sex_offset(cases: Sequence[FieldCase], n_boot: int, seed: int) -> _SexOffset:
    x = _police_design(cases)
    y = np.array([c.serious for c in cases], dtype=float)
    w = np.array([c.weight for c in cases])
    b, se = _female_log_or(x, y, w)
    rng = np.random.default_rng(seed)
    boot = np.empty(n_boot)
    for k in range(n_boot):
        ix = rng.integers(0, y.size, y.size)
        boot[k] = _female_log_or(x[ix], y[ix], w[ix])[0]
    female = np.array([not c.male for c in cases], dtype=float)
    return _SexOffset(b, se, float(np.average(female, weights=w)), boot)


# ------------------------------------------------------------ the data


@dataclass(frozen=True)
class CalibrationDesign:
    """The calibration rows as the field model sees them.

    Attributes
    ----------
    rows : tuple of CalibrationRow
    inputs : tuple of FieldInputs
        Built as a request builds them (:func:`models.triage.notification_field_inputs`).
    x : ndarray, shape (n, k)
        Design matrix (:data:`models.field.features.FEATURE_NAMES`).
    y : ndarray, shape (n,)
        MAIS 3+.
    modes : list of FieldMode
    imputation : Imputation
        The medians of age and body mass index.
    sha256 : str
        Of the CSV.
    """

    rows: tuple[CalibrationRow, ...]
    inputs: tuple[FieldInputs, ...]
    x: FloatArray
    y: FloatArray
    modes: list[FieldMode]
    imputation: Imputation
    sha256: str


def calibration_design(path: Path | None = None) -> CalibrationDesign:
    """Read the calibration CSV and build the field model's design matrix (no engine runs)."""
    csv_path = path or CALIBRATION_CSV
    rows = load_calibration_rows(csv_path)
    inputs = tuple(inp for r in rows for inp in notification_field_inputs(row_notification(r)))
    ages = np.array([f.age_years for f in inputs], dtype=float)
    bmis = np.array([f.bmi for f in inputs], dtype=float)
    imputation = Imputation(age_years=float(np.median(ages)), bmi=float(np.median(bmis)))
    x, _ = design_matrix(inputs, imputation)
    return CalibrationDesign(
        rows=rows,
        inputs=inputs,
        x=x,
        y=np.array([r.mais3 for r in rows], dtype=float),
        modes=[f.mode for f in inputs],
        imputation=imputation,
        sha256=hashlib.sha256(csv_path.read_bytes()).hexdigest(),
    )


# ------------------------------------------------------------ the main routine


def _model_scores(
    name: str,
    description: str,
    y: FloatArray,
    oof: FloatArray,
    modes: Sequence[FieldMode],
    indices: Sequence[npt.NDArray[np.int64]],
    probability: bool,
    reference: FloatArray | None,
) -> ModelScores:
    """Figures of repeated out-of-fold scores `oof`, shape (repeats, n)."""
    mean_score = oof.mean(axis=0)
    mode_arr = np.array([m.value for m in modes])
    per_repeat = float(np.mean([auc(y, r) for r in oof]))
    ci = bootstrap_ci(lambda ix: auc(y[ix], mean_score[ix]), indices)
    by_mode = {}
    for m in FieldMode:
        sel = np.flatnonzero(mode_arr == m.value)
        sub = [ix[np.isin(ix, sel)] for ix in indices[:500]]
        by_mode[m.value] = (
            auc(y[sel], mean_score[sel]),
            bootstrap_ci(lambda ix: auc(y[ix], mean_score[ix]), sub),
        )
    cal = None
    if probability:
        c = calibration(y, mean_score)
        cal = {
            "intercept": c.intercept,
            "slope": c.slope,
            "brier": c.brier,
            "mean_predicted": c.expected,
            "observed_rate": c.observed,
        }
    diff = None
    if reference is not None:
        ref = reference.mean(axis=0)
        d = auc(y, ref) - auc(y, mean_score)
        diff = (
            d,
            bootstrap_ci(lambda ix: auc(y[ix], ref[ix]) - auc(y[ix], mean_score[ix]), indices),
        )
    return ModelScores(name, description, per_repeat, ci, by_mode, cal, diff)


@dataclass(frozen=True)
class _CrossValidation:
    """Out-of-fold scores of the compared models and the operating points' held-out flags.

    Attributes
    ----------
    splits : list of (ndarray, ndarray)
        The outer (train, test) index pairs, repeat by repeat.
    oof : dict of str to ndarray, shape (repeats, n)
        Out-of-fold probabilities of each fitted model.
    flags : dict of str to ndarray of bool, shape (repeats, n)
        Held-out flags of each operating point (thresholds set on the training part).
    chosen_c : list of float
        The penalty chosen inside each training part.
    """

    splits: list[tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]]
    oof: dict[str, FloatArray]
    flags: dict[str, BoolArray]
    chosen_c: list[float]


def _cross_validate(
    x: FloatArray,
    x_phys: FloatArray,
    x_meas: FloatArray,
    y: FloatArray,
    modes: Sequence[FieldMode],
    cfg: FitConfig,
    progress: bool,
) -> _CrossValidation:
    """Step 2 and 3 of the module docstring: every model on the same repeated folds."""
    col = {name: i for i, name in enumerate(FEATURE_NAMES)}
    x_plain = x[:, [col[c] for c in _PLAIN_COLUMNS]]
    x_dv = x[:, [col["intercept"], col["delta_v_kmh"]]]
    splitter = RepeatedStratifiedKFold(
        n_splits=cfg.n_splits, n_repeats=cfg.n_repeats, random_state=cfg.seed
    )
    splits = list(splitter.split(x, y))
    r_n = cfg.n_repeats
    oof = {
        k: np.zeros((r_n, y.size))
        for k in ("delta_v", "plain", "field", "field_physics", "field_measures")
    }
    flags: dict[str, BoolArray] = {
        k: np.zeros((r_n, y.size), dtype=bool) for k in ("sens80", "sens80_per_mode", "bahouth")
    }
    chosen_c: list[float] = []
    for k, (tr, te) in enumerate(tqdm(splits, desc="cross-validation folds", disable=not progress)):
        rep = k // cfg.n_splits
        oof["delta_v"][rep, te] = _expit(x_dv[te] @ penalised_fit(x_dv[tr], y[tr], None))
        oof["plain"][rep, te] = _expit(x_plain[te] @ penalised_fit(x_plain[tr], y[tr], None))
        c, inner = _inner_oof(x[tr], y[tr], cfg.c_grid, cfg.inner_splits, cfg.seed + k)
        chosen_c.append(c)
        beta = penalised_fit(x[tr], y[tr], c)
        p_te = _expit(x[te] @ beta)
        oof["field"][rep, te] = p_te
        c_phys, _ = _inner_oof(x_phys[tr], y[tr], cfg.c_grid, cfg.inner_splits, cfg.seed + k)
        oof["field_physics"][rep, te] = _expit(
            x_phys[te] @ penalised_fit(x_phys[tr], y[tr], c_phys)
        )
        c_meas, _ = _inner_oof(x_meas[tr], y[tr], cfg.c_grid, cfg.inner_splits, cfg.seed + k)
        oof["field_measures"][rep, te] = _expit(
            x_meas[te] @ penalised_fit(x_meas[tr], y[tr], c_meas)
        )
        # thresholds chosen inside the training part, applied to the held-out part
        tr_modes = [modes[i] for i in tr]
        te_modes = [modes[i] for i in te]
        t80 = threshold_for_sensitivity(y[tr], inner, cfg.sensitivity_target)
        flags["sens80"][rep, te] = p_te >= t80
        per_mode = _per_mode_thresholds(y[tr], inner, tr_modes, cfg)
        flags["sens80_per_mode"][rep, te] = _flags(p_te, te_modes, per_mode)
        flags["bahouth"][rep, te] = _flags(p_te, te_modes, BAHOUTH_THRESHOLDS)
    return _CrossValidation(splits, oof, flags, chosen_c)


def _final_fit(
    x: FloatArray,
    y: FloatArray,
    modes: list[FieldMode],
    splits: Sequence[tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]],
    cfg: FitConfig,
) -> tuple[float, FloatArray, dict[str, dict[FieldMode, float]]]:
    """The penalty, the coefficients and the operating points' thresholds from the whole file.

    Returns
    -------
    c_final : float
    beta : ndarray, shape (k,)
    thresholds : dict of str to dict of FieldMode to float
    """
    c_final, _ = _inner_oof(x, y, cfg.c_grid, cfg.n_splits, cfg.seed)
    beta = penalised_fit(x, y, c_final)
    r_n = cfg.n_repeats
    full_oof = np.zeros((r_n, y.size))
    for k, (tr, te) in enumerate(splits):
        full_oof[k // cfg.n_splits, te] = _expit(x[te] @ penalised_fit(x[tr], y[tr], c_final))
    y_rep = np.tile(y, r_n)
    p_rep = full_oof.reshape(-1)
    modes_rep = modes * r_n
    thresholds = {
        "sens80": dict.fromkeys(
            FieldMode, threshold_for_sensitivity(y_rep, p_rep, cfg.sensitivity_target)
        ),
        "sens80_per_mode": _per_mode_thresholds(y_rep, p_rep, modes_rep, cfg, copies=r_n),
        "bahouth": dict(BAHOUTH_THRESHOLDS),
    }
    _check_monotone(beta)
    return c_final, beta, thresholds


def _bootstrap_refits(
    x: FloatArray, y: FloatArray, c: float, cfg: FitConfig, progress: bool
) -> FloatArray:
    """Step 5: coefficients refitted on stratified resamples, shape (n_bootstrap, k)."""
    boot = np.empty((cfg.n_bootstrap, x.shape[1]))
    for b, ix in enumerate(
        tqdm(
            stratified_bootstrap_indices(y, cfg.n_bootstrap, cfg.seed + 1),
            desc="bootstrap refits",
            disable=not progress,
        )
    ):
        boot[b] = penalised_fit(x[ix], y[ix], c)
    return boot


def _compared_scores(
    y: FloatArray,
    modes: Sequence[FieldMode],
    oof: dict[str, FloatArray],
    indices: Sequence[npt.NDArray[np.int64]],
) -> list[ModelScores]:
    """The figures of every compared model (``oof`` includes ``occupant_models``)."""
    specs = [
        ("field", "field model: telematics (the decision)", True),
        (
            "field_physics",
            "field model + physics (occupant-model logit P(ISS>=15) where it runs)",
            True,
        ),
        (
            "field_measures",
            "field model + injury measures (the occupant model's HIC, Nij, chest and "
            "abdomen measures where it runs)",
            True,
        ),
        ("plain", "plain logistic regression on the telematics fields", True),
        ("delta_v", "delta-V alone (logistic)", True),
        (
            "occupant_models",
            "occupant models' P(ISS>=15) as decided before (baseline outside coverage)",
            False,
        ),
    ]
    return [
        _model_scores(n, d, y, oof[n], modes, indices, prob, None if n == "field" else oof["field"])
        for n, d, prob in specs
    ]


#: The physics variants of the ablation, with what they add.
_PHYSICS_VARIANTS: Final[dict[str, str]] = {
    "field_physics": "the occupant model's P(ISS >= 15)",
    "field_measures": "the occupant model's injury measures",
}


def _physics_verdict(scores: Sequence[ModelScores]) -> str:
    """The sentence on the physics features; raises if they help (the artifact lacks them).

    A variant helps when the 95 % interval of its cross-validated AUC gain over
    the telematics-only field model lies above zero. The fit refuses to write
    an artifact without physics when one does (the service would first need
    the physics features in :data:`models.field.features.FEATURE_NAMES`).
    """
    parts = []
    for name, what in _PHYSICS_VARIANTS.items():
        phys = next(s for s in scores if s.name == name)
        assert phys.difference_to_field is not None
        d_phys, ci_phys = phys.difference_to_field
        gain, lo, hi = -d_phys, -ci_phys[1], -ci_phys[0]
        if lo > 0.0:
            raise RuntimeError(
                f"{what} helps in cross-validation (AUC {gain:+.4f}, 95 % CI {lo:+.4f} to "
                f"{hi:+.4f}): the artifact would need it (not built: extend FEATURE_NAMES "
                "and the service first)"
            )
        parts.append(f"adding {what} changes it by {gain:+.4f} (95 % CI {lo:+.4f} to {hi:+.4f})")
    return (
        "Physics features do not help at the true delta-V: on the cross-validated AUC, "
        + "; ".join(parts)
        + ". The field model decides on telematics alone, and the occupant models stay in "
        "every answer as the physics explanation."
    )


def _artifact_document(
    *,
    cfg: FitConfig,
    data: CalibrationDesign,
    beta: FloatArray,
    boot: FloatArray,
    sex: _SexOffset,
    thresholds: dict[str, dict[FieldMode, float]],
    op_figures: dict[str, dict[str, Any]],
    c_final: float,
    chosen_c: Sequence[float],
    scores: Sequence[ModelScores],
    physics_kept: bool,
    police: dict[str, Any],
) -> dict[str, Any]:
    """Step 6: the artifact's JSON document, its content checksum inside."""
    doc: dict[str, Any] = {
        "schema": ARTIFACT_SCHEMA,
        "model": {"name": MODEL_NAME, "version": MODEL_VERSION},
        "outcome": OUTCOME,
        "outcome_description": (
            "maximum AIS 3 or more (NASS-CDS 2000-2014): the stand-in for ISS 15+ "
            "(conservative: one AIS 3 injury alone is ISS 9)"
        ),
        "feature_names": list(FEATURE_NAMES),
        "coefficients": [float(v) for v in beta],
        "bootstrap_coefficients": boot.tolist(),
        "sex_offset": {
            "log_odds_ratio_female": sex.log_odds_ratio,
            "standard_error": sex.standard_error,
            "female_share": sex.female_share,
            "bootstrap": sex.bootstrap.tolist(),
            "source": (
                "NASS-CDS 1997-2000 (models/offline/data), survey-weighted logistic "
                "regression of police-reported A+K injury on delta-V band, belt, age, "
                "sex, airbag fitted and deployed"
            ),
        },
        "imputation": {"age_years": data.imputation.age_years, "bmi": data.imputation.bmi},
        "operating_points": {
            name: {
                "description": _OP_DESCRIPTIONS[name],
                "thresholds": {m.value: float(t) for m, t in th.items()},
                "cross_validated": op_figures[name],
            }
            for name, th in thresholds.items()
        },
        "default_operating_point": DEFAULT_OPERATING_POINT,
        "feature_code_sha256": feature_code_sha256(),
        "data": {
            "calibration_csv_sha256": data.sha256,
            "police_csv_sha256": hashlib.sha256(police_data_path().read_bytes()).hexdigest(),
            "rows": int(data.y.size),
            "positives": int(data.y.sum()),
            "delta_v_max_kmh": float(max(f.delta_v_kmh for f in data.inputs)),
        },
        "fit": {
            "penalty_c": c_final,
            "penalty_c_chosen_in_folds": sorted(set(chosen_c)),
            "config": asdict(cfg),
            "physics_features_kept": physics_kept,
        },
        "cross_validated": {
            s.name: {
                "auc": s.auc,
                "auc_ci95": list(s.auc_ci95),
                "calibration": s.calibration,
            }
            for s in scores
        },
        "police_validation": {
            "n": police["n"],
            "positives": police["positives"],
            "weighted_rate": police["weighted_rate"],
            **{
                name: {"auc_weighted": v["auc_weighted"], "auc_unweighted": v["auc_unweighted"]}
                for name, v in police["auc"].items()
            },
        },
        "fit_date": datetime.now(UTC).date().isoformat(),
    }
    doc["content_sha256"] = canonical_content_sha256(doc)
    return doc


def fit_field(
    config: FitConfig | None = None,
    *,
    cache_dir: Path | None = None,
    workers: int | None = None,
    progress: bool = True,
) -> FieldFit:
    """Fit, cross-validate and describe the field model (see the module docstring).

    Returns
    -------
    FieldFit
        The artifact document (not yet written) and the report's figures.
    """
    cfg = config or FitConfig()
    data = calibration_design()
    x, y, modes = data.x, data.y, data.modes
    notes = [row_notification(r) for r in data.rows]
    evidence = evidence_for(
        notes,
        f"mais-{data.sha256[:12]}",
        cache_dir=cache_dir,
        workers=workers,
        progress=progress,
    )
    if [ev.inputs for ev in evidence] != list(data.inputs):
        raise RuntimeError("the engine's field inputs differ from notification_field_inputs")
    x_phys = np.column_stack([x, _physics_columns(evidence)])
    x_meas = np.column_stack([x, _measure_columns(evidence)])
    p_prev = np.array([ev.p_previous_decision for ev in evidence])

    cv = _cross_validate(x, x_phys, x_meas, y, modes, cfg, progress)
    c_final, beta, thresholds = _final_fit(x, y, modes, cv.splits, cfg)

    # bootstrap refits (the service's interval) and the borrowed sex offset
    police = field_cases(police_data_path())
    sex = _sex_offset(police, cfg.n_bootstrap, cfg.seed)
    boot = _bootstrap_refits(x, y, c_final, cfg, progress)

    # figures
    indices = stratified_bootstrap_indices(y, cfg.n_metric_bootstrap, cfg.seed + 2)
    oof = cv.oof | {"occupant_models": np.tile(p_prev, (cfg.n_repeats, 1))}
    scores = _compared_scores(y, modes, oof, indices)
    op_figures = _operating_point_figures(y, modes, cv.flags, indices, thresholds)
    verdict = _physics_verdict(scores)
    physics_kept = False

    police_fig = _police_figures(
        police, beta, data.imputation, sex, cfg, cache_dir, workers, progress
    )
    doc = _artifact_document(
        cfg=cfg,
        data=data,
        beta=beta,
        boot=boot,
        sex=sex,
        thresholds=thresholds,
        op_figures=op_figures,
        c_final=c_final,
        chosen_c=cv.chosen_c,
        scores=scores,
        physics_kept=physics_kept,
        police=police_fig,
    )
    return FieldFit(
        artifact=doc,
        scores=scores,
        operating_points=op_figures,
        police=police_fig,
        coefficients=dict(zip(FEATURE_NAMES, (float(v) for v in beta), strict=True)),
        physics_kept=physics_kept,
        physics_verdict=verdict,
        oof=oof,
        y=y,
        modes=modes,
        inputs=data.inputs,
    )


_OP_DESCRIPTIONS: Final[dict[str, str]] = {
    "sens80": (
        "the fewest occupants flagged at a cross-validated MAIS 3+ sensitivity of at least "
        "0.80 over all modes (one threshold for every mode)"
    ),
    "sens80_per_mode": (
        "default: sensitivity of at least 0.80 within each mode with 20 or more positives in "
        "the data (frontal, near side); the sparser modes take the sens80 threshold"
    ),
    "bahouth": (
        "published thresholds on a field-calibrated probability: 0.10 frontal and rear, "
        "0.05 side and rollover (Bahouth, Digges & Schulman)"
    ),
}


def _check_monotone(beta: FloatArray) -> None:
    """Risk does not fall as delta-V rises; belted is not worse than unbelted."""
    col = {name: i for i, name in enumerate(FEATURE_NAMES)}
    delta_v_kmh = np.linspace(1.0, 200.0, 400)
    slope = beta[col["delta_v_kmh"]] + beta[col["log_delta_v"]] / delta_v_kmh
    if np.any(slope <= 0.0):
        raise RuntimeError("the fitted risk falls with delta-V somewhere in 1-200 km/h")
    if beta[col["belted"]] > 0.0:
        raise RuntimeError("the fitted risk is higher belted than unbelted")


def _operating_point_figures(
    y: FloatArray,
    modes: Sequence[FieldMode],
    flags: dict[str, BoolArray],
    indices: Sequence[npt.NDArray[np.int64]],
    thresholds: dict[str, dict[FieldMode, float]],
) -> dict[str, dict[str, Any]]:
    """Held-out sensitivity, flagged share and PPV of each operating point, overall and by mode."""
    mode_arr = np.array([m.value for m in modes])
    out: dict[str, dict[str, Any]] = {}
    for name, f in flags.items():
        share = f.mean(axis=0)  # share of repeats flagging each row

        def rates(
            sel: npt.NDArray[np.int64], share: FloatArray = share, f: BoolArray = f
        ) -> dict[str, Any]:
            reps = [triage_rates(y[sel], fr[sel]) for fr in f]
            sens = float(np.mean([r.sensitivity for r in reps]))
            flagged = float(np.mean([r.flagged for r in reps]))
            ppv = float(np.nanmean([r.ppv for r in reps]))
            yy, ss = y[sel], share[sel]
            ci_s = bootstrap_ci(lambda ix: _wmean(ss[ix], yy[ix] == 1), _local(indices, sel))
            ci_f = bootstrap_ci(lambda ix: float(ss[ix].mean()), _local(indices, sel))
            return {
                "sensitivity": sens,
                "sensitivity_ci95": list(ci_s),
                "flagged": flagged,
                "flagged_ci95": list(ci_f),
                "ppv": ppv,
                "n": int(sel.size),
                "positives": int(yy.sum()),
            }

        res = {"overall": rates(np.arange(y.size))}
        for m in FieldMode:
            res[m.value] = rates(np.flatnonzero(mode_arr == m.value))
        res["thresholds"] = {m.value: float(t) for m, t in thresholds[name].items()}
        out[name] = res
    return out


def _wmean(values: FloatArray, mask: npt.NDArray[np.bool_]) -> float:
    return float(values[mask].mean()) if mask.any() else float("nan")


def _local(
    indices: Sequence[npt.NDArray[np.int64]], sel: npt.NDArray[np.int64]
) -> list[npt.NDArray[np.int64]]:
    """Bootstrap resamples restricted to the rows `sel`, as positions within `sel`."""
    pos = np.full(max(int(sel.max()) + 1, 1), -1, dtype=np.int64)
    pos[sel] = np.arange(sel.size)
    out = []
    for ix in indices[:1000]:
        local = pos[ix[ix <= sel.max()]]
        out.append(local[local >= 0])
    return out


def _police_figures(
    police: Sequence[FieldCase],
    beta: FloatArray,
    imputation: Imputation,
    sex: _SexOffset,
    cfg: FitConfig,
    cache_dir: Path | None,
    workers: int | None,
    progress: bool,
) -> dict[str, Any]:
    """The field model on NASS-CDS 1997-2000 frontal occupants (police A+K outcome).

    The field model is not fitted on these rows except for the sex offset,
    which is estimated in the training folds (5 folds by PSU); the baseline is
    refitted in the same folds. AUCs are survey-weighted and unweighted.
    """
    notes = [police_notification(c, i) for i, c in enumerate(police)]
    sha = hashlib.sha256(police_data_path().read_bytes()).hexdigest()
    evidence = evidence_for(
        notes, f"police-{sha[:12]}", cache_dir=cache_dir, workers=workers, progress=progress
    )
    y = np.array([c.serious for c in police], dtype=float)
    w = np.array([c.weight for c in police])
    psu = np.array([c.psu for c in police])
    x, _ = design_matrix([ev.inputs for ev in evidence], imputation)
    eta = x @ beta
    female = np.array([ev.inputs.sex is Sex.FEMALE for ev in evidence], dtype=float)
    x_sex = _police_design(police)
    x_base = np.column_stack(
        [
            np.ones(y.size),
            [c.delta_v_kmh for c in police],
            [c.belted for c in police],
            [c.frontal_airbag.value == "deployed" for c in police],
            np.ones(y.size),  # frontal: every row
            [c.age_years for c in police],
            [c.male for c in police],
        ]
    ).astype(float)
    x_base = np.delete(x_base, 4, axis=1)  # frontal is constant here
    ids = np.unique(psu)
    perm = np.random.default_rng(cfg.seed).permutation(ids.size)
    fold_of = dict(zip(ids[perm], np.arange(ids.size) % cfg.n_splits, strict=True))
    fold = np.array([fold_of[g] for g in psu])
    p_field_cv = np.empty(y.size)
    p_base_cv = np.empty(y.size)
    for k in range(cfg.n_splits):
        te, tr = fold == k, fold != k
        b, _ = _female_log_or(x_sex[tr], y[tr], w[tr])
        s = float(np.average(female[tr], weights=w[tr]))
        p_field_cv[te] = _expit(eta[te] + b * (female[te] - s))
        fit = sm.GLM(
            y[tr], x_base[tr], family=sm.families.Binomial(), var_weights=w[tr] / w[tr].mean()
        ).fit()
        p_base_cv[te] = _expit(x_base[te] @ np.asarray(fit.params))
    p_field_shipped = _expit(eta + sex.log_odds_ratio * (female - sex.female_share))
    p_prev = np.array([ev.p_previous_decision for ev in evidence])
    band_midpoint_kmh = np.array([c.delta_v_kmh for c in police])
    rows = {
        "field_model_cv": ("field model (sex offset fitted in the training folds)", p_field_cv),
        "field_model_no_sex": ("field model without the sex offset", _expit(eta)),
        "baseline_cv": ("statistical baseline, refitted in the training folds", p_base_cv),
        "delta_v": ("delta-V band alone", band_midpoint_kmh),
        "occupant_models": ("occupant models' P as decided before", p_prev),
    }
    out: dict[str, Any] = {
        "n": int(y.size),
        "positives": int(y.sum()),
        "weighted_rate": float(np.average(y, weights=w)),
        "auc": {
            name: {
                "description": desc,
                "auc_weighted": auc(y, p, w),
                "auc_unweighted": auc(y, p),
            }
            for name, (desc, p) in rows.items()
        },
    }
    out["shipped_probability"] = p_field_shipped
    out["cv_probability"] = p_field_cv
    out["y"] = y
    out["w"] = w
    return out


# ------------------------------------------------------------------ writing


def write_artifact(doc: dict[str, Any], path: Path | None = None) -> Path:
    """Write the artifact as indented JSON (LF line ends); returns its path."""
    target = path or default_artifact_path()
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n", encoding="utf-8")
    return target
