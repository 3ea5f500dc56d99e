"""Reproducible fit of the statistical baseline on NASS-CDS 1997-2000.

Run ``python -m models.offline.baseline.fit`` (the service exposes it as
``aacn-triage baseline fit``). It reads the shipped CSV
(``models/offline/data/nass-cds-1997-2000.csv``, see ``PROVENANCE.md``) and
writes ``models/baseline/artifacts/nass_logistic_v1.json``.

Model
-----
Survey-weighted logistic regression (statsmodels ``GLM``, ``Binomial`` family,
logit link, ``var_weights`` = NASS national inflation factor ``weight``
normalised to mean 1 over the rows used), a pseudo-maximum-likelihood fit::

    logit P(y) = b0 + b1 delta_v_kmh + b2 belted + b3 airbag_deployed
                 + b4 frontal + b5 age_years + b6 male

Outcome and rows
----------------
``y = 1`` when ``injSeverity`` is 3 (incapacitating) or 4 (killed), police
reported: a proxy for serious injury, **not** ISS15+. Rows with
``injSeverity`` 5 (unknown), 6 (prior death) or empty (``NA``) are excluded:
their outcome is unknown or not caused by the crash. Rows with weight 0
(193 rows) carry no weight in any weighted estimate and are dropped as well.

Encoding
--------
* ``delta_v_kmh``: the band midpoint, :data:`DELTA_V_BAND_MIDPOINTS_KMH`
  (``1-9`` -> 5, ``10-24`` -> 17, ``25-39`` -> 32, ``40-54`` -> 47). The
  open band ``55+`` is given 62 km/h, the midpoint of a 15 km/h wide band
  55-69 like the three bands below it. [R] Among values 58-75 for the open
  band the weighted deviance is lowest at 62; using 60 or 75 instead moves the
  delta-V slope by +1 % or -9 % (``MODEL_CARD.md``). At predict time delta-V
  is continuous.
* ``belted``: ``seatbelt == "belted"``; ``airbag_deployed``: ``deploy == 1``;
  ``frontal``: ``frontal == 1``; ``age_years``: ``ageOFocc``;
  ``male``: ``sex == "m"``.

Standard errors
---------------
Cluster-robust (sandwich) covariance with the primary sampling unit (PSU, the
first field of ``caseid``; 24 PSUs) as the cluster, CR1 small-sample factor
``G/(G-1) (N-1)/(N-K)``::

    V = c H^-1 (sum_g s_g s_g') H^-1,  H = X' diag(w p (1-p)) X,
    s_g = sum_{i in g} w_i (y_i - p_i) x_i

It accounts for the unequal weights and the clustering of cases within PSUs;
NASS strata are not in the data, so it ignores stratification (conservative).
It equals statsmodels' ``cov_type="cluster"`` (checked in the tests); it is
computed here because statsmodels flags that covariance as "not fully
supported" with weights.

Validation and threshold
------------------------
* Held-out by year: fit on accident years 1997-1999, evaluate on 2000.
* 5-fold cross-validation, folds by crash (accident year, PSU and case, so
  both front-seat occupants of a vehicle fall in the same fold), assigned by a
  seeded permutation (``seed``).
* AUCs are survey-weighted (``sklearn.metrics.roc_auc_score`` with the weights).
* Under-triage (UT) = weighted share of serious-injury occupants with
  ``p < threshold``; over-triage (OT) = weighted share of the others with
  ``p >= threshold``.
* Threshold rule: the largest threshold, floored to 0.001, whose weighted
  *out-of-fold* UT is at most :data:`UNDER_TRIAGE_TARGET` = 5 %, the ACS-COT
  field-triage benchmark (``crash-data-and-triage.md`` section 4). The same
  rule applied to 1997-1999 alone gives the threshold used for the year-2000
  held-out UT/OT.
"""

from __future__ import annotations

import argparse
import csv
import datetime as dt
import hashlib
import json
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np
import numpy.typing as npt
import statsmodels.api as sm
from sklearn.metrics import roc_auc_score

