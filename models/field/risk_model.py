"""The field risk models at request time: P(ISS 15+), region AIS 3+ and P(anyone ISS 15+).

Fitted offline on NASS-CDS 1997-2014 (:mod:`models.offline.field.risk_fit`,
``aacn-triage fit-field``; model card ``docs/field/MODEL_CARD.md``), served
with numpy (the trees walked by one compiled loop). One artifact holds several
outcome models, each of one of three kinds (``kind``, chosen per outcome by
cross-validation; an artifact without ``kind``, 3.0.0, holds regressions)::

    eta = x' beta                  (logistic: ranking fit, x: design columns kept)
    eta = mean_j s_j(x)            (boosted: a bag of boosted trees, models.field.boosted)
    logit P = a + b eta            (recalibration with the national weights)
    logit P = (1 - w) logit_logistic + w logit_boosted      (blend, since 3.2.0)

for ``iss15`` (the decision) and ``region_<region>`` (AIS 3+ in each body
region, AIS 2+ where the artifact says so), plus the vehicle answer::

    logit P(anyone ISS 15+) = a_v + b_v logit(1 - prod_i (1 - P_i(ISS 15+)))

recalibrated on held-out vehicles, and never below its riskiest occupant's
P(ISS 15+) (anyone is at least as likely as any one; the held-out figures of the
model card are of the recalibrated value before this floor). The 95 % intervals
are the spread of the calibrated logit over bootstrap refits by crash stored in
the artifact (a bag's members for the boosted kind), ``expit(eta -/+ z sd)``
around the point estimate.

The artifact carries the checksum of its content and of the code that builds
its features (its feature set's: :mod:`models.field.risk_features`, and
:mod:`models.field.risk_impacts` since 3.2.0); a tampered or stale artifact is
refused at load.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property, lru_cache
from pathlib import Path
from typing import Any, Final

import numpy as np

from models.arrays import FloatArray, IntArray
from models.codehash import source_tree_sha256
from models.constants import Z_95
from models.field.boosted import Forest, TreeBag
from models.field.children_calibration import ChildrenCalibration
from models.field.measurement import (
    MEASUREMENT_MODELS,
    DeltaVSource,
    MeasurementModel,
    delta_v_source_of,
    over_reconstructed_nodes,
)
from models.field.model import (  # one artifact check for both kinds
    ArtifactError,
    canonical_content_sha256,
    verified_document,
)
from models.field.risk_children import (
    ALL_COLUMNS_3,
    CHILD_MAX_AGE_YEARS,
    FEATURE_SET_SOURCES_3,
    ChildRiskInputs,
    Restraint,
    design_columns_3,
    inputs_arrays_3,
    restraint_of,
)
from models.field.risk_features import (
    ALL_COLUMNS,
    RiskImputation,
    RiskInputs,
    design_columns,
    inputs_arrays,
)
from models.field.risk_impacts import (
    IMPACT_COUNT_CLAMP,
    design_columns_2,
    inputs_arrays_2,
)
from models.field.unknowns import DonorTable, pick_donors, seat_group, substitute

__all__ = [
    "ARTIFACT_SCHEMA",
    "OUTCOME",
    "AnyOutcomeModel",
    "BlendOutcomeModel",
    "BoostedOutcomeModel",
    "REGION_NAMES",
    "OutcomeModel",
    "RegionRisk",
    "RiskModel",
    "RiskPrediction",
    "VehicleRisk",
    "canonical_content_sha256",
    "default_artifact_path",
    "feature_code_sha256",
    "load_default",
]

#: Identifier of the artifact layout written by the offline fit.
ARTIFACT_SCHEMA: Final[str] = "aacn-triage/field-risk/1"

#: The decision's outcome: ISS 15+ (ISS >= 16 in NASS-CDS), the trauma-center criterion.
OUTCOME: Final[str] = "ISS15+"

#: Body regions of the region risks, in order (AIS 1990 regions).
REGION_NAMES: Final[tuple[str, ...]] = (
    "head",
    "face",
    "neck",
    "thorax",
    "abdomen",
    "spine",
    "upper_extremity",
    "lower_extremity",
)

#: Design columns that carry each input that may be imputed: an imputed input is
#: named in the answer only when a model uses it.
_INPUT_COLUMNS: Final[Mapping[str, tuple[str, ...]]] = {
    "age_years": ("age_years", "age_s1"),
    "female": ("female",),
    "stature_cm": ("stature_cm",),
    "mass_kg": ("mass_kg",),
    "quarter_turns": ("log1p_quarter_turns",),
    "model_year": ("model_year",),
    "impact_count": ("impact_count",),
}

_ARTIFACT_FILE: Final[str] = "field_iss15.json"

#: What was known of an occupant, for the threshold (feature set 3): the
#: operating points keep their promise for each (:meth:`RiskModel.threshold`).
KNOWLEDGE: Final[tuple[str, ...]] = ("adult", "child", "age_unknown")

#: The same with a measured delta-V (read as the reconstruction it stands for,
#: :mod:`models.field.measurement`; decided at the same threshold).
KNOWLEDGE_MEASURED: Final[tuple[str, ...]] = tuple(f"{k}_measured" for k in KNOWLEDGE)


@lru_cache(maxsize=4)
def feature_code_sha256(columns: tuple[str, ...] = ALL_COLUMNS_3) -> str:
    """Checksum of the normalised code that builds the features of a feature set.

    Parameters
    ----------
    columns : tuple of str, optional
        The set's candidate columns (default: the newest set,
        :data:`models.field.risk_children.ALL_COLUMNS_3`).

    Raises
    ------
    KeyError
        Columns of no known feature set.
    """
    root = Path(__file__).resolve().parents[1]
    return source_tree_sha256([root / rel for rel in FEATURE_SET_SOURCES_3[columns]])


def _artifact_feature_sha256(doc: dict[str, Any]) -> str:
    """The feature code checksum an artifact's own feature set must match."""
    columns = tuple(_get(doc, "candidate_columns"))
    if columns not in FEATURE_SET_SOURCES_3:
        raise ArtifactError("`candidate_columns` are of no known feature set")
    return feature_code_sha256(columns)


