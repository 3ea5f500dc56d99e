"""The field risk model at request time: load and verify the artifact, predict P(MAIS 3+).

The model is a penalised logistic regression fitted offline on real NASS-CDS
crashes (:mod:`models.offline.field.fit`; model card in
``docs/field/MODEL_CARD.md``)::

    logit P(MAIS 3+) = x' b + sex offset

with ``x`` the design row of :mod:`models.field.features`. The sex offset is
borrowed from NASS-CDS 1997-2000 (the MAIS file has no sex column):
``b_female (female - female share)``, zero when sex is unknown.

The 95 % interval is the field model's own uncertainty: the standard deviation
of the logit over bootstrap refits (the calibration rows, and the 1997-2000 rows
for the sex offset, resampled and the whole fit repeated) stored in the
artifact, ``expit(eta -/+ z sd)``. The point estimate lies inside it by
construction. Posture and seat position do not enter this model, so their sensor
uncertainty does not widen this interval (it widens the occupant model's).

The artifact carries the checksum of its own content and of the code that
builds its features (:func:`models.codehash.source_tree_sha256`): a tampered
artifact or one fitted for other feature code is refused at load, and the
service is then not ready. This module needs only numpy.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any, Final

import numpy as np

from models.arrays import FloatArray
from models.codehash import source_tree_sha256
from models.constants import Z_95
from models.field.features import (
    FEATURE_NAMES,
    FieldInputs,
    FieldMode,
    Imputation,
    design_matrix,
)
from models.notification import Sex

__all__ = [
    "ARTIFACT_SCHEMA",
    "WITHDRAWN_VERSIONS",
    "OUTCOME",
    "FieldModel",
    "FieldPrediction",
    "OperatingPoint",
    "ArtifactError",
    "canonical_content_sha256",
    "verified_document",
    "default_artifact_path",
    "feature_code_sha256",
    "load_default",
]


#: Identifier of the artifact layout written by the offline fit.
ARTIFACT_SCHEMA: Final[str] = "aacn-triage/field-logistic/1"

#: The outcome the field model gives a probability of: maximum AIS 3 or more
#: (NASS-CDS), the stand-in for ISS 15+ (a conservative one: one AIS 3 injury
#: alone is ISS 9).
OUTCOME: Final[str] = "MAIS3+"

_ARTIFACT_FILE: Final[str] = "field_mais3.json"

#: Sources whose code decides the model's features (paths under ``models/``).
_FEATURE_SOURCES: Final[tuple[str, ...]] = ("field/features.py",)


@lru_cache(maxsize=1)
def feature_code_sha256() -> str:
    """Checksum of the normalised code that builds the features (docstrings and layout aside)."""
    root = Path(__file__).resolve().parents[1]
    return source_tree_sha256([root / rel for rel in _FEATURE_SOURCES])


def canonical_content_sha256(doc: Mapping[str, Any]) -> str:
    """SHA-256 of an artifact document without its ``content_sha256`` (canonical JSON)."""
    body = {k: v for k, v in doc.items() if k != "content_sha256"}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


@dataclass(frozen=True)
class OperatingPoint:
    """A named set of decision thresholds on P(MAIS 3+), one per crash mode.

    Attributes
    ----------
    name : str
    description : str
    thresholds : Mapping[FieldMode, float]
        Flag when ``probability >= threshold``.
    """

    name: str
    description: str
    thresholds: Mapping[FieldMode, float]


@dataclass(frozen=True)
class FieldPrediction:
    """P(MAIS 3+) of one occupant.

    Attributes
    ----------
    probability : float
    ci95 : (float, float)
        95 % interval (bootstrap refits, logit scale); holds `probability`.
    logit : float
        Linear predictor including the sex offset.
    logit_sd : float
        Bootstrap standard deviation of the logit.
    mode : FieldMode
    imputed : tuple of str
        Inputs that were unknown and imputed (``age_years``, ``bmi``).
    extrapolated : bool
        Delta-V above the largest delta-V of the calibration data.
    """

    probability: float
    ci95: tuple[float, float]
    logit: float
    logit_sd: float
    mode: FieldMode
    imputed: tuple[str, ...]
    extrapolated: bool


class ArtifactError(ValueError):
    """A field model artifact (either kind) that is malformed, altered or stale: the reason."""


def _get(obj: Any, key: str) -> Any:
    if not isinstance(obj, dict) or key not in obj:
        raise ArtifactError(f"missing `{key}`")
    return obj[key]


def verified_document(
    raw: bytes, *, schema: str, feature_sha256: str | Callable[[dict[str, Any]], str]
) -> dict[str, Any]:
    """A field model artifact's JSON object, its schema, content and feature code checked.

    Parameters
    ----------
    raw : bytes
        The artifact file's bytes.
    schema : str
        The ``schema`` the artifact must declare (each kind has its own).
    feature_sha256 : str or callable
        The checksum of the feature code the artifact must have been fitted for,
        or a function of the document giving it (an artifact names its feature
        set; it is called after the content checksum holds).

    Raises
    ------
    ArtifactError
        Not UTF-8 JSON, another schema, altered content or stale feature code.
    """
    try:
        doc = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ArtifactError(f"not valid UTF-8 JSON ({exc})") from None
    if not isinstance(doc, dict) or doc.get("schema") != schema:
        raise ArtifactError(f"`schema` must be {schema!r}")
    if _get(doc, "content_sha256") != canonical_content_sha256(doc):
        raise ArtifactError("content checksum mismatch (the artifact was altered)")
    expected = feature_sha256 if isinstance(feature_sha256, str) else feature_sha256(doc)
    if _get(doc, "feature_code_sha256") != expected:
        raise ArtifactError("stale: fitted for other feature code; run `aacn-triage fit-field`")
    return doc


def _vector(value: Any, n: int, where: str) -> FloatArray:
    arr = np.array(value, dtype=np.float64)
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise ArtifactError(f"`{where}` must be {n} finite numbers")
    return arr


def _readonly(a: FloatArray) -> FloatArray:
    a = np.array(a, dtype=np.float64)
    a.setflags(write=False)
    return a


def _expit(x: float) -> float:
    if x >= 0.0:
        return 1.0 / (1.0 + math.exp(-x))
    e = math.exp(x)
    return e / (1.0 + e)


@dataclass(frozen=True, eq=False)
class FieldModel:
    """The fitted field model (immutable). Build it with :meth:`from_artifact`.

    Attributes
    ----------
    name, version : str
    sha256 : str
        SHA-256 of the artifact file's bytes (recorded with every case).
    outcome : str
        :data:`OUTCOME`.
    coefficients : ndarray, shape (k,)
        Per :data:`models.field.features.FEATURE_NAMES`.
    bootstrap_coefficients : ndarray, shape (B, k)
    sex_log_odds_ratio : float
        Female against male (logit).
    sex_bootstrap : ndarray, shape (B,)
    female_share : float
        Share of women the offset is centred on.
    imputation : Imputation
    delta_v_max_kmh : float
        Largest delta-V of the calibration data, km/h.
    operating_points : Mapping[str, OperatingPoint]
    default_operating_point : str
    document : Mapping[str, Any]
        The whole artifact (model card figures).
    """

    name: str
    version: str
    sha256: str
    outcome: str
    coefficients: FloatArray
    bootstrap_coefficients: FloatArray
    sex_log_odds_ratio: float
    sex_bootstrap: FloatArray
    female_share: float
    imputation: Imputation
    delta_v_max_kmh: float
    operating_points: Mapping[str, OperatingPoint]
    default_operating_point: str
    document: Mapping[str, Any]

    @classmethod
    def from_artifact(cls, path: str | Path) -> FieldModel:
        """Load, verify and validate an artifact.

        Raises
        ------
        ValueError
            Not the schema, malformed, tampered (its content checksum does not
            match), or fitted for other feature code (stale).
        OSError
            The file cannot be read.
        """
        p = Path(path)
        raw = p.read_bytes()
        try:
            return cls._from_bytes(raw)
        except ArtifactError as exc:
            raise ValueError(f"field model artifact {p}: {exc}") from None

    @classmethod
    def from_document(cls, doc: Mapping[str, Any]) -> FieldModel:
        """Load and verify an artifact document not yet written (the offline fit's).

        Raises
        ------
        ValueError
            As :meth:`from_artifact`.
        """
        raw = json.dumps(doc, indent=1, allow_nan=False).encode()
        try:
            return cls._from_bytes(raw)
        except ArtifactError as exc:
            raise ValueError(f"field model document: {exc}") from None

    @classmethod
    def _from_bytes(cls, raw: bytes) -> FieldModel:
        doc = verified_document(raw, schema=ARTIFACT_SCHEMA, feature_sha256=feature_code_sha256())
        if tuple(_get(doc, "feature_names")) != FEATURE_NAMES:
            raise ArtifactError(f"`feature_names` must be {list(FEATURE_NAMES)}")
        k = len(FEATURE_NAMES)
        coef = _vector(_get(doc, "coefficients"), k, "coefficients")
        boot = np.array(_get(doc, "bootstrap_coefficients"), dtype=np.float64)
        if boot.ndim != 2 or boot.shape[1] != k or boot.shape[0] < 2:
            raise ArtifactError("`bootstrap_coefficients` must be B >= 2 rows of k numbers")
        if not np.all(np.isfinite(boot)):
            raise ArtifactError("`bootstrap_coefficients` must be finite")
        sex = _get(doc, "sex_offset")
        b_sex = float(_get(sex, "log_odds_ratio_female"))
        sex_boot = _vector(_get(sex, "bootstrap"), boot.shape[0], "sex_offset.bootstrap")
        share = float(_get(sex, "female_share"))
        if not (math.isfinite(b_sex) and 0.0 <= share <= 1.0):
            raise ArtifactError("`sex_offset` must hold a finite log odds ratio and a share")
        imp = _get(doc, "imputation")
        imputation = Imputation(
            age_years=float(_get(imp, "age_years")), bmi=float(_get(imp, "bmi"))
        )
        points = {}
        for name, op in _get(doc, "operating_points").items():
            thresholds = {FieldMode(m): float(t) for m, t in _get(op, "thresholds").items()}
            if set(thresholds) != set(FieldMode) or not all(
                0.0 < t < 1.0 for t in thresholds.values()
            ):
                raise ArtifactError(f"operating point {name!r}: a threshold in (0, 1) per mode")
            points[name] = OperatingPoint(
                name=name, description=str(_get(op, "description")), thresholds=thresholds
            )
        default = _get(doc, "default_operating_point")
        if default not in points:
            raise ArtifactError(f"default operating point {default!r} is not defined")
        model = _get(doc, "model")
        return cls(
            name=str(_get(model, "name")),
            version=str(_get(model, "version")),
            sha256=hashlib.sha256(raw).hexdigest(),
            outcome=str(_get(doc, "outcome")),
            coefficients=_readonly(coef),
            bootstrap_coefficients=_readonly(boot),
            sex_log_odds_ratio=b_sex,
            sex_bootstrap=_readonly(sex_boot),
            female_share=share,
            imputation=imputation,
            delta_v_max_kmh=float(_get(_get(doc, "data"), "delta_v_max_kmh")),
            operating_points=points,
            default_operating_point=default,
            document=doc,
        )

    def _sex_indicator(self, sex: Sex | None) -> float | None:
        if sex is None:
            return None
        return 1.0 if sex is Sex.FEMALE else 0.0

    def predict(self, inputs: FieldInputs) -> FieldPrediction:
        """P(MAIS 3+) of one occupant with its 95 % interval.

        Parameters
        ----------
        inputs : FieldInputs

        Returns
        -------
        FieldPrediction

        Raises
        ------
        ValueError
            Delta-V or age out of range (naming the field).
        """
        x, imputed = design_matrix([inputs], self.imputation)
        row = x[0]
        eta = float(row @ self.coefficients)
        eta_b = self.bootstrap_coefficients @ row
        female = self._sex_indicator(inputs.sex)
        if female is not None:
            eta += self.sex_log_odds_ratio * (female - self.female_share)
            eta_b = eta_b + self.sex_bootstrap * (female - self.female_share)
        sd = float(np.std(eta_b, ddof=1))
        p = _expit(eta)
        ci = (min(_expit(eta - Z_95 * sd), p), max(_expit(eta + Z_95 * sd), p))
        return FieldPrediction(
            probability=p,
            ci95=ci,
            logit=eta,
            logit_sd=sd,
            mode=inputs.mode,
            imputed=imputed[0],
            extrapolated=inputs.delta_v_kmh > self.delta_v_max_kmh,
        )

    def threshold(self, mode: FieldMode, operating_point: str | None = None) -> float:
        """Decision threshold of `mode` at `operating_point` (default: the artifact's).

        Raises
        ------
        KeyError
            An operating point the artifact does not define.
        """
        name = operating_point or self.default_operating_point
        return self.operating_points[name].thresholds[mode]


def default_artifact_path() -> Path:
    """The shipped artifact, ``models/field/artifacts/field_mais3.json``."""
    return Path(__file__).resolve().parent / "artifacts" / _ARTIFACT_FILE


#: Field model versions withdrawn for a defect, with the defect: never served (the
#: service is not ready with one), kept byte for byte for recall reports
#: (``aacn-triage cases rescore``) and forensic replays.
WITHDRAWN_VERSIONS: Final[Mapping[str, str]] = {
    "1.0.0": (
        "fitted on an mph delta-V column read as km/h: it reads every notification at 1.6 "
        "times its delta-V and over-triages (issue 32; refitted as 2.0.0)"
    ),
}


def load_default() -> FieldModel:
    """Load and verify the shipped artifact."""
    return FieldModel.from_artifact(default_artifact_path())