from models.arrays import FloatArray, IntArray
from models.baseline.logistic import (
    ARTIFACT_SCHEMA,
    FEATURE_NAMES,
    MODEL_NAME,
    MODEL_VERSION,
    default_artifact_path,
)
from models.offline.paths import DATA_DIR

__all__ = [
    "CV_FOLDS",
    "DELTA_V_BAND_MIDPOINTS_KMH",
    "EXCLUDED_SEVERITIES",
    "HOLDOUT_YEAR",
    "SERIOUS_SEVERITIES",
    "THRESHOLD_RESOLUTION",
    "UNDER_TRIAGE_TARGET",
    "FitReport",
    "cluster_robust_covariance",
    "default_data_path",
    "fit_baseline",
    "main",
    "triage_rates",
    "under_triage_threshold",
]


#: Midpoint used for each delta-V band of ``dvcat``, km/h (module docstring).
DELTA_V_BAND_MIDPOINTS_KMH: Final[dict[str, float]] = {
    "1-9km/h": 5.0,
    "10-24": 17.0,
    "25-39": 32.0,
    "40-54": 47.0,
    "55+": 62.0,
}

#: ``injSeverity`` values counted as serious injury: 3 incapacitating, 4 killed.
SERIOUS_SEVERITIES: Final[frozenset[int]] = frozenset({3, 4})

#: ``injSeverity`` values kept as not serious: 0 none, 1 possible, 2 non-incapacitating.
NOT_SERIOUS_SEVERITIES: Final[frozenset[int]] = frozenset({0, 1, 2})

#: ``injSeverity`` values excluded: 5 unknown, 6 prior death (empty is excluded too).
EXCLUDED_SEVERITIES: Final[frozenset[int]] = frozenset({5, 6})

#: Accident year held out for validation; the model for it is fitted on earlier years.
HOLDOUT_YEAR: Final[int] = 2000

#: Number of cross-validation folds.
CV_FOLDS: Final[int] = 5

#: Largest weighted under-triage accepted when choosing the threshold: the
#: ACS-COT benchmark UT <= 5 % (crash-data-and-triage.md section 4) [V].
UNDER_TRIAGE_TARGET: Final[float] = 0.05

#: Thresholds are floored to this resolution (keeps UT within the target).
THRESHOLD_RESOLUTION: Final[float] = 0.001

#: Thresholds reported for comparison: Lubbe 2 %, Bahouth 5 % side / 10 %
#: frontal, CDC 20 % (crash-data-and-triage.md sections 1 and 4).
COMPARISON_THRESHOLDS: Final[tuple[float, ...]] = (0.02, 0.05, 0.10, 0.20)

_REQUIRED_COLUMNS: Final[tuple[str, ...]] = (
    "dvcat",
    "weight",
    "seatbelt",
    "frontal",
    "sex",
    "ageOFocc",
    "yearacc",
    "deploy",
    "injSeverity",
    "caseid",
)

_MAX_ITER: Final[int] = 100
_TOL: Final[float] = 1e-12


def default_data_path() -> Path:
    """Path of the shipped training data, ``models/offline/data/nass-cds-1997-2000.csv``."""
    return DATA_DIR / "nass-cds-1997-2000.csv"


@dataclass(frozen=True)
class _Data:
    """The rows used, as arrays."""

    x: FloatArray  # (n, 7) design matrix
    y: FloatArray  # (n,) 0/1
    weight: FloatArray  # (n,) raw NASS weights, > 0
    year: IntArray  # (n,)
    psu: IntArray  # (n,)
    crash: IntArray  # (n,) crash id (year, PSU, case) as an integer code
    counts: dict[str, int]