def _get(obj: Any, key: str) -> Any:
    if not isinstance(obj, dict) or key not in obj:
        raise ArtifactError(f"missing `{key}`")
    return obj[key]


def _matrix(value: Any, shape: tuple[int, ...], where: str) -> FloatArray:
    arr = np.array(value, dtype=np.float64)
    ok = arr.ndim == len(shape) and all(
        s in (-1, a) for s, a in zip(shape, arr.shape, strict=False)
    )
    if not ok or not np.all(np.isfinite(arr)):
        raise ArtifactError(f"`{where}` must be finite numbers of shape {shape}")
    arr.setflags(write=False)
    return arr


def _expit(x: FloatArray) -> FloatArray:
    out: FloatArray = 0.5 * (1.0 + np.tanh(0.5 * x))
    return out


@dataclass(frozen=True, eq=False)
class OutcomeModel:
    """One outcome's fitted model.

    Attributes
    ----------
    name, label : str
        e.g. ``region_head``, ``head AIS3+``.
    ais_level : int or None
    columns : tuple of int
        Indices into the artifact's candidate columns (its feature set's).
    beta : ndarray, shape (k,)
    calibration : ndarray, shape (2,)
        ``(a, b)``.
    bootstrap_beta : ndarray, shape (B, k)
    bootstrap_calibration : ndarray, shape (B, 2)
    """

    name: str
    label: str
    ais_level: int | None
    columns: tuple[int, ...]
    beta: FloatArray
    calibration: FloatArray
    bootstrap_beta: FloatArray
    bootstrap_calibration: FloatArray

    @property
    def n_bootstrap(self) -> int:
        """``B``: bootstrap refits behind the interval."""
        return int(self.bootstrap_beta.shape[0])

    def logits(self, x_all: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Calibrated logit (n,) and its bootstrap refits (n, B) of full design rows (n, K)."""
        x = x_all[:, list(self.columns)]
        eta = self.calibration[0] + self.calibration[1] * (x @ self.beta)
        boot = self.bootstrap_calibration[:, 0] + self.bootstrap_calibration[:, 1] * (
            x @ self.bootstrap_beta.T
        )
        return eta, boot


@dataclass(frozen=True, eq=False)
class BoostedOutcomeModel:
    """One outcome's bag of boosted trees (:mod:`models.field.boosted`).

    ``logit P = a + b mean_j s_j(x)`` over the members' raw scores ``s_j``; the
    members, each fitted on a resample of whole crashes, are the bootstrap
    behind the interval (``a + b s_j(x)``).

    Attributes
    ----------
    name, label : str
    ais_level : int or None
    bag : TreeBag
    calibration : ndarray, shape (2,)
        ``(a, b)``.
    """

    name: str
    label: str
    ais_level: int | None
    bag: TreeBag
    calibration: FloatArray

    @property
    def columns(self) -> tuple[int, ...]:
        """Design columns the trees split on."""
        return self.bag.columns

    @property
    def n_bootstrap(self) -> int:
        """``B``: the members."""
        return self.bag.n_members

    def logits(self, x_all: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Calibrated logit (n,) and each member's (n, B) of full design rows (n, K)."""
        return self.logits_of_scores(self.bag.member_scores(x_all))

    def logits_of_scores(self, scores: FloatArray) -> tuple[FloatArray, FloatArray]:
        """:meth:`logits` from the members' raw scores (n, B) (a forest's, evaluated once)."""
        a, b = float(self.calibration[0]), float(self.calibration[1])
        eta: FloatArray = a + b * scores.mean(axis=1)
        boot: FloatArray = a + b * scores
        return eta, boot


@dataclass(frozen=True, eq=False)
class BlendOutcomeModel:
    """One outcome's blend of a regression and a bag of boosted trees.

    ``logit P = (1 - w) logit_regression + w logit_bag``, each part with its own
    calibration (:mod:`models.offline.field.risk_blend`). The regression's
    bootstrap refits were fitted on the bag's resamples of crashes, in order:
    refit ``j`` blended with member ``j`` is a bootstrap refit of the blend.

    Attributes
    ----------
    name, label : str
    ais_level : int or None
    logistic : OutcomeModel
    boosted : BoostedOutcomeModel
    weight : float
        ``w``, in (0, 1).
    """

    name: str
    label: str
    ais_level: int | None
    logistic: OutcomeModel
    boosted: BoostedOutcomeModel
    weight: float

    @property
    def columns(self) -> tuple[int, ...]:
        """Design columns either part uses."""
        return tuple(sorted(set(self.logistic.columns) | set(self.boosted.columns)))

    @property
    def bag(self) -> TreeBag:
        """The boosted part's trees (walked with the other bags')."""
        return self.boosted.bag

    @property
    def n_bootstrap(self) -> int:
        """``B``: the bag's members (and the regression's refits on their resamples)."""
        return self.boosted.n_bootstrap

    def logits(self, x_all: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Calibrated logit (n,) and its bootstrap refits (n, B) of full design rows (n, K)."""
        return self.logits_of_scores(x_all, self.bag.member_scores(x_all))

    def logits_of_scores(
        self, x_all: FloatArray, scores: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """:meth:`logits` with the bag's raw member scores (n, B) given."""
        e1, b1 = self.logistic.logits(x_all)
        e2, b2 = self.boosted.logits_of_scores(scores)
        w = self.weight
        return (1.0 - w) * e1 + w * e2, (1.0 - w) * b1 + w * b2


#: Any kind of outcome model.
AnyOutcomeModel = OutcomeModel | BoostedOutcomeModel | BlendOutcomeModel


def _interval(eta: float, boot: FloatArray) -> tuple[float, float, float, float]:
    """Probability, 95 % interval (holding it) and logit sd."""
    sd = float(np.std(boot, ddof=1))
    p = float(_expit(np.array(eta)))
    lo = float(_expit(np.array(eta - Z_95 * sd)))
    hi = float(_expit(np.array(eta + Z_95 * sd)))
    return p, min(lo, p), max(hi, p), sd


@dataclass(frozen=True)
class RegionRisk:
    """P(AIS `ais_level`+ injury in one body region) of one occupant.

    Attributes
    ----------
    probability : float
    ci95 : (float, float)
    ais_level : int
        3, or 2 where AIS 3+ is too rare in the data (named in the answer).
    """

    probability: float
    ci95: tuple[float, float]
    ais_level: int


@dataclass(frozen=True, eq=False)
class RiskPrediction:
    """The field risk models' answer for one occupant.

    Attributes
    ----------
    probability : float
        P(ISS 15+).
    ci95 : (float, float)
    logit, logit_sd : float
    mode : str
        ``frontal``, ``near_side``, ``far_side``, ``rear`` or ``rollover``.
    imputed : tuple of str
        Inputs that were unknown and imputed, where a model uses them.
    extrapolated : bool
        Delta-V above the largest of the data.
    regions : Mapping[str, RegionRisk]
        Every region of :data:`REGION_NAMES`.
    bootstrap_probability : ndarray, shape (B,)
        P(ISS 15+) of each bootstrap refit (for the vehicle answer's interval).
    integrated : tuple of str
        Inputs that were unknown and integrated over (feature set 3:
        :mod:`models.field.unknowns`); empty when every input was known.
    unknown_inputs_range95 : (float, float) or None
        The spread of P(ISS 15+) over the unknown inputs: the 2.5 and 97.5
        percentiles over the donors averaged (None when nothing was
        integrated). Not a confidence interval: ``ci95`` is the probability's.
    knowledge : str
        What was known, for the threshold: ``adult`` (age known, 16+),
        ``child`` (age known, under 16) or ``age_unknown``.
    """

    probability: float
    ci95: tuple[float, float]
    logit: float
    logit_sd: float
    mode: str
    imputed: tuple[str, ...]
    extrapolated: bool
    regions: Mapping[str, RegionRisk]
    bootstrap_probability: FloatArray
    integrated: tuple[str, ...] = ()
    unknown_inputs_range95: tuple[float, float] | None = None
    knowledge: str = "adult"


@dataclass(frozen=True)
class VehicleRisk:
    """P(anyone in the vehicle ISS 15+) with its 95 % interval."""

    probability: float
    ci95: tuple[float, float]


def knowledge_of(inputs: RiskInputs, measured: bool = False) -> str:
    """What was known of an occupant, for the threshold (:data:`KNOWLEDGE`): ``adult``,
    ``child`` or ``age_unknown``, with ``_measured`` where its delta-V was measured and
    read through the measurement model."""
    if inputs.age_years is None:
        base = "age_unknown"
    else:
        base = "child" if inputs.age_years < CHILD_MAX_AGE_YEARS else "adult"
    return f"{base}_measured" if measured else base


def _logit(p: FloatArray) -> FloatArray:
    q = np.clip(p, 1e-15, 1.0 - 1e-15)
    out: FloatArray = np.log(q) - np.log1p(-q)
    return out


def _recal(p: float, a: float, b: float) -> float:
    """One probability through the recalibration ``expit(a + b logit p)``."""
    return float(_expit(a + b * _logit(np.array(p))))


def _integrated(
    logits: Sequence[tuple[FloatArray, FloatArray]], owner: IntArray, weight: FloatArray, n: int
) -> tuple[FloatArray, FloatArray, FloatArray, list[tuple[float, float] | None]]:
    """Weighted means over each occupant's rows: calibrated logit (k, n), refits' logit sd
    (k, n), P(ISS 15+) of each refit (n, B), and the spread over the rows of P(ISS 15+)
    (weighted 2.5 and 97.5 percentiles; None for an occupant of one row)."""
    etas, sds = [], []
    boot_first: FloatArray = np.empty((0, 0))
    for k, (e, b) in enumerate(logits):
        pm = np.zeros(n)
        np.add.at(pm, owner, weight * _expit(e))
        pb = np.zeros((n, b.shape[1]))
        np.add.at(pb, owner, weight[:, None] * _expit(b))
        etas.append(_logit(pm))
        sds.append(np.std(_logit(pb), axis=1, ddof=1))
        if k == 0:
            boot_first = pb
    p0 = _expit(logits[0][0])
    spread: list[tuple[float, float] | None] = []
    for i in range(n):
        rows = owner == i
        if rows.sum() == 1:
            spread.append(None)
            continue
        order = np.argsort(p0[rows], kind="stable")
        values, cum = p0[rows][order], np.cumsum(weight[rows][order])
        lo = values[min(int(np.searchsorted(cum, 0.025 * cum[-1])), values.size - 1)]
        hi = values[min(int(np.searchsorted(cum, 0.975 * cum[-1])), values.size - 1)]
        spread.append((float(lo), float(hi)))
    return np.stack(etas), np.stack(sds), boot_first, spread


def _modes(x_all: FloatArray, inputs: Sequence[RiskInputs]) -> list[str]:
    """Crash mode of each occupant from its design row (rollover when reported)."""
    col = {n: x_all[:, ALL_COLUMNS.index(n)] for n in ("near_side", "far_side", "rear")}
    out = []
    for i, f in enumerate(inputs):
        if f.rollover:
            out.append("rollover")
        elif col["near_side"][i]:
            out.append("near_side")
        elif col["far_side"][i]:
            out.append("far_side")
        else:
            out.append("rear" if col["rear"][i] else "frontal")
    return out


@dataclass(frozen=True, eq=False)
class RiskModel:
    """The fitted field risk models (immutable). Build with :meth:`from_artifact`.

    Attributes
    ----------
    name, version, sha256, outcome : str
    decision : AnyOutcomeModel
        ISS 15+.
    regions : Mapping[str, AnyOutcomeModel]
    vehicle_calibration : ndarray, shape (2,)
    vehicle_bootstrap_calibration : ndarray, shape (B, 2)
    imputation : RiskImputation
    delta_v_max_kmh : float
    thresholds : Mapping[str, float]
        Operating point name -> threshold on P(ISS 15+).
    operating_point_descriptions : Mapping[str, str]
    default_operating_point : str
    document : Mapping[str, Any]
    candidate_columns : tuple of str
        The feature set's design columns (the outcome models index them).
    impact_count_imputed : float or None
        Feature sets 2 and 3: the impact count taken for multiple impacts of
        unknown count (None: feature set 1, no count).
    donors : DonorTable or None
        Feature set 3: the fitted population's donors that unknown inputs are
        integrated over (None: older sets impute medians).
    knowledge_thresholds : Mapping[str, Mapping[str, float]]
        Feature set 3: per operating point, the threshold by what was known
        (``adult``, ``child``, ``age_unknown``; a measured delta-V takes the
        same); empty for older artifacts, whose one threshold applies to every
        occupant.
    measurement : MeasurementModel or None
        The delta-V measurement model a measured delta-V is read through
        (:mod:`models.field.measurement`; 3.3.0 on). None: every delta-V is
        taken as reconstructed, as the data's (older artifacts).
    recalibration : (float, float) or None
        ``(a, b)`` of a local recalibration of the decision,
        ``logit P = a + b logit P_decided`` (:mod:`models.field.recalibration`),
        applied to the decided probability, its interval and refits, and the
        spread over unknown inputs; None: the national model as fitted.
    children : ChildrenCalibration or None
        The children's own calibration of the decision (by age group and child
        seat, :mod:`models.field.children_calibration`; 3.4.0 on), applied to
        every child row before the integration over unknown inputs; None: the
        shared calibration for everyone (older artifacts).
    """

    name: str
    version: str
    sha256: str
    outcome: str
    decision: AnyOutcomeModel
    regions: Mapping[str, AnyOutcomeModel]
    vehicle_calibration: FloatArray
    vehicle_bootstrap_calibration: FloatArray
    imputation: RiskImputation
    delta_v_max_kmh: float
    thresholds: Mapping[str, float]
    operating_point_descriptions: Mapping[str, str]
    default_operating_point: str
    document: Mapping[str, Any]
    candidate_columns: tuple[str, ...] = ALL_COLUMNS
    impact_count_imputed: float | None = None
    donors: DonorTable | None = None
    knowledge_thresholds: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    measurement: MeasurementModel | None = None
    recalibration: tuple[float, float] | None = None
    children: ChildrenCalibration | None = None

    @classmethod
    def from_artifact(cls, path: str | Path) -> RiskModel:
        """Load, verify and validate an artifact.

        Raises
        ------
        ValueError
            Not the schema, malformed, tampered or stale.
        OSError
            The file cannot be read.
        """
        p = Path(path)
        try:
            return cls._from_bytes(p.read_bytes())
        except ArtifactError as exc:
            raise ValueError(f"field risk artifact {p}: {exc}") from None

    @classmethod
    def from_document(cls, doc: Mapping[str, Any]) -> RiskModel:
        """Load and verify a document not yet written (the offline fit's)."""
        raw = json.dumps(doc, indent=1, allow_nan=False).encode()
        try:
            return cls._from_bytes(raw)
        except ArtifactError as exc:
            raise ValueError(f"field risk document: {exc}") from None

    @staticmethod
    def _outcome(name: str, od: Any, candidates: tuple[str, ...]) -> AnyOutcomeModel:
        kind = od.get("kind", "logistic") if isinstance(od, dict) else None
        if kind == "blend":
            w = od.get("weight_boosted")
            if not isinstance(w, float) or not 0.0 < w < 1.0:
                raise ArtifactError(f"outcome {name!r}: `weight_boosted` must be in (0, 1)")
            common = {"label": _get(od, "label"), "ais_level": od.get("ais_level")}
            parts = [
                RiskModel._outcome(name, {**_get(od, part), **common}, candidates)
                for part in ("logistic", "boosted")
            ]
            lr_part, bag_part = parts
            if not isinstance(lr_part, OutcomeModel) or not isinstance(
                bag_part, BoostedOutcomeModel
            ):
                raise ArtifactError(f"outcome {name!r}: a blend of a logistic and a boosted part")
            if lr_part.n_bootstrap != bag_part.n_bootstrap:
                raise ArtifactError(f"outcome {name!r}: one refit per member of the bag")
            return BlendOutcomeModel(name, lr_part.label, lr_part.ais_level, lr_part, bag_part, w)
        if kind == "boosted":
            level = od.get("ais_level")
            try:
                bag = TreeBag.from_document(_get(od, "trees"), candidates, f"{name}.trees")
            except ValueError as exc:
                raise ArtifactError(str(exc)) from None
            if bag.n_members < 2:
                raise ArtifactError(f"outcome {name!r}: at least 2 members")
            return BoostedOutcomeModel(
                name=name,
                label=str(_get(od, "label")),
                ais_level=None if level is None else int(level),
                bag=bag,
                calibration=_matrix(_get(od, "calibration"), (2,), f"{name}.calibration"),
            )
        if kind != "logistic":
            raise ArtifactError(f"outcome {name!r}: `kind` must be logistic, boosted or blend")
        names = list(_get(od, "columns"))
        if not names or names[0] != "intercept" or not set(names) <= set(candidates):
            raise ArtifactError(f"outcome {name!r}: `columns` must be known, intercept first")
        k = len(names)
        beta = _matrix(_get(od, "coefficients"), (k,), f"{name}.coefficients")
        boot = _matrix(_get(od, "bootstrap_coefficients"), (-1, k), f"{name}.bootstrap")
        cal = _matrix(_get(od, "calibration"), (2,), f"{name}.calibration")
        bcal = _matrix(_get(od, "bootstrap_calibration"), (boot.shape[0], 2), f"{name}.bcal")
        if boot.shape[0] < 2:
            raise ArtifactError(f"outcome {name!r}: at least 2 bootstrap refits")
        level = od.get("ais_level")
        return OutcomeModel(
            name=name,
            label=str(_get(od, "label")),
            ais_level=None if level is None else int(level),
            columns=tuple(candidates.index(c) for c in names),
            beta=beta,
            calibration=cal,
            bootstrap_beta=boot,
            bootstrap_calibration=bcal,
        )

    @classmethod
    def _from_bytes(cls, raw: bytes) -> RiskModel:
        doc = verified_document(
            raw, schema=ARTIFACT_SCHEMA, feature_sha256=_artifact_feature_sha256
        )
        cand = tuple(str(c) for c in doc["candidate_columns"])
        outs = _get(doc, "outcomes")
        decision = cls._outcome("iss15", _get(outs, "iss15"), cand)
        regions = {
            r: cls._outcome(f"region_{r}", _get(outs, f"region_{r}"), cand) for r in REGION_NAMES
        }
        veh = _get(doc, "vehicle")
        vcal = _matrix(_get(veh, "calibration"), (2,), "vehicle.calibration")
        vboot = _matrix(
            _get(veh, "bootstrap_calibration"),
            (decision.n_bootstrap, 2),
            "vehicle.bcal",
        )
        imp = _get(doc, "imputation")
        imputation = RiskImputation(
            **{k: float(_get(imp, k)) for k in RiskImputation.__dataclass_fields__}
        )
        # feature set 2: the count imputed for multiple impacts of unknown count
        count = float(_get(imp, "impact_count")) if cand != ALL_COLUMNS else None
        top = IMPACT_COUNT_CLAMP[1]  # a count of multiple impacts, within the served clamp
        if count is not None and not 2.0 <= count <= top:
            raise ArtifactError(f"`imputation.impact_count` must be in [2, {top:g}]")
        points = _get(doc, "operating_points")
        thresholds = {str(n): float(_get(op, "threshold")) for n, op in points.items()}
        if not all(0.0 < t < 1.0 for t in thresholds.values()):
            raise ArtifactError("operating point thresholds must be in (0, 1)")
        default = _get(doc, "default_operating_point")
        if default not in thresholds:
            raise ArtifactError(f"default operating point {default!r} is not defined")
        donors, by_knowledge = None, {}
        measurement = None
        if "measurement_model" in doc:
            mm = _get(doc, "measurement_model")
            name, version = str(_get(mm, "name")), str(_get(mm, "version"))
            known = MEASUREMENT_MODELS.get(version)
            if known is None or known.name != name:
                raise ArtifactError(
                    f"measurement model {name}@{version} is not one this code knows "
                    f"({', '.join(m.label for m in MEASUREMENT_MODELS.values())})"
                )
            measurement = known
        if cand == ALL_COLUMNS_3:
            try:
                donors = DonorTable.from_document(_get(_get(doc, "unknowns"), "donors"))
            except ValueError as exc:
                raise ArtifactError(str(exc)) from None
            for n, op in points.items():
                table = {str(k): float(v) for k, v in _get(op, "thresholds_by_knowledge").items()}
                if set(table) != set(KNOWLEDGE) or not all(0 < t < 1 for t in table.values()):
                    raise ArtifactError(f"operating point {n!r}: thresholds by knowledge malformed")
                by_knowledge[str(n)] = table
        model = _get(doc, "model")
        recal = None
        if "recalibration" in doc:
            rc = _get(doc, "recalibration")
            recal = (float(_get(rc, "intercept")), float(_get(rc, "slope")))
            if not all(np.isfinite(recal)) or recal[1] <= 0.0:
                raise ArtifactError("`recalibration` must be finite with a positive slope")
        children = None
        if "children_calibration" in doc:
            try:
                children = ChildrenCalibration.from_document(
                    _get(doc, "children_calibration"), cand, decision.n_bootstrap
                )
            except ValueError as exc:
                raise ArtifactError(str(exc)) from None
        return cls(
            name=str(_get(model, "name")),
            version=str(_get(model, "version")),
            sha256=hashlib.sha256(raw).hexdigest(),
            outcome=str(_get(doc, "outcome")),
            decision=decision,
            regions=regions,
            vehicle_calibration=vcal,
            vehicle_bootstrap_calibration=vboot,
            imputation=imputation,
            delta_v_max_kmh=float(_get(_get(doc, "data"), "delta_v_max_kmh")),
            thresholds=thresholds,
            operating_point_descriptions={
                str(n): str(_get(op, "description")) for n, op in points.items()
            },
            default_operating_point=str(default),
            document=doc,
            candidate_columns=cand,
            impact_count_imputed=count,
            donors=donors,
            knowledge_thresholds=by_knowledge,
            measurement=measurement,
            recalibration=recal,
            children=children,
        )

    def design(
        self, inputs: Sequence[RiskInputs]
    ) -> tuple[FloatArray, tuple[tuple[str, ...], ...]]:
        """Full design rows (n, K) of `inputs` and the inputs imputed per occupant.

        ``K`` is the artifact's feature set's: feature set 2
        (:mod:`models.field.risk_impacts`) reads the impact count of
        :class:`~models.field.risk_impacts.ImpactRiskInputs`; feature set 3
        needs every occupant input known (:meth:`expanded_design` integrates).
        """
        if self.donors is not None:
            assert self.impact_count_imputed is not None
            arrays, imputed = inputs_arrays_3(inputs, self.imputation, self.impact_count_imputed)
            return design_columns_3(arrays), imputed
        if self.impact_count_imputed is not None:
            arrays, imputed = inputs_arrays_2(inputs, self.imputation, self.impact_count_imputed)
            return design_columns_2(arrays), imputed
        arrays, imputed = inputs_arrays(inputs, self.imputation)
        return design_columns(arrays), imputed

    def expanded_design(
        self, inputs: Sequence[RiskInputs]
    ) -> tuple[
        FloatArray, IntArray, FloatArray, tuple[tuple[str, ...], ...], tuple[tuple[str, ...], ...]
    ]:
        """Design rows with each occupant's unknown inputs expanded over its donors, and
        a measured delta-V over the reconstructions it allows.

        Returns
        -------
        x : ndarray, shape (N, K)
        owner : ndarray of int, shape (N,)
            The occupant of each row (an occupant with every input known and a
            reconstructed delta-V has one).
        weight : ndarray, shape (N,)
            Each row's weight within its occupant (summing to 1).
        imputed : tuple of tuple of str
            Per occupant, the vehicle inputs imputed (quarter turns, model year,
            impact count).
        integrated : tuple of tuple of str
            Per occupant, the inputs integrated over (``delta_v_kmh``: a measured
            delta-V read through the measurement model).
        """
        if self.donors is None:
            x, imputed = self.design(inputs)
            n = len(inputs)
            return x, np.arange(n), np.ones(n), imputed, tuple(() for _ in inputs)
        stand_ins, blocks, integrated = [], [], []  # unknown inputs: values the donors replace
        measured: dict[int, float] = {}
        for i, f in enumerate(inputs):
            restraint = restraint_of(f)
            unknown = tuple(
                name
                for name, value in (
                    ("age_years", f.age_years),
                    ("female", f.female),
                    ("stature_cm", f.stature_cm),
                    ("mass_kg", f.mass_kg),
                    ("restraint", restraint),
                )
                if value is None
            )
            stand_ins.append(
                replace(f, restraint=Restraint.BELTED)
                if isinstance(f, ChildRiskInputs) and restraint is None
                else f
            )
            donors = None
            if unknown:
                donors = pick_donors(
                    self.donors,
                    seat_group(f.seat_row, f.seat_side.value, f.driver),
                    age_years=f.age_years,
                    female=None if f.female is None else float(f.female),
                    restraint=None if restraint is None else restraint.value,
                )
            blocks.append((i, donors, unknown))
            if self.measurement is not None and delta_v_source_of(f) is DeltaVSource.MEASURED:
                measured[i] = float(f.delta_v_kmh)
                unknown = (*unknown, "delta_v_kmh")
            integrated.append(unknown)
        assert self.impact_count_imputed is not None
        arrays, imputed = inputs_arrays_3(stand_ins, self.imputation, self.impact_count_imputed)
        expanded, owner = substitute(arrays, blocks, self.donors)
        counts = np.bincount(owner, minlength=len(inputs)).astype(np.float64)
        weight = 1.0 / counts[owner]
        if measured and self.measurement is not None:
            expanded, owner, weight = over_reconstructed_nodes(
                expanded, owner, weight, measured, self.measurement
            )
        # the medians inputs_arrays_3 put in for unknown inputs were replaced by the donors'
        named = tuple(
            tuple(k for k in imp if k not in unknown)
            for imp, unknown in zip(imputed, integrated, strict=True)
        )
        return design_columns_3(expanded), owner, weight, named, tuple(integrated)

    @cached_property
    def used_inputs(self) -> frozenset[str]:
        """The imputable inputs some outcome model uses (others are not named when unknown)."""
        cand = self.candidate_columns
        cols = {cand[i] for m in (self.decision, *self.regions.values()) for i in m.columns}
        return frozenset(k for k, names in _INPUT_COLUMNS.items() if cols & set(names))

    def predict_many(self, inputs: Sequence[RiskInputs]) -> list[RiskPrediction]:
        """Every occupant's answer (vectorised over occupants).

        An occupant with unknown inputs (feature set 3) gets the mean
        probability over its donors (:mod:`models.field.unknowns`): each
        bootstrap refit's mean likewise, so ``ci95`` is the confidence interval
        of the integrated probability (the spread of its refits' logits), and
        the donors' own spread is ``unknown_inputs_range95``.

        Raises
        ------
        ValueError
            Delta-V or age out of range (naming the field).
        """
        if not inputs:
            return []
        x, owner, weight, imputed, integrated = self.expanded_design(inputs)
        used = self.used_inputs
        names = ("iss15", *self.regions)
        models = (self.decision, *self.regions.values())
        logits = self._logits(models, x)
        n = len(inputs)
        if x.shape[0] == n:  # every input known: the rows are the occupants
            eta = np.stack([e for e, _ in logits])  # (1 + regions, n)
            sd = np.stack([np.std(b, axis=1, ddof=1) for _, b in logits])
            boot_p = _expit(logits[0][1])
            spread: list[tuple[float, float] | None] = [None] * n
        else:
            eta, sd, boot_p, spread = _integrated(logits, owner, weight, n)
        if self.recalibration is not None:  # the decision's local recalibration
            a, b = self.recalibration
            eta[0], sd[0] = a + b * eta[0], b * sd[0]
            boot_p = _expit(a + b * _logit(boot_p))
            spread = [
                None if s is None else (_recal(s[0], a, b), _recal(s[1], a, b)) for s in spread
            ]
        p = _expit(eta)
        lo = np.minimum(_expit(eta - Z_95 * sd), p).tolist()
        hi = np.maximum(_expit(eta + Z_95 * sd), p).tolist()
        pl, etal, sdl = p.tolist(), eta.tolist(), sd.tolist()
        levels = [3 if m.ais_level is None else m.ais_level for m in models]
        first = np.searchsorted(owner, np.arange(n))
        modes = _modes(x[first], inputs)
        out = []
        for i, f in enumerate(inputs):
            regions = {
                names[k]: RegionRisk(pl[k][i], (lo[k][i], hi[k][i]), levels[k])
                for k in range(1, len(names))
            }
            out.append(
                RiskPrediction(
                    probability=pl[0][i],
                    ci95=(lo[0][i], hi[0][i]),
                    logit=etal[0][i],
                    logit_sd=sdl[0][i],
                    mode=modes[i],
                    imputed=tuple(k for k in imputed[i] if k in used),
                    extrapolated=f.delta_v_kmh > self.delta_v_max_kmh,
                    regions=regions,
                    bootstrap_probability=boot_p[i],
                    integrated=integrated[i],
                    unknown_inputs_range95=spread[i],
                    knowledge=knowledge_of(f, "delta_v_kmh" in integrated[i]),
                )
            )
        return out

    @cached_property
    def _forest(self) -> Forest | None:
        """Every boosted outcome's trees in one forest (None when none is boosted)."""
        bags = tuple(m.bag for m in self._boosted)
        return Forest.of(bags) if bags else None

    @cached_property
    def _boosted(self) -> tuple[BoostedOutcomeModel | BlendOutcomeModel, ...]:
        """The outcome models with trees (boosted and blends)."""
        models = (self.decision, *self.regions.values())
        return tuple(m for m in models if isinstance(m, BoostedOutcomeModel | BlendOutcomeModel))

    def _logits(
        self, models: Sequence[AnyOutcomeModel], x: FloatArray
    ) -> list[tuple[FloatArray, FloatArray]]:
        """Each model's calibrated logit and bootstrap logits; the trees walked once."""
        scores: dict[str, FloatArray] = {}
        if self._forest is not None:
            parts = self._forest.split(self._forest.member_scores(x))
            scores = {m.name: p for m, p in zip(self._boosted, parts, strict=True)}
        out = []
        for m in models:
            if isinstance(m, BoostedOutcomeModel):
                logits = m.logits_of_scores(scores[m.name])
            elif isinstance(m, BlendOutcomeModel):
                logits = m.logits_of_scores(x, scores[m.name])
            else:
                logits = m.logits(x)
            if m is self.decision and self.children is not None:
                logits = self.children.apply(*logits, x)
            out.append(logits)
        return out

    def decision_probability(self, x_all: FloatArray) -> FloatArray:
        """P(ISS 15+) (n,) of full design rows (n, K) with every input known (recalibrated
        when the artifact is): the decision of :meth:`predict_many` for rows that need
        no integration (e.g. the data's own rows, reconstructed delta-V)."""
        eta, _ = self._logits([self.decision], x_all)[0]
        if self.recalibration is not None:
            eta = self.recalibration[0] + self.recalibration[1] * eta
        return _expit(eta)

    def predict(self, inputs: RiskInputs) -> RiskPrediction:
        """One occupant's answer (:meth:`predict_many` of one)."""
        return self.predict_many([inputs])[0]

    def vehicle(self, predictions: Sequence[RiskPrediction]) -> VehicleRisk:
        """P(anyone in the vehicle ISS 15+) from its occupants' answers.

        Raises
        ------
        ValueError
            No occupant.
        """
        if not predictions:
            raise ValueError("the vehicle answer needs at least one occupant")

        def z(ps: Sequence[FloatArray]) -> FloatArray:
            none = np.sum([np.log1p(-np.clip(p, 0.0, 1.0 - 1e-12)) for p in ps], axis=0)
            q = np.clip(-np.expm1(none), 1e-9, 1.0 - 1e-9)
            out: FloatArray = np.log(q / (1.0 - q))
            return out

        z0 = float(z([np.array(p.probability) for p in predictions]))
        zb = z([p.bootstrap_probability for p in predictions])
        eta = float(self.vehicle_calibration[0] + self.vehicle_calibration[1] * z0)
        boot = (
            self.vehicle_bootstrap_calibration[:, 0] + self.vehicle_bootstrap_calibration[:, 1] * zb
        )
        p, lo, hi, _ = _interval(eta, boot)
        # never below its riskiest occupant's: anyone is at least as likely as any one
        floor = max(q.probability for q in predictions)
        if p < floor:
            p, lo, hi = floor, min(lo, floor), max(hi, floor)
        return VehicleRisk(p, (lo, hi))

    @property
    def vehicle_heldout_auc(self) -> float:
        """AUC of P(anyone ISS 15+) on vehicles held out by crash (the artifact's figure)."""
        return float(self.document["vehicle"]["heldout"]["auc"])

    @property
    def operating_points(self) -> Mapping[str, float]:
        """Operating point name -> threshold (the names the service may configure)."""
        return self.thresholds

    def threshold(self, operating_point: str | None = None, knowledge: str | None = None) -> float:
        """Decision threshold on P(ISS 15+) (default: the artifact's operating point).

        Parameters
        ----------
        operating_point : str, optional
        knowledge : str, optional
            What was known of the occupant (:data:`KNOWLEDGE`): feature set 3
            artifacts set each operating point's threshold for each, so that
            its promise holds for the information at hand; None, or an older
            artifact: the operating point's one threshold.

        Raises
        ------
        KeyError
            An operating point the artifact does not define.
        """
        name = operating_point or self.default_operating_point
        if name in self.knowledge_thresholds:
            # a measured delta-V is read as the reconstruction it stands for: the same
            # threshold; without a knowledge, an adult's with the age sent (the vehicle's)
            return self.knowledge_thresholds[name][(knowledge or "adult").removesuffix("_measured")]
        return self.thresholds[name]


def default_artifact_path() -> Path:
    """The shipped artifact, ``models/field/artifacts/field_iss15.json``."""
    return Path(__file__).resolve().parent / "artifacts" / _ARTIFACT_FILE


def load_default() -> RiskModel:
    """Load and verify the shipped artifact."""
    return RiskModel.from_artifact(default_artifact_path())
