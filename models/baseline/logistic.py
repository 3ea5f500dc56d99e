"""The statistical baseline at prediction time: load the artifact, predict a risk.

The model is a logistic regression fitted by :mod:`models.offline.baseline.fit` on
NASS-CDS 1997-2000 (``docs/baseline/MODEL_CARD.md``)::

    logit P(serious injury) = b0 + b1 delta_v_kmh + b2 belted + b3 airbag_deployed
                              + b4 frontal + b5 age_years + b6 male

The outcome is police-reported incapacitating or fatal injury (``injSeverity``
3 or 4), a proxy for ISS15+, not ISS15+ itself.

The 95 % interval comes from the coefficient covariance (cluster-robust by
PSU, stored in the artifact) by the delta method on the logit:
``se = sqrt(x' V x)``, ``CI = expit(x' b -/+ z se)`` with ``z = 1.95996``; it
is never a constant. Unknown age or sex is replaced by the weighted mean of the
training data stored in the artifact (the imputation's own uncertainty is not
propagated).

This module needs only numpy; the fit (statsmodels, scikit-learn) lives in
:mod:`models.offline.baseline.fit`.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np
import numpy.typing as npt

from models import constants, limits
from models.arrays import FloatArray
from models.notification import Sex

__all__ = [
    "ARTIFACT_SCHEMA",
    "FEATURE_NAMES",
    "INPUT_FEATURE_NAMES",
    "MAX_AGE_YEARS",
    "MAX_DELTA_V_KMH",
    "MODEL_NAME",
    "MODEL_VERSION",
    "Z_95",
    "BaselineFeatures",
    "BaselineModel",
    "BaselinePrediction",
    "BaselinePredictions",
    "default_artifact_path",
    "load_default",
]


#: Identifier of the artifact layout written by :mod:`models.offline.baseline.fit`.
ARTIFACT_SCHEMA: Final[str] = "aacn-triage/baseline-logistic/1"

#: Model name and version written into the artifact (bump the version on refit
#: with different data, features or rules).
MODEL_NAME: Final[str] = "nass_logistic"
MODEL_VERSION: Final[str] = "1.0.0"

#: Design-matrix columns, in order (the intercept first).
FEATURE_NAMES: Final[tuple[str, ...]] = (
    "intercept",
    "delta_v_kmh",
    "belted",
    "airbag_deployed",
    "frontal",
    "age_years",
    "male",
)

#: Columns of the ``X`` given to :meth:`BaselineModel.predict_many`.
INPUT_FEATURE_NAMES: Final[tuple[str, ...]] = FEATURE_NAMES[1:]

#: Two-sided 95 % standard normal quantile, ``Phi^-1(0.975)``.
Z_95: Final[float] = constants.Z_95

#: Largest delta-V and age accepted (the engine's limits, ``models/limits.py``).
MAX_DELTA_V_KMH: Final[float] = limits.MAX_DELTA_V_KMH
MAX_AGE_YEARS: Final[float] = limits.MAX_AGE_YEARS

_ARTIFACT_FILE: Final[str] = "nass_logistic_v1.json"
_SYMMETRY_RTOL: Final[float] = 1e-9


@dataclass(frozen=True)
class BaselineFeatures:
    """Inputs of the baseline for one occupant.

    Attributes
    ----------
    delta_v_kmh : float
        Resultant delta-V of the vehicle, km/h; 0 to 200. The model was fitted
        on banded delta-V (band midpoints; ``MODEL_CARD.md``).
    belted : bool
        Seat belt worn.
    airbag_deployed : bool
        One or more airbags deployed (NASS-CDS ``deploy``).
    frontal : bool
        Frontal impact (NASS-CDS ``frontal``; from the PDOF use
        :attr:`models.impact_mode.ImpactClassification.frontal_nass`).
    age_years : float or None
        Age, years (0 to 120); None imputes the training weighted mean.
    sex : Sex or None
        None imputes the training weighted share of males.
    """

    delta_v_kmh: float
    belted: bool
    airbag_deployed: bool
    frontal: bool
    age_years: float | None = None
    sex: Sex | None = None


@dataclass(frozen=True)
class BaselinePrediction:
    """Risk of serious injury for one occupant.

    Attributes
    ----------
    probability : float
        P(police-reported incapacitating or fatal injury), in (0, 1).
    ci95 : tuple of float
        95 % interval of the probability from the coefficient covariance
        (delta method on the logit), ``(low, high)``.
    linear_predictor : float
        ``x' b``, the logit of `probability`.
    standard_error : float
        Standard error of the linear predictor, ``sqrt(x' V x)`` (logit scale).
    """

    probability: float
    ci95: tuple[float, float]
    linear_predictor: float
    standard_error: float


@dataclass(frozen=True, eq=False)
class BaselinePredictions:
    """Vectorised :class:`BaselinePrediction` (read-only arrays, shape (n,))."""

    probability: FloatArray
    ci95_low: FloatArray
    ci95_high: FloatArray
    linear_predictor: FloatArray
    standard_error: FloatArray


def _expit(x: FloatArray) -> FloatArray:
    """Logistic function, overflow-safe."""
    out: FloatArray = np.empty_like(x)
    pos = x >= 0.0
    out[pos] = 1.0 / (1.0 + np.exp(-x[pos]))
    e = np.exp(x[~pos])
    out[~pos] = e / (1.0 + e)
    return out


def _expit_one(x: float) -> float:
    """:func:`_expit` of one value: the same numbers."""
    if x >= 0.0:
        return float(1.0 / (1.0 + np.exp(np.float64(-x))))
    e = np.exp(np.float64(x))
    return float(e / (1.0 + e))


def _readonly(a: npt.ArrayLike) -> FloatArray:
    arr = np.array(a, dtype=np.float64)
    arr.setflags(write=False)
    return arr


class _ArtifactError(ValueError):
    """A malformed artifact (a ValueError)."""


def _get(obj: Any, key: str, where: str) -> Any:
    if not isinstance(obj, dict) or key not in obj:
        raise _ArtifactError(f"missing `{where}{key}`")
    return obj[key]


def _finite(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise _ArtifactError(f"`{where}` must be a number")
    x = float(value)
    if not math.isfinite(x):
        raise _ArtifactError(f"`{where}` must be finite")
    return x


def _string(value: Any, where: str) -> str:
    if not isinstance(value, str) or not value:
        raise _ArtifactError(f"`{where}` must be a non-empty string")
    return value


@dataclass(frozen=True, eq=False)
class BaselineModel:
    """The fitted baseline (immutable: frozen, read-only arrays).

    Build it with :meth:`from_artifact` or :func:`load_default`.

    Attributes
    ----------
    name, version : str
        Model name and version from the artifact.
    sha256 : str
        sha256 of the artifact file bytes (hex).
    threshold : float
        Decision threshold on the probability: flag when ``probability >=
        threshold`` (the rule is in the artifact and ``MODEL_CARD.md``).
    feature_names : tuple of str
        Design-matrix columns, :data:`FEATURE_NAMES`.
    coefficients : ndarray, shape (7,)
        Logit coefficients, per :data:`FEATURE_NAMES` (delta-V per km/h, age
        per year).
    covariance : ndarray, shape (7, 7)
        Coefficient covariance (cluster-robust by PSU).
    impute_age_years : float
        Age used when it is unknown, years.
    impute_male : float
        Value of the ``male`` indicator used when sex is unknown.
    fit_date : str
        Date of the fit (ISO 8601).
    data_sha256 : str
        sha256 of the training CSV.
    """

    name: str
    version: str
    sha256: str
    threshold: float
    feature_names: tuple[str, ...]
    coefficients: FloatArray
    covariance: FloatArray
    impute_age_years: float
    impute_male: float
    fit_date: str
    data_sha256: str

    @classmethod
    def from_artifact(cls, path: str | Path) -> BaselineModel:
        """Load and validate a JSON artifact written by :mod:`models.offline.baseline.fit`.

        Parameters
        ----------
        path : str or Path
            The artifact file.

        Returns
        -------
        BaselineModel

        Raises
        ------
        ValueError
            If the file is not JSON or does not hold a valid baseline (wrong
            schema, features, shapes, non-finite numbers, a covariance that is
            not symmetric positive semi-definite, a threshold outside (0, 1)).
        OSError
            If the file cannot be read.
        """
        p = Path(path)
        raw = p.read_bytes()
        try:
            return cls._from_bytes(raw)
        except _ArtifactError as exc:
            raise ValueError(f"malformed baseline artifact {p}: {exc}.") from None

    @classmethod
    def _from_bytes(cls, raw: bytes) -> BaselineModel:
        try:
            doc = json.loads(raw.decode("utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise _ArtifactError(f"not valid UTF-8 JSON ({exc})") from None
        if not isinstance(doc, dict):
            raise _ArtifactError("the top level must be an object")
        schema = _get(doc, "schema", "")
        if schema != ARTIFACT_SCHEMA:
            raise _ArtifactError(f"`schema` must be {ARTIFACT_SCHEMA!r}, got {schema!r}")
        model = _get(doc, "model", "")
        name = _string(_get(model, "name", "model."), "model.name")
        version = _string(_get(model, "version", "model."), "model.version")
        names = _get(doc, "feature_names", "")
        if not isinstance(names, list) or tuple(names) != FEATURE_NAMES:
            raise _ArtifactError(f"`feature_names` must be {list(FEATURE_NAMES)}")
        k = len(FEATURE_NAMES)
        coef_raw = _get(doc, "coefficients", "")
        if not isinstance(coef_raw, list) or len(coef_raw) != k:
            raise _ArtifactError(f"`coefficients` must be a list of {k} numbers")
        coef = np.array([_finite(c, f"coefficients[{i}]") for i, c in enumerate(coef_raw)])
        cov_raw = _get(doc, "covariance", "")
        if (
            not isinstance(cov_raw, list)
            or len(cov_raw) != k
            or not all(isinstance(row, list) and len(row) == k for row in cov_raw)
        ):
            raise _ArtifactError(f"`covariance` must be a {k}x{k} list of lists")
        cov = np.array(
            [
                [_finite(v, f"covariance[{i}][{j}]") for j, v in enumerate(r)]
                for i, r in enumerate(cov_raw)
            ]
        )
        scale = float(np.max(np.abs(cov))) or 1.0
        if not np.allclose(cov, cov.T, rtol=_SYMMETRY_RTOL, atol=_SYMMETRY_RTOL * scale):
            raise _ArtifactError("`covariance` must be symmetric")
        if np.any(np.diag(cov) <= 0.0):
            raise _ArtifactError("`covariance` must have a positive diagonal")
        if float(np.min(np.linalg.eigvalsh(cov))) < -1e-12 * scale:
            raise _ArtifactError("`covariance` must be positive semi-definite")
        thr = _finite(_get(_get(doc, "threshold", ""), "value", "threshold."), "threshold.value")
        if not 0.0 < thr < 1.0:
            raise _ArtifactError("`threshold.value` must lie in (0, 1)")
        imp = _get(doc, "imputation", "")
        age = _finite(_get(imp, "age_years", "imputation."), "imputation.age_years")
        if not 0.0 <= age <= MAX_AGE_YEARS:
            raise _ArtifactError(f"`imputation.age_years` must lie in [0, {MAX_AGE_YEARS:g}]")
        male = _finite(_get(imp, "male", "imputation."), "imputation.male")
        if not 0.0 <= male <= 1.0:
            raise _ArtifactError("`imputation.male` must lie in [0, 1]")
        fit_date = _string(_get(doc, "fit_date", ""), "fit_date")
        data_sha = _string(_get(_get(doc, "data", ""), "sha256", "data."), "data.sha256")
        return cls(
            name=name,
            version=version,
            sha256=hashlib.sha256(raw).hexdigest(),
            threshold=thr,
            feature_names=FEATURE_NAMES,
            coefficients=_readonly(coef),
            covariance=_readonly(cov),
            impute_age_years=age,
            impute_male=male,
            fit_date=fit_date,
            data_sha256=data_sha,
        )

    # ------------------------------------------------------------------ encoding

    def encode(self, features: BaselineFeatures) -> FloatArray:
        """Design-matrix row for `features` (unknowns imputed).

        Parameters
        ----------
        features : BaselineFeatures

        Returns
        -------
        ndarray, shape (7,)
            Values per :data:`FEATURE_NAMES`.

        Raises
        ------
        ValueError
            Naming the field, if delta-V or age is not finite or out of range,
            or a flag is not a bool, or `sex` is not a :class:`Sex`.
        """
        f = features
        dv = _check_number("delta_v_kmh", f.delta_v_kmh, 0.0, MAX_DELTA_V_KMH)
        for field in ("belted", "airbag_deployed", "frontal"):
            if not isinstance(getattr(f, field), bool | np.bool_):
                raise ValueError(f"`{field}` must be a bool.")
        if f.age_years is None:
            age = self.impute_age_years
        else:
            age = _check_number("age_years", f.age_years, 0.0, MAX_AGE_YEARS)
        if f.sex is None:
            male = self.impute_male
        elif isinstance(f.sex, Sex):
            male = 1.0 if f.sex is Sex.MALE else 0.0
        else:
            raise ValueError(f"`sex` must be a Sex or None, got {f.sex!r}.")
        return np.array(
            [1.0, dv, float(f.belted), float(f.airbag_deployed), float(f.frontal), age, male]
        )

    # ------------------------------------------------------------------ prediction

    def _predict_design(self, x: FloatArray) -> BaselinePredictions:
        eta = x @ self.coefficients
        var = np.einsum("ij,jk,ik->i", x, self.covariance, x)
        se = np.sqrt(np.maximum(var, 0.0))
        return BaselinePredictions(
            probability=_readonly(_expit(eta)),
            ci95_low=_readonly(_expit(eta - Z_95 * se)),
            ci95_high=_readonly(_expit(eta + Z_95 * se)),
            linear_predictor=_readonly(eta),
            standard_error=_readonly(se),
        )

    def predict(self, features: BaselineFeatures) -> BaselinePrediction:
        """Risk of serious injury for one occupant.

        Parameters
        ----------
        features : BaselineFeatures

        Returns
        -------
        BaselinePrediction
            Probability, its 95 % interval, the logit and its standard error.

        Raises
        ------
        ValueError
            As :meth:`encode`.
        """
        x = self.encode(features)[None, :]
        # the arithmetic of _predict_design on one row, the logistic in numpy
        # scalars (their exponential is the array loop's: the same bits)
        eta = float((x @ self.coefficients)[0])
        var = float(np.einsum("ij,jk,ik->i", x, self.covariance, x)[0])
        se = float(np.sqrt(max(var, 0.0)))
        return BaselinePrediction(
            probability=_expit_one(eta),
            ci95=(_expit_one(eta - Z_95 * se), _expit_one(eta + Z_95 * se)),
            linear_predictor=eta,
            standard_error=se,
        )

    def predict_many(self, X: npt.ArrayLike) -> BaselinePredictions:
        """Vectorised prediction.

        Parameters
        ----------
        X : array_like, shape (n, 6)
            Columns per :data:`INPUT_FEATURE_NAMES`: delta-V (km/h), belted,
            airbag deployed, frontal (0/1), age (years), male (0/1). NaN in the
            age or male column imputes as in :meth:`predict`.

        Returns
        -------
        BaselinePredictions
            Arrays of shape (n,); row i equals ``predict`` of the same inputs.

        Raises
        ------
        ValueError
            If `X` has the wrong shape, a flag is not 0/1, or delta-V or age is
            non-finite or out of range.
        """
        a = np.array(X, dtype=np.float64, ndmin=2)
        m = len(INPUT_FEATURE_NAMES)
        if a.ndim != 2 or a.shape[1] != m:
            raise ValueError(f"`X` must have shape (n, {m}), got {a.shape}.")
        dv, age, male = a[:, 0], a[:, 4], a[:, 5]
        if not (np.all(np.isfinite(dv)) and np.all((dv >= 0.0) & (dv <= MAX_DELTA_V_KMH))):
            raise ValueError(
                f"`delta_v_kmh` (column 0) must be finite, in [0, {MAX_DELTA_V_KMH:g}]."
            )
        for j in (1, 2, 3):
            if not np.all((a[:, j] == 0.0) | (a[:, j] == 1.0)):
                raise ValueError(f"`{INPUT_FEATURE_NAMES[j]}` (column {j}) must be 0 or 1.")
        age = np.where(np.isnan(age), self.impute_age_years, age)
        if not np.all(np.isfinite(age) & (age >= 0.0) & (age <= MAX_AGE_YEARS)):
            raise ValueError(f"`age_years` (column 4) must be NaN or in [0, {MAX_AGE_YEARS:g}].")
        male = np.where(np.isnan(male), self.impute_male, male)
        if not np.all((male == 0.0) | (male == 1.0) | (male == self.impute_male)):
            raise ValueError("`male` (column 5) must be 0, 1 or NaN.")
        x = np.column_stack([np.ones(a.shape[0]), a[:, :4], age, male])
        return self._predict_design(x)


def _check_number(name: str, value: object, lo: float, hi: float) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise ValueError(f"`{name}` must be a number, got {type(value).__name__}.")
    x = float(value)
    if not math.isfinite(x) or not lo <= x <= hi:
        raise ValueError(f"`{name}` must be finite and in [{lo:g}, {hi:g}], got {x!r}.")
    return x


def default_artifact_path() -> Path:
    """Path of the shipped artifact, ``models/baseline/artifacts/nass_logistic_v1.json``."""
    return Path(__file__).resolve().parent / "artifacts" / _ARTIFACT_FILE


def load_default() -> BaselineModel:
    """Load the shipped artifact (:func:`default_artifact_path`)."""
    return BaselineModel.from_artifact(default_artifact_path())