@dataclass(frozen=True)
class FitReport:
    """Summary of a fit (the full record is the artifact).

    Attributes
    ----------
    artifact_path : Path
        Where the artifact was written.
    artifact_sha256 : str
        sha256 of the artifact bytes.
    data_sha256 : str
        sha256 of the CSV.
    feature_names : tuple of str
    coefficients : tuple of float
        Logit coefficients per feature (delta-V per km/h, age per year).
    standard_errors : tuple of float
        Cluster-robust standard errors.
    threshold : float
        Chosen decision threshold (probability).
    rows_used : int
    holdout_auc : float
        Weighted AUC on accident year 2000 (fitted on 1997-1999).
    cv_auc_mean : float
        Mean of the per-fold weighted AUCs.
    cv_under_triage, cv_over_triage : float
        Weighted out-of-fold UT and OT at `threshold`.
    holdout_under_triage, holdout_over_triage : float
        Weighted UT and OT on 2000 at the threshold chosen on 1997-1999.
    """

    artifact_path: Path
    artifact_sha256: str
    data_sha256: str
    feature_names: tuple[str, ...]
    coefficients: tuple[float, ...]
    standard_errors: tuple[float, ...]
    threshold: float
    rows_used: int
    holdout_auc: float
    cv_auc_mean: float
    cv_under_triage: float
    cv_over_triage: float
    holdout_under_triage: float
    holdout_over_triage: float


# --------------------------------------------------------------------------- data


def _parse_int(text: str, column: str, line: int) -> int:
    try:
        return int(text)
    except ValueError:
        raise ValueError(f"line {line}: `{column}` = {text!r} is not an integer.") from None


def _load(csv_path: Path) -> _Data:
    """Read and encode the CSV; counts of rows kept and excluded."""
    counts = {
        "rows_in_file": 0,
        "excluded_injseverity_missing": 0,
        "excluded_injseverity_5_unknown": 0,
        "excluded_injseverity_6_prior_death": 0,
        "excluded_zero_weight": 0,
    }
    rows: list[list[float]] = []
    ys: list[float] = []
    ws: list[float] = []
    years: list[int] = []
    psus: list[int] = []
    crashes: list[str] = []
    with csv_path.open(newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        missing = [c for c in _REQUIRED_COLUMNS if c not in (reader.fieldnames or [])]
        if missing:
            raise ValueError(f"{csv_path}: missing columns {missing}.")
        for line, rec in enumerate(reader, start=2):
            counts["rows_in_file"] += 1
            sev_text = rec["injSeverity"].strip()
            if sev_text in ("", "NA"):
                counts["excluded_injseverity_missing"] += 1
                continue
            sev = int(float(sev_text))
            if sev == 5:
                counts["excluded_injseverity_5_unknown"] += 1
                continue
            if sev == 6:
                counts["excluded_injseverity_6_prior_death"] += 1
                continue
            if sev not in SERIOUS_SEVERITIES | NOT_SERIOUS_SEVERITIES:
                raise ValueError(f"line {line}: unknown injSeverity {sev_text!r}.")
            weight = float(rec["weight"])
            if not math.isfinite(weight) or weight < 0.0:
                raise ValueError(f"line {line}: `weight` = {rec['weight']!r} is not >= 0.")
            if weight == 0.0:
                counts["excluded_zero_weight"] += 1
                continue
            band = rec["dvcat"]
            if band not in DELTA_V_BAND_MIDPOINTS_KMH:
                raise ValueError(f"line {line}: unknown dvcat {band!r}.")
            belt = {"belted": 1.0, "none": 0.0}.get(rec["seatbelt"])
            sex = {"m": 1.0, "f": 0.0}.get(rec["sex"])
            deploy = _parse_int(rec["deploy"], "deploy", line)
            frontal = _parse_int(rec["frontal"], "frontal", line)
            if belt is None or sex is None or deploy not in (0, 1) or frontal not in (0, 1):
                raise ValueError(f"line {line}: unexpected seatbelt/sex/deploy/frontal value.")
            age = float(_parse_int(rec["ageOFocc"], "ageOFocc", line))
            year = _parse_int(rec["yearacc"], "yearacc", line)
            psu_text, case_text, _vehicle = rec["caseid"].split(":")
            rows.append(
                [
                    1.0,
                    DELTA_V_BAND_MIDPOINTS_KMH[band],
                    belt,
                    float(deploy),
                    float(frontal),
                    age,
                    sex,
                ]
            )
            ys.append(1.0 if sev in SERIOUS_SEVERITIES else 0.0)
            ws.append(weight)
            years.append(year)
            psus.append(_parse_int(psu_text, "caseid", line))
            crashes.append(f"{year}:{psu_text}:{case_text}")
    if not rows:
        raise ValueError(f"{csv_path}: no usable rows.")
    _, crash_codes = np.unique(np.array(crashes), return_inverse=True)
    counts["rows_used"] = len(rows)
    return _Data(
        x=np.array(rows, dtype=np.float64),
        y=np.array(ys, dtype=np.float64),
        weight=np.array(ws, dtype=np.float64),
        year=np.array(years, dtype=np.int64),
        psu=np.array(psus, dtype=np.int64),
        crash=crash_codes.astype(np.int64),
        counts=counts,
    )


# --------------------------------------------------------------------------- model


def _expit(eta: FloatArray) -> FloatArray:
    out: FloatArray = 0.5 * (1.0 + np.tanh(0.5 * eta))
    return out


def _fit_glm(x: FloatArray, y: FloatArray, weight: FloatArray) -> FloatArray:
    """Weighted logistic regression (statsmodels GLM Binomial, IRLS); coefficients."""
    w = weight / weight.mean()
    model = sm.GLM(y, x, family=sm.families.Binomial(), var_weights=w)
    res = model.fit(maxiter=_MAX_ITER, tol=_TOL)
    if not res.converged:
        raise RuntimeError("the weighted logistic regression did not converge.")
    params: FloatArray = np.asarray(res.params, dtype=np.float64)
    return params


def cluster_robust_covariance(
    x: FloatArray, y: FloatArray, weight: FloatArray, beta: FloatArray, clusters: npt.ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Cluster-robust (CR1) and model-based covariance of weighted logistic coefficients.

    Parameters
    ----------
    x : ndarray, shape (n, k)
        Design matrix.
    y : ndarray, shape (n,)
        Outcome, 0/1.
    weight : ndarray, shape (n,)
        Survey weights (any scale; normalised to mean 1 here).
    beta : ndarray, shape (k,)
        Fitted coefficients.
    clusters : array_like, shape (n,)
        Cluster label of each row (PSU).

    Returns
    -------
    robust : ndarray, shape (k, k)
        ``G/(G-1) (n-1)/(n-k) H^-1 M H^-1`` with ``H = X' diag(w p (1-p)) X``
        and ``M = sum_g s_g s_g'``, ``s_g = sum_{i in g} w_i (y_i - p_i) x_i``.
    naive : ndarray, shape (k, k)
        ``H^-1``, the covariance if the weights were frequencies (too small
        for survey data; reported for comparison only).
    """
    w = weight / weight.mean()
    p = _expit(x @ beta)
    hessian = (x * (w * p * (1.0 - p))[:, None]).T @ x
    h_inv = np.linalg.inv(hessian)
    scores = x * (w * (y - p))[:, None]
    _, codes = np.unique(np.asarray(clusters), return_inverse=True)
    g = int(codes.max()) + 1
    per_cluster = np.zeros((g, x.shape[1]))
    np.add.at(per_cluster, codes, scores)
    meat = per_cluster.T @ per_cluster
    n, k = x.shape
    factor = g / (g - 1.0) * (n - 1.0) / (n - k)
    robust = factor * h_inv @ meat @ h_inv
    robust = 0.5 * (robust + robust.T)
    naive = 0.5 * (h_inv + h_inv.T)
    return robust, naive


# --------------------------------------------------------------------------- metrics


def _auc(y: FloatArray, p: FloatArray, weight: FloatArray) -> float:
    return float(roc_auc_score(y, p, sample_weight=weight))


def triage_rates(
    y: FloatArray, p: FloatArray, weight: FloatArray, threshold: float
) -> tuple[float, float]:
    """Weighted under- and over-triage at a threshold.

    Parameters
    ----------
    y : ndarray, shape (n,)
        1 serious, 0 not.
    p : ndarray, shape (n,)
        Predicted probabilities.
    weight : ndarray, shape (n,)
        Survey weights.
    threshold : float
        Flag when ``p >= threshold``.

    Returns
    -------
    under_triage : float
        Weighted share of serious cases with ``p < threshold``.
    over_triage : float
        Weighted share of non-serious cases with ``p >= threshold``.
    """
    pos = y == 1.0
    flagged = p >= threshold
    ut = float(weight[pos & ~flagged].sum() / weight[pos].sum())
    ot = float(weight[~pos & flagged].sum() / weight[~pos].sum())
    return ut, ot


def under_triage_threshold(
    y: FloatArray, p: FloatArray, weight: FloatArray, target: float = UNDER_TRIAGE_TARGET
) -> float:
    """Largest threshold (floored to 0.001) with weighted under-triage <= `target`.

    Parameters
    ----------
    y, p, weight : ndarray, shape (n,)
        Outcome (0/1), predicted probability, survey weight.
    target : float
        Largest acceptable weighted under-triage, in [0, 1).

    Returns
    -------
    float
        The threshold. Under-triage at it is at most `target`.
    """
    pos = y == 1.0
    order = np.argsort(p[pos], kind="stable")
    ps = p[pos][order]
    share = np.cumsum(weight[pos][order]) / weight[pos].sum()
    # UT(t) = weight share of positives with p < t; the supremum of the
    # thresholds with UT <= target is the first p whose inclusive share exceeds it.
    k = int(np.searchsorted(share, target, side="right"))
    t_sup = float(ps[min(k, ps.size - 1)])
    steps = math.floor(t_sup / THRESHOLD_RESOLUTION)
    # round() gives the shortest decimal (0.042, not 0.042000000000000003); it
    # moves the value by less than 1e-12, far below the resolution.
    return round(steps * THRESHOLD_RESOLUTION, 12)


def _folds(crash: IntArray, seed: int) -> IntArray:
    """Fold (0..CV_FOLDS-1) of each row; whole crashes per fold, seeded permutation."""
    ids = np.unique(crash)
    perm = np.random.default_rng(seed).permutation(ids.size)
    fold_of_id = np.empty(ids.size, dtype=np.int64)
    fold_of_id[perm] = np.arange(ids.size) % CV_FOLDS
    out: IntArray = fold_of_id[np.searchsorted(ids, crash)]
    return out


def _out_of_fold(data: _Data, rows: IntArray, seed: int) -> tuple[FloatArray, list[float]]:
    """Out-of-fold predictions for `rows` and the weighted AUC of each fold."""
    x, y, w = data.x[rows], data.y[rows], data.weight[rows]
    fold = _folds(data.crash[rows], seed)
    oof = np.empty(rows.size)
    aucs = []
    for k in range(CV_FOLDS):
        test = fold == k
        beta = _fit_glm(x[~test], y[~test], w[~test])
        oof[test] = _expit(x[test] @ beta)
        aucs.append(_auc(y[test], oof[test], w[test]))
    return oof, aucs


# --------------------------------------------------------------------------- fit


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _matrix(a: FloatArray) -> list[list[float]]:
    return [[float(v) for v in row] for row in a]


def _iso_fit_date(fit_date: str | None) -> str:
    """`fit_date` normalised to ISO 8601, or today (UTC) when None."""
    if fit_date is None:
        return dt.datetime.now(dt.UTC).date().isoformat()
    try:
        return dt.date.fromisoformat(fit_date).isoformat()
    except (TypeError, ValueError):
        raise ValueError(
            f"`fit_date` must be an ISO date (YYYY-MM-DD), got {fit_date!r}."
        ) from None


def _model_and_features_doc() -> dict[str, Any]:
    """The artifact's fixed description of the model and of its features."""
    return {
        "model": {
            "name": MODEL_NAME,
            "version": MODEL_VERSION,
            "description": (
                "Survey-weighted logistic regression of police-reported incapacitating or "
                "fatal injury (NASS-CDS injSeverity 3 or 4; a proxy for ISS15+, not ISS15+) "
                "of front-seat occupants of towed passenger vehicles, US, 1997-2000."
            ),
            "library": "statsmodels GLM(Binomial, logit link), var_weights = weight / mean",
        },
        "features": {
            "intercept": {"encoding": "1"},
            "delta_v_kmh": {
                "unit": "km/h",
                "source_column": "dvcat",
                "encoding": "band midpoint at fit time; continuous at predict time",
                "band_midpoints_kmh": dict(DELTA_V_BAND_MIDPOINTS_KMH),
                "open_band_rule": "55+ taken as a 15 km/h band 55-69, midpoint 62 km/h",
            },
            "belted": {"source_column": "seatbelt", "encoding": "1 if 'belted' else 0"},
            "airbag_deployed": {"source_column": "deploy", "encoding": "1 if deploy == 1"},
            "frontal": {
                "source_column": "frontal",
                "encoding": "1 frontal impact, 0 side or rear (not distinguished)",
            },
            "age_years": {"unit": "year", "source_column": "ageOFocc", "encoding": "linear"},
            "male": {"source_column": "sex", "encoding": "1 if 'm' else 0"},
        },
    }


def _threshold_doc(threshold: float) -> dict[str, Any]:
    """The artifact's ``threshold`` section: the value, its rule and why."""
    return {
        "value": threshold,
        "rule": (
            f"largest threshold (floored to {THRESHOLD_RESOLUTION}) with weighted "
            f"out-of-fold under-triage <= {UNDER_TRIAGE_TARGET} ({CV_FOLDS}-fold CV)"
        ),
        "why": (
            "ACS-COT field-triage benchmark: under-triage <= 5 %; missing a seriously "
            "injured occupant costs more than an unneeded trauma-centre alert. The "
            "over-triage that results exceeds the 25-50 % benchmark (see metrics)."
        ),
        "flag_when": "probability >= value",
    }


def _holdout_2000(
    data: _Data, seed: int, threshold: float
) -> tuple[dict[str, Any], npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Held out by year: the model and its threshold chosen on 1997-1999, judged on 2000.

    Returns
    -------
    metrics : dict
        The artifact's ``metrics.holdout_2000`` section.
    train, test : ndarray of int64
        Row indices of the two parts.
    """
    x, y, w = data.x, data.y, data.weight
    train = np.flatnonzero(data.year < HOLDOUT_YEAR).astype(np.int64)
    test = np.flatnonzero(data.year == HOLDOUT_YEAR).astype(np.int64)
    beta_tr = _fit_glm(x[train], y[train], w[train])
    oof_tr, _ = _out_of_fold(data, train, seed)
    thr_tr = under_triage_threshold(y[train], oof_tr, w[train])
    p_te = _expit(x[test] @ beta_tr)
    ho_ut, ho_ot = triage_rates(y[test], p_te, w[test], thr_tr)
    ho_ut_s, ho_ot_s = triage_rates(y[test], p_te, w[test], threshold)
    metrics = {
        "fitted_on": "accident years 1997-1999",
        "auc": _auc(y[test], p_te, w[test]),
        "auc_unweighted": float(roc_auc_score(y[test], p_te)),
        "threshold_chosen_on_1997_1999": thr_tr,
        "under_triage": ho_ut,
        "over_triage": ho_ot,
        "under_triage_at_shipped_threshold": ho_ut_s,
        "over_triage_at_shipped_threshold": ho_ot_s,
    }
    return metrics, train, test


def _counts(
    data: _Data, train: npt.NDArray[np.int64], test: npt.NDArray[np.int64]
) -> dict[str, int]:
    """Row, outcome, cluster and crash counts of the data and of the year hold-out."""
    counts = dict(data.counts)
    counts["rows_serious"] = int(data.y.sum())
    counts["rows_not_serious"] = int(data.y.size - data.y.sum())
    counts["psu_clusters"] = int(np.unique(data.psu).size)
    counts["crashes"] = int(np.unique(data.crash).size)
    counts["rows_holdout_train"] = int(train.size)
    counts["rows_holdout_test"] = int(test.size)
    return counts


def fit_baseline(
    csv_path: str | Path,
    out_path: str | Path,
    *,
    seed: int = 0,
    fit_date: str | None = None,
) -> FitReport:
    """Fit the baseline, validate it and write the JSON artifact.

    Parameters
    ----------
    csv_path : str or Path
        NASS-CDS CSV (the columns of ``data/PROVENANCE.md``).
    out_path : str or Path
        Artifact to write (parent directories are created).
    seed : int, optional
        Seed of the cross-validation fold assignment.
    fit_date : str or None, optional
        ISO 8601 date recorded as the fit date; default today (UTC). The
        output is byte-identical for the same data, seed and `fit_date`.

    Returns
    -------
    FitReport

    Raises
    ------
    ValueError
        If the CSV is missing columns or holds unexpected values, or
        `fit_date` is not an ISO date.
    RuntimeError
        If the regression does not converge.
    """
    csv_path, out_path = Path(csv_path), Path(out_path)
    fit_date = _iso_fit_date(fit_date)
    data = _load(csv_path)
    x, y, w = data.x, data.y, data.weight
    all_rows = np.arange(y.size, dtype=np.int64)

    # Final model on all years.
    beta = _fit_glm(x, y, w)
    cov, naive_cov = cluster_robust_covariance(x, y, w, beta, data.psu)
    se = np.sqrt(np.diag(cov))
    p_in = _expit(x @ beta)

    # Cross-validation and the threshold.
    oof, fold_aucs = _out_of_fold(data, all_rows, seed)
    threshold = under_triage_threshold(y, oof, w)
    cv_ut, cv_ot = triage_rates(y, oof, w, threshold)
    in_ut, in_ot = triage_rates(y, p_in, w, threshold)

    holdout, train, test = _holdout_2000(data, seed, threshold)

    operating_points = []
    for t in sorted({*COMPARISON_THRESHOLDS, threshold}):
        ut, ot = triage_rates(y, oof, w, t)
        operating_points.append({"threshold": t, "under_triage": ut, "over_triage": ot})

    sev_weights = w / w.sum()
    impute_age = float(np.sum(sev_weights * x[:, 5]))
    impute_male = float(np.sum(sev_weights * x[:, 6]))

    doc: dict[str, Any] = {
        "schema": ARTIFACT_SCHEMA,
        **_model_and_features_doc(),
        "fit_date": fit_date,
        "seed": seed,
        "outcome": {
            "name": "serious_injury",
            "definition": "injSeverity in {3 incapacitating, 4 killed} (police KABCO-style)",
            "excluded": "injSeverity 5 (unknown), 6 (prior death) or empty; weight 0",
            "proxy_for": "ISS15+ (not the same: police-reported severity, not AIS/ISS)",
            "weighted_prevalence": float(np.sum(sev_weights * y)),
        },
        "feature_names": list(FEATURE_NAMES),
        "coefficients": [float(b) for b in beta],
        "standard_errors": [float(s) for s in se],
        "covariance": _matrix(cov),
        "covariance_type": (
            "cluster-robust sandwich (CR1), clusters = PSU (first field of caseid), "
            "weights normalised to mean 1; strata not available"
        ),
        "naive_standard_errors": [float(s) for s in np.sqrt(np.diag(naive_cov))],
        "imputation": {
            "age_years": impute_age,
            "male": impute_male,
            "rule": "unknown age or sex -> weighted mean of the training rows",
        },
        "threshold": _threshold_doc(threshold),
        "data": {
            "file": csv_path.name,
            "sha256": _sha256(csv_path),
            "source": "NASS-CDS 1997-2000 via R package DAAG nassCDS (see PROVENANCE.md)",
            "counts": _counts(data, train, test),
        },
        "metrics": {
            "definitions": {
                "auc": "survey-weighted ROC AUC (sklearn roc_auc_score, sample_weight=weight)",
                "under_triage": "weighted share of serious-injury occupants with p < threshold",
                "over_triage": "weighted share of other occupants with p >= threshold",
            },
            "holdout_2000": holdout,
            "cv5": {
                "folds": CV_FOLDS,
                "grouping": "by crash (accident year, PSU, case); seeded permutation",
                "auc_folds": fold_aucs,
                "auc_mean": float(np.mean(fold_aucs)),
                "auc_sd": float(np.std(fold_aucs, ddof=1)),
                "auc_pooled_out_of_fold": _auc(y, oof, w),
                "under_triage": cv_ut,
                "over_triage": cv_ot,
                "note": "the threshold is chosen on these out-of-fold predictions",
            },
            "in_sample": {
                "auc": _auc(y, p_in, w),
                "under_triage": in_ut,
                "over_triage": in_ot,
            },
            "operating_points_out_of_fold": operating_points,
        },
    }
    text = json.dumps(doc, sort_keys=True, indent=2, allow_nan=False) + "\n"
    out_path.parent.mkdir(parents=True, exist_ok=True)
    out_path.write_text(text, encoding="utf-8")
    return FitReport(
        artifact_path=out_path,
        artifact_sha256=hashlib.sha256(text.encode("utf-8")).hexdigest(),
        data_sha256=doc["data"]["sha256"],
        feature_names=FEATURE_NAMES,
        coefficients=tuple(float(b) for b in beta),
        standard_errors=tuple(float(s) for s in se),
        threshold=threshold,
        rows_used=int(y.size),
        holdout_auc=doc["metrics"]["holdout_2000"]["auc"],
        cv_auc_mean=doc["metrics"]["cv5"]["auc_mean"],
        cv_under_triage=cv_ut,
        cv_over_triage=cv_ot,
        holdout_under_triage=holdout["under_triage"],
        holdout_over_triage=holdout["over_triage"],
    )


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: fit the baseline and write the artifact.

    Parameters
    ----------
    argv : sequence of str or None
        Arguments without the program name; None reads ``sys.argv``.

    Returns
    -------
    int
        Exit status (0 on success).
    """
    parser = argparse.ArgumentParser(
        prog="python -m models.offline.baseline.fit",
        description="Fit the NASS-CDS logistic baseline and write its JSON artifact.",
    )
    parser.add_argument("--data", type=Path, default=default_data_path(), help="input CSV")
    parser.add_argument("--out", type=Path, default=default_artifact_path(), help="artifact")
    parser.add_argument("--seed", type=int, default=0, help="seed of the CV folds")
    parser.add_argument("--fit-date", default=None, help="ISO date to record (default today)")
    args = parser.parse_args(argv)
    report = fit_baseline(args.data, args.out, seed=args.seed, fit_date=args.fit_date)
    print(f"wrote {report.artifact_path} (sha256 {report.artifact_sha256})")
    print(f"rows used {report.rows_used}; data sha256 {report.data_sha256}")
    for name, b, s in zip(
        report.feature_names, report.coefficients, report.standard_errors, strict=True
    ):
        print(f"  {name:16s} {b:+.5f}  (se {s:.5f})")
    print(
        f"threshold {report.threshold:.3f}; held-out 2000 AUC {report.holdout_auc:.3f}, "
        f"UT {report.holdout_under_triage:.3f}, OT {report.holdout_over_triage:.3f}; "
        f"5-fold AUC {report.cv_auc_mean:.3f}, UT {report.cv_under_triage:.3f}, "
        f"OT {report.cv_over_triage:.3f}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
