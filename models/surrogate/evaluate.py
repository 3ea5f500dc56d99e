"""Request-path evaluation of the PCE surrogates (numpy only, no chaospy).

:meth:`SurrogateLibrary.load` reads and verifies the artifacts once;
:meth:`SurrogateFamily.propagate` turns the occupant sensor uncertainty into
95% intervals in a few milliseconds, with all bootstrap replicates.

Propagation (reference paper section 2.5; issue 5)
----------------------------------------------------
* Sensor errors: posture and seat track readings are Gaussian with the given
  standard deviations (service default: 5 deg and 50 mm at 95%, i.e.
  ``5 / 1.96``), clipped to the model domain. A FIXED sample set of
  :data:`N_SENSOR_SAMPLES` standard-normal pairs (a Fibonacci lattice through
  the Box-Muller map: deterministic, low discrepancy) is used, so the same
  call always gives bit-identical output.
* A delta-V piece in which the head strikes the rigid interior in part of
  the design holds two sets of PCEs, one per side of the strike onset, and a
  gate PCE of the head's least clearance (mm) that picks the side at every
  point, blended over a few millimetres (:class:`_SplitPiece`).
* Each piece carries the Kriging of its point-PCE residuals on its design
  runs (PC-Kriging, :mod:`models.surrogate.kriging`): one kernel matrix of the
  sensor samples against the design and one matrix product, added on the
  fitted scale to the point PCE and every replicate (:class:`_KrigedPiece`).
* Delta-V, |angle from the mode axis| and pulse duration are taken as given
  (clamped to the design ranges; :attr:`UncertaintyResult.clamped_inputs`).
* P(ISS >= 15) is not read from its own PCE: at every sensor sample of every
  replicate it is computed from the surrogate measures by the assessment's
  risk curves and the exact ISS sum (:func:`models.injury.batch.p_iss15_batch`,
  with the occupant's age when known), so it is the same function of the
  measures as in a direct LPM case. [R] The P(ISS >= 15) PCE of the artifacts
  smooths the thresholds of a composite function: with it the held-out ISS15+
  agreement was 94.7-97.3 % in six families; from the measures it is 96.7 % in
  two and 98-100 % in the others, and the median |P error| is lower in 13
  families and equal (below 1e-4) in the rest (2026-12-01, same artifacts,
  REPORT.md Table B). The point value is the mean over
  the sensor distribution with the point PCEs; its 95% interval the 2.5 and
  97.5 percentiles of the same mean over the bootstrap replicates
  (model-adequacy uncertainty of the surrogate; each replicate's mean taken
  on a 24-sample subset as its deviation from the point PCEs there,
  :data:`_P_SUBSET`), widened by a held-out factor.
* Measures and ISS: the point value is the point PCE at the (clamped) readings;
  the 95% interval the 2.5 and 97.5 percentiles (order statistics, "inverted
  CDF") over all sensor samples and all bootstrap replicates (sensor and
  surrogate uncertainty together), widened on the fitted scale by the
  polynomial's own error, which the replicates do not see: a bound calibrated
  on the family's held-out LPM runs, added in quadrature on each side of the
  point value (:meth:`SurrogateFamily._interval_factors`).
* The evaluation is versioned (:data:`EVALUATION_VERSION`, with this module's
  checksum) and recorded with every case beside the artifacts' checksum.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from types import MappingProxyType
from typing import Any, Final

import numpy as np
import numpy.typing as npt
from scipy.sparse import csr_array

import models.injury.batch as _batch_module
from models.codehash import source_tree_sha256
from models.impact_mode import ImpactMode
from models.injury.batch import p_iss15_batch
from models.notification import Body
from models.surrogate.basis import design_matrix, evaluate_univariate
from models.surrogate.kriging import ResidualKriging
from models.surrogate.spec import (
    AIRBAG_MODES,
    FAMILIES,
    HEAD_CLEARANCE,
    INPUT_NAMES,
    family_name,
    from_output_scale,
    to_output_scale,
    to_unit,
)
from models.surrogate.store import MANIFEST_NAME, read_artifact, sha256_file

__all__ = [
    "EVALUATION_NAME",
    "EVALUATION_VERSION",
    "DEFAULT_POSTURE_SD_DEG",
    "DEFAULT_SEAT_TRACK_SD_MM",
    "N_SENSOR_SAMPLES",
    "SurrogateFamily",
    "SurrogateLibrary",
    "UncertaintyResult",
    "default_artifact_dir",
    "evaluation_sha256",
]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: What turns the shipped artifacts into an answer (recorded with every case
#: beside the artifacts' manifest checksum, so that a change of the
#: propagation or of the interval calibration shows in the audit record).
EVALUATION_NAME: Final[str] = "PCE sensor-uncertainty propagation and interval calibration"
#: 1: bootstrap percentiles, P(ISS >= 15) interval widened by the held-out factor;
#: 2: the measure and ISS intervals extended by their held-out calibrated margins;
#: 3: P(ISS >= 15) from the surrogate measures through the risk curves (age-aware);
#: 4: delta-V pieces split at the head-strike onset, chosen by a gate PCE (format 4);
#: 5: the sensor-sample sums by a sparse product and one sensor basis per split
#: piece (summation order only: served values within 4e-12 relative of version
#: 4 at 480 random readings over the 24 families);
#: 6: the Kriging of each piece's residuals added to its PCEs (format 5,
#: models.surrogate.kriging);
#: 7: the gate of a split piece is a point PCE, evaluated alone (format 6).
EVALUATION_VERSION: Final[str] = "7"


#: Sources of the evaluation (this module and the batch risk it calls).
_EVALUATION_SOURCES: Final[tuple[Path, ...]] = (
    Path(__file__),
    Path(_batch_module.__file__),
    Path(__file__).with_name("kriging.py"),
)


@lru_cache(maxsize=1)
def evaluation_sha256() -> str:
    """SHA-256 over the evaluation's sources (its checksum in a case record).

    Of the normalised syntax trees (:mod:`models.codehash`): docstrings and layout aside.
    """
    return source_tree_sha256(_EVALUATION_SOURCES)


#: z of a two-sided 95% Gaussian interval.
_Z95: Final[float] = 1.959963984540054
#: Default posture sensor standard deviation, deg: error within 5 deg 95% of the
#: time, Gaussian (reference paper section 2.5; issue 5).
DEFAULT_POSTURE_SD_DEG: Final[float] = 5.0 / _Z95
#: Default seat track sensor standard deviation, mm: within 5 cm 95% of the time.
DEFAULT_SEAT_TRACK_SD_MM: Final[float] = 50.0 / _Z95
#: Size of the fixed sensor sample set (a 2-D Fibonacci lattice). [R] Chosen
#: for the 5 ms budget per occupant (benchmarks/bench_surrogate.py); the
#: coverage checks compare with LPM runs at the same points.
N_SENSOR_SAMPLES: Final[int] = 96
#: Percentiles of a 95% interval.
_PCT: Final[tuple[float, float]] = (2.5, 97.5)
#: Floor of the bootstrap standard deviation of logit P(ISS >= 15) in the held-out
#: calibration (logit units): where every replicate agrees (saturated P, the
#: smallest delta-V) a residual is measured against this instead of zero. [R]
_P_SD_FLOOR: Final[float] = 0.01
#: Fewest held-out points for the calibration (a 95 % quantile of fewer is the
#: sample maximum or worse); fewer: no widening. [R]
_MIN_CALIBRATION_POINTS: Final[int] = 20
_POSTURE, _SEAT = 2, 3  # columns of the sensor inputs in INPUT_NAMES
#: Floor of the bootstrap standard deviation of a measure (fitted scale log(x +
#: floor): 0.01 is 1 % of the value) and of ISS (points) in the interval
#: calibration: where every replicate agrees a residual is measured against
#: this instead of zero. [R] as :data:`_P_SD_FLOOR`.
_FITTED_SD_FLOOR: Final[Mapping[str, float]] = MappingProxyType({"iss": 0.1})
_FITTED_SD_FLOOR_MEASURE: Final[float] = 0.01


def _bootstrap_sd(replicates: FloatArray, name: str) -> FloatArray:
    """Standard deviation over the last axis (the replicates), floored for `name`."""
    floor = _FITTED_SD_FLOOR.get(name, _FITTED_SD_FLOOR_MEASURE)
    return np.maximum(np.std(replicates, axis=-1, ddof=1), floor)


def default_artifact_dir() -> Path:
    """``models/surrogate/artifacts`` of this package."""
    return Path(__file__).resolve().parent / "artifacts"


def _sensor_normals(n: int) -> FloatArray:
    """Deterministic standard-normal pairs: Fibonacci lattice + Box-Muller, shape (n, 2)."""
    i = np.arange(n, dtype=np.float64)
    u1 = (i + 0.5) / n
    u2 = np.mod(i * (math.sqrt(5.0) - 1.0) / 2.0 + 0.5 / n, 1.0)
    r = np.sqrt(-2.0 * np.log(u1))
    return np.stack([r * np.cos(2.0 * np.pi * u2), r * np.sin(2.0 * np.pi * u2)], axis=1)


_NORMALS: Final[FloatArray] = _sensor_normals(N_SENSOR_SAMPLES)
_NORMALS.flags.writeable = False
#: Sensor samples at which the bootstrap replicates' P(ISS >= 15) is computed:
#: every 4th point of the lattice (24; still a lattice over both inputs). [R]
#: P comes from the measures through the risk curves, about 0.35 us per sample
#: and replicate on the benchmark machine; all 96 x 150 cost 5 ms, past the
#: 5 ms budget of the whole evaluation. The replicate spread is measured as the
#: deviation of each replicate from the point PCEs on the same subset, so the
#: subset's quadrature error, common to both, cancels; the point value uses
#: every sample.
_P_SUBSET: Final[npt.NDArray[np.intp]] = np.arange(0, N_SENSOR_SAMPLES, 4)
_P_SUBSET.flags.writeable = False


@dataclass(frozen=True)
class UncertaintyResult:
    """Surrogate answer for one occupant with 95% intervals.

    Attributes
    ----------
    p_iss15 : float
        P(ISS >= 15) averaged over the sensor errors.
    p_iss15_ci95 : (float, float)
        95% interval of that probability: the bootstrap interval widened by the
        family's held-out calibration factor (:attr:`p_interval_inflation`).
    iss : float
        ISS of the point PCE at the readings (continuous surrogate of an integer score).
    iss_ci95 : (float, float)
    measures : Mapping[str, float]
        Each measure the mode computes at the readings (units in the names;
        HIC15 and Nij dimensionless).
    measures_ci95 : Mapping[str, (float, float)]
        95% interval of each measure: sensor and bootstrap percentiles extended
        by the held-out calibrated margin (:attr:`SurrogateFamily.interval_factors`).
    n_samples : int
        Sensor samples per replicate.
    n_bootstrap : int
        Bootstrap replicates used.
    clamped_inputs : tuple of str
        Inputs that were outside the design range and clamped to it
        (delta-V above 120 km/h: the result is a lower bound).
    """

    p_iss15: float
    p_iss15_ci95: tuple[float, float]
    iss: float
    iss_ci95: tuple[float, float]
    measures: Mapping[str, float]
    measures_ci95: Mapping[str, tuple[float, float]]
    n_samples: int
    n_bootstrap: int
    clamped_inputs: tuple[str, ...] = field(default=())
    #: factor (>= 1) by which the bootstrap interval of P(ISS >= 15) was widened on
    #: the logit scale for the surrogate's own error (:attr:`SurrogateFamily.p_interval_inflation`)
    p_interval_inflation: float = 1.0


#: Inputs fixed over the sensor samples (delta-V, angle, duration), columns of INPUT_NAMES.
_FIXED_INPUTS: Final[tuple[int, int, int]] = (0, 1, 4)

#: :meth:`_Piece.sensor_basis`: univariate polynomials of the fixed inputs, each
#: shape (max degree + 1,), then of the posture and seat track samples, each
#: shape (n, max degree + 1).
_SensorBasis = tuple[tuple[FloatArray, ...], FloatArray, FloatArray]


def _smoothstep(u: FloatArray) -> FloatArray:
    """``3 u^2 - 2 u^3`` on u in [0, 1]: the blend weight of pieces and of split sides."""
    return np.asarray(u * u * (3.0 - 2.0 * u), dtype=np.float64)


class _Piece:
    """Point and bootstrap PCEs of every output on one delta-V piece (immutable)."""

    __slots__ = (
        "_coef_t",
        "_group_ptr",
        "_group_shape",
        "_hi",
        "_lo",
        "_maxdeg",
        "_nb1",
        "_pairs",
        "_ranges",
        "_recs",
        "_term_index",
        "_terms",
        "outputs",
    )

    outputs: tuple[str, ...]
    _coef_t: FloatArray
    #: CSR row pointers of the (posture, seat track) groups over the sorted terms
    _group_ptr: IntArray
    _group_shape: tuple[int, int]
    _term_index: IntArray
    _nb1: int
    _hi: FloatArray
    _lo: FloatArray
    _maxdeg: int
    _pairs: IntArray
    _ranges: tuple[tuple[float, float], ...]
    _recs: tuple[tuple[FloatArray, FloatArray], ...]
    _terms: IntArray

    def __setattr__(self, key: str, value: object) -> None:
        raise AttributeError(f"surrogate pieces are immutable ({key})")

    def __init__(
        self, arrays: Mapping[str, npt.NDArray[Any]], outputs: tuple[str, ...], prefix: str
    ) -> None:
        cand = np.asarray(arrays[prefix + "candidates"], dtype=np.int64)
        alpha = np.asarray(arrays[prefix + "recurrence_alpha"], dtype=np.float64)
        beta = np.asarray(arrays[prefix + "recurrence_beta"], dtype=np.float64)
        rr = np.asarray(arrays[prefix + "ranges"], dtype=np.float64)
        point = [
            (
                np.asarray(arrays[f"{prefix}{o}/point_terms"], dtype=np.int64),
                np.asarray(arrays[f"{prefix}{o}/point_coef"], dtype=np.float64),
            )
            for o in outputs
        ]
        boots = [
            (
                np.asarray(arrays[f"{prefix}{o}/boot_offsets"], dtype=np.int64),
                np.asarray(arrays[f"{prefix}{o}/boot_terms"], dtype=np.int64),
                np.asarray(arrays[f"{prefix}{o}/boot_coef"], dtype=np.float64),
            )
            for o in outputs
        ]
        if rr.shape != (len(INPUT_NAMES), 2) or cand.shape[1] != len(INPUT_NAMES):
            raise ValueError(f"{prefix}: unexpected input dimensions")
        n_boot = {b[0].size - 1 for b in boots}
        if len(n_boot) != 1:
            raise ValueError(f"{prefix}: outputs differ in bootstrap size")
        nb = n_boot.pop()
        used = np.unique(np.concatenate([p[0] for p in point] + [b[1] for b in boots]))
        col = np.full(cand.shape[0], -1, dtype=np.int64)
        col[used] = np.arange(used.size)
        coef = np.zeros((len(outputs), nb + 1, used.size))
        for k, ((pt, pc), (off, bt, bc)) in enumerate(zip(point, boots, strict=True)):
            coef[k, 0, col[pt]] = pc
            rows = np.repeat(np.arange(1, nb + 1), np.diff(off))
            coef[k, rows, col[bt]] = bc
        terms = cand[used]
        # group the terms by their (posture, seat track) degrees: the sensor
        # samples only vary those two inputs; terms sorted by group, and the
        # coefficients stored as (terms, outputs x replicates) for contiguous sums
        key = terms[:, _POSTURE] * (int(terms.max()) + 1) + terms[:, _SEAT]
        order = np.argsort(key, kind="stable")
        terms = np.ascontiguousarray(terms[order])
        sk = key[order]
        starts = np.flatnonzero(np.concatenate([[True], sk[1:] != sk[:-1]]))
        pairs = np.ascontiguousarray(terms[starts][:, [_POSTURE, _SEAT]])
        coef_t = np.ascontiguousarray(coef[:, :, order].reshape(-1, used.size).T)
        for arr in (coef_t, terms, starts, pairs, alpha, beta, rr):
            arr.flags.writeable = False
        sa = object.__setattr__
        sa(self, "outputs", outputs)
        sa(self, "_nb1", nb + 1)
        sa(self, "_lo", rr[:, 0])
        sa(self, "_hi", rr[:, 1])
        sa(self, "_ranges", tuple((float(a), float(b)) for a, b in rr))
        sa(self, "_recs", tuple((alpha[j], beta[j]) for j in range(alpha.shape[0])))
        sa(self, "_maxdeg", int(cand.max()))
        sa(self, "_terms", terms)
        sa(self, "_coef_t", coef_t)
        sa(self, "_pairs", pairs)
        n_terms = int(terms.shape[0])
        term_index = np.arange(n_terms, dtype=np.int64)
        group_ptr = np.append(starts, n_terms).astype(np.int64)
        for arr in (term_index, group_ptr):
            arr.flags.writeable = False
        sa(self, "_term_index", term_index)
        sa(self, "_group_ptr", group_ptr)
        sa(self, "_group_shape", (int(starts.size), n_terms))

    @property
    def n_bootstrap(self) -> int:
        return int(self._nb1 - 1)

    def predict_raw(self, x: FloatArray, replicate: int) -> FloatArray:
        """Fitted-scale outputs at raw inputs, shape (n, n_out)."""
        psi = design_matrix(to_unit(x, self._ranges), self._recs, self._terms)
        cols = replicate + self._nb1 * np.arange(len(self.outputs))
        return np.asarray(psi @ self._coef_t[:, cols], dtype=np.float64)

    def predict_raw_all(self, x: FloatArray) -> FloatArray:
        """Fitted-scale values of every output, point PCE and replicates.

        Returns an array of shape (n, n_out, B + 1).
        """
        psi = design_matrix(to_unit(x, self._ranges), self._recs, self._terms)
        out = np.asarray(psi @ self._coef_t, dtype=np.float64)
        return out.reshape(x.shape[0], len(self.outputs), self._nb1)

    @property
    def delta_v_design(self) -> tuple[float, float]:
        """Delta-V design range of the piece, km/h."""
        return self._ranges[0]

    def sensor_basis(self, xc: FloatArray, post: FloatArray, seat: FloatArray) -> _SensorBasis:
        """Univariate polynomials of :meth:`samples`: the fixed inputs and the sensor samples.

        Parameters
        ----------
        xc : ndarray, shape (1, 5)
            Raw inputs (clamped to the domain).
        post, seat : ndarray, shape (n,)
            Posture (deg) and seat track (mm) samples.
        """
        z = to_unit(xc, self._ranges)[0]
        md = self._maxdeg
        fixed = tuple(
            evaluate_univariate(z[j : j + 1], self._recs[j], md)[0] for j in _FIXED_INPUTS
        )
        zp = 2.0 * (post - self._lo[_POSTURE]) / (self._hi[_POSTURE] - self._lo[_POSTURE]) - 1.0
        zs = 2.0 * (seat - self._lo[_SEAT]) / (self._hi[_SEAT] - self._lo[_SEAT]) - 1.0
        up = evaluate_univariate(zp, self._recs[_POSTURE], md)
        us = evaluate_univariate(zs, self._recs[_SEAT], md)
        return fixed, up, us

    def same_basis(self, other: _Piece) -> bool:
        """Whether `other` has the same input ranges and recurrences (sensor bases shareable)."""
        return (
            self._ranges == other._ranges
            and self._maxdeg == other._maxdeg
            and all(
                np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
                for a, b in zip(self._recs, other._recs, strict=True)
            )
        )

    def samples(
        self,
        xc: FloatArray,
        post: FloatArray,
        seat: FloatArray,
        basis: _SensorBasis | None = None,
    ) -> FloatArray:
        """Fitted-scale outputs, shape (n_out, B + 1, n) at fixed inputs and sensor samples.

        `basis`, when given, is :meth:`sensor_basis` at the same points (of this
        piece or of one with the :meth:`same_basis`).
        """
        fixed, up, us = self.sensor_basis(xc, post, seat) if basis is None else basis
        s = np.ones(self._terms.shape[0])
        for j, uni in zip(_FIXED_INPUTS, fixed, strict=True):  # one scalar factor per term
            s *= uni[self._terms[:, j]]
        psi2 = np.take(up, self._pairs[:, 0], axis=1) * np.take(us, self._pairs[:, 1], axis=1)
        # per (posture, seat track) group the coefficients weighted by the term's
        # other factor: a sparse (M, terms) matrix with one entry per term, times
        # the coefficients, (M, O(B+1)). [R] scipy's CSR product: 0.13 ms against
        # 0.95 ms for a multiply and np.add.reduceat on a 446 x 1208 block (one
        # pass, no temporary), measured 2026-12-02
        grouped = csr_array((s, self._term_index, self._group_ptr), shape=self._group_shape)
        c2 = np.asarray(grouped @ self._coef_t)
        return (psi2 @ c2).T.reshape(len(self.outputs), self._nb1, -1)


class _SplitPiece:
    """A delta-V piece fitted on each side of the head-strike onset (immutable).

    A gate PCE of the head's least clearance to the rigid interior
    (:data:`models.surrogate.spec.HEAD_CLEARANCE`, mm) decides, at each input
    point, which side's PCEs apply: the struck side's below ``-band``, the
    free side's above ``+band``, a smoothstep blend in between (so the
    surrogate is continuous across the onset). The point gate PCE decides for
    the replicates too: the bootstrap measures each side's fit, not the gate's.
    Same interface as :class:`_Piece`.
    """

    __slots__ = ("_band", "_contact", "_free", "_gate", "outputs")

    outputs: tuple[str, ...]
    _band: float
    _contact: _Piece
    _free: _Piece
    _gate: _Piece

    def __setattr__(self, key: str, value: object) -> None:
        raise AttributeError(f"surrogate pieces are immutable ({key})")

    def __init__(
        self,
        arrays: Mapping[str, npt.NDArray[Any]],
        outputs: tuple[str, ...],
        prefix: str,
        band_mm: float,
    ) -> None:
        if not band_mm > 0.0:
            raise ValueError(f"{prefix}: split band must be > 0 mm")
        gate = _Piece(arrays, (HEAD_CLEARANCE,), prefix + "gate/")
        contact = _Piece(arrays, outputs, prefix + "contact/")
        free = _Piece(arrays, outputs, prefix + "free/")
        if contact.n_bootstrap != free.n_bootstrap:
            raise ValueError(f"{prefix}: sides differ in bootstrap size")
        if gate.n_bootstrap != 0:
            raise ValueError(f"{prefix}: the gate is a point PCE (no bootstrap replicates)")
        if not (gate.same_basis(contact) and gate.same_basis(free)):
            raise ValueError(f"{prefix}: the gate and the sides differ in their basis")
        sa = object.__setattr__
        sa(self, "outputs", outputs)
        sa(self, "_band", float(band_mm))
        sa(self, "_gate", gate)
        sa(self, "_contact", contact)
        sa(self, "_free", free)

    @property
    def n_bootstrap(self) -> int:
        return self._contact.n_bootstrap

    @property
    def delta_v_design(self) -> tuple[float, float]:
        """Delta-V design range of the piece, km/h."""
        return self._contact.delta_v_design

    def struck_weight(self, clearance_mm: FloatArray) -> FloatArray:
        """Weight of the struck side at gate clearances (mm): 1 below -band, 0 above +band."""
        return _smoothstep(np.clip((self._band - clearance_mm) / (2.0 * self._band), 0.0, 1.0))

    def clearance(self, x: FloatArray) -> FloatArray:
        """Point gate PCE at raw inputs: predicted head clearance, mm, shape (n,)."""
        return np.asarray(self._gate.predict_raw(x, 0)[:, 0], dtype=np.float64)

    def _blend_rows(
        self,
        x: FloatArray,
        shape: tuple[int, ...],
        side_values: Callable[[_Piece, FloatArray], FloatArray],
    ) -> FloatArray:
        """``w * struck + (1 - w) * free`` per input row, each side evaluated on its rows only.

        `shape` is the per-row shape of ``side_values(side, rows)``.
        """
        wc = self.struck_weight(self.clearance(x))
        out = np.zeros((x.shape[0], *shape))
        expand = (slice(None),) + (None,) * len(shape)
        for side, w in ((self._contact, wc), (self._free, 1.0 - wc)):
            rows = w > 0.0
            if np.any(rows):
                out[rows] += w[rows][expand] * side_values(side, x[rows])
        return out

    def predict_raw(self, x: FloatArray, replicate: int) -> FloatArray:
        """Fitted-scale outputs at raw inputs, shape (n, n_out)."""
        return self._blend_rows(
            x, (len(self.outputs),), lambda side, xr: side.predict_raw(xr, replicate)
        )

    def predict_raw_all(self, x: FloatArray) -> FloatArray:
        """Fitted-scale outputs, point PCE and replicates, shape (n, n_out, B + 1)."""
        shape = (len(self.outputs), self.n_bootstrap + 1)
        return self._blend_rows(x, shape, lambda side, xr: side.predict_raw_all(xr))

    def samples(self, xc: FloatArray, post: FloatArray, seat: FloatArray) -> FloatArray:
        """Fitted-scale outputs, shape (n_out, B + 1, n) at fixed inputs and sensor samples."""
        basis = self._gate.sensor_basis(xc, post, seat)  # shared: the sides' basis is the gate's
        gate = self._gate.samples(xc, post, seat, basis)[0, 0]  # point gate PCE, (n,)
        wc = self.struck_weight(gate)
        out = np.zeros((len(self.outputs), self.n_bootstrap + 1, post.size))
        fixed, up, us = basis
        for side, w in ((self._contact, wc), (self._free, 1.0 - wc)):
            cols = np.flatnonzero(w > 0.0)
            if cols.size == post.size:
                out += w * side.samples(xc, post, seat, basis)
            elif cols.size:
                sub = (fixed, up[cols], us[cols])
                out[:, :, cols] += w[cols] * side.samples(xc, post[cols], seat[cols], sub)
        return out


class _KrigedPiece:
    """A piece (plain or split) plus the Kriging of its residuals (immutable).

    :mod:`models.surrogate.kriging`: the correction, a function of the inputs
    only, is added on the fitted scale to the point PCE and to every bootstrap
    replicate alike. Same interface as :class:`_Piece`.
    """

    __slots__ = ("_kriging", "_ranges", "base", "outputs")

    outputs: tuple[str, ...]
    #: the PCE piece the correction applies to
    base: _Piece | _SplitPiece
    _kriging: ResidualKriging
    _ranges: tuple[tuple[float, float], ...]

    def __setattr__(self, key: str, value: object) -> None:
        raise AttributeError(f"surrogate pieces are immutable ({key})")

    def __init__(
        self,
        base: _Piece | _SplitPiece,
        kriging: ResidualKriging,
        ranges: tuple[tuple[float, float], ...],
        prefix: str,
    ) -> None:
        if kriging.n_outputs != len(base.outputs):
            raise ValueError(
                f"{prefix}: kriging has {kriging.n_outputs} outputs, the piece {len(base.outputs)}"
            )
        sa = object.__setattr__
        sa(self, "outputs", base.outputs)
        sa(self, "base", base)
        sa(self, "_kriging", kriging)
        sa(self, "_ranges", ranges)

    @property
    def n_bootstrap(self) -> int:
        return self.base.n_bootstrap

    @property
    def delta_v_design(self) -> tuple[float, float]:
        """Delta-V design range of the piece, km/h."""
        return self.base.delta_v_design

    def correction(self, x: FloatArray) -> FloatArray:
        """Kriging correction at raw inputs, fitted scale, shape (n, n_out)."""
        return self._kriging.correction(to_unit(x, self._ranges))

    def predict_raw(self, x: FloatArray, replicate: int) -> FloatArray:
        """Fitted-scale outputs at raw inputs, shape (n, n_out)."""
        return self.base.predict_raw(x, replicate) + self.correction(x)

    def predict_raw_all(self, x: FloatArray) -> FloatArray:
        """Fitted-scale outputs, point PCE and replicates, shape (n, n_out, B + 1)."""
        return self.base.predict_raw_all(x) + self.correction(x)[:, :, None]

    def samples(self, xc: FloatArray, post: FloatArray, seat: FloatArray) -> FloatArray:
        """Fitted-scale outputs, shape (n_out, B + 1, n) at fixed inputs and sensor samples."""
        pts = np.repeat(xc, post.size, axis=0)
        pts[:, _POSTURE] = post
        pts[:, _SEAT] = seat
        return self.base.samples(xc, post, seat) + self.correction(pts).T[:, None, :]


def _piece(
    arrays: Mapping[str, npt.NDArray[Any]],
    outputs: tuple[str, ...],
    prefix: str,
    piece_meta: Mapping[str, Any],
) -> _Piece | _SplitPiece | _KrigedPiece:
    """The piece at `prefix`: split at the head-strike onset when its metadata
    says so, with the Kriging of its residuals when its metadata has one."""
    split = piece_meta.get("split")
    base: _Piece | _SplitPiece
    if split is None:
        base = _Piece(arrays, outputs, prefix)
    elif split.get("gate") != HEAD_CLEARANCE:
        raise ValueError(f"{prefix}: unknown split gate {split.get('gate')!r}")
    else:
        base = _SplitPiece(arrays, outputs, prefix, float(split["band_mm"]))
    if piece_meta.get("kriging") is None:
        return base
    ranges = tuple((float(a), float(b)) for a, b in piece_meta["design_ranges"])
    return _KrigedPiece(base, ResidualKriging.from_arrays(arrays, prefix), ranges, prefix)


class SurrogateFamily:
    """PCE surrogates of one mode x body x restraint family (immutable).

    A family is a set of delta-V pieces (:data:`models.surrogate.spec.DELTA_V_PIECES_KMH`),
    each with a point PCE and bootstrap replicates per output.
    Build with :meth:`from_arrays` (or through :class:`SurrogateLibrary`).

    Attributes
    ----------
    name : str
    outputs : tuple of str
        Output names (the mode's measures, ``p_iss15``, ``iss``).
    meta : Mapping
        The artifact's metadata (degrees, LOO, checksums, held-out errors).
    """

    __slots__ = (
        "_body",
        "_edges",
        "_fitted",
        "_hi",
        "_lo",
        "_meas_rows",
        "_measures",
        "_mode",
        "_pieces",
        "meta",
        "name",
        "interval_factors",
        "outputs",
        "p_interval_inflation",
    )

    name: str
    outputs: tuple[str, ...]
    meta: Mapping[str, Any]
    #: factor (>= 1) widening the bootstrap interval of P(ISS >= 15) on the logit
    #: scale, calibrated on the family's held-out LPM runs (:meth:`_p_inflation`)
    p_interval_inflation: float
    #: per output (measures and ISS): the held-out calibration factor of the
    #: 95% interval's margin, in bootstrap standard deviations (:meth:`_interval_factors`)
    interval_factors: Mapping[str, float]
    _body: Body
    _edges: FloatArray
    #: outputs evaluated from their PCEs: every output but ``p_iss15``, which is
    #: computed from the measures (:meth:`_p_from_raw`)
    _fitted: tuple[str, ...]
    _hi: FloatArray
    _lo: FloatArray
    _meas_rows: IntArray
    _measures: tuple[str, ...]
    _mode: ImpactMode
    _pieces: tuple[_Piece | _SplitPiece | _KrigedPiece, ...]

    def __setattr__(self, key: str, value: object) -> None:
        raise AttributeError(f"SurrogateFamily is immutable ({key})")

    @classmethod
    def from_arrays(
        cls, arrays: Mapping[str, npt.NDArray[Any]], meta: Mapping[str, Any]
    ) -> SurrogateFamily:
        """Assemble a family from artifact arrays and metadata.

        Raises
        ------
        ValueError
            When members are missing or inconsistent.
        """
        self = cls.__new__(cls)
        try:
            outputs = tuple(str(o) for o in meta["outputs"])
            inputs = meta["inputs"]
            edges = np.asarray(meta["delta_v_pieces_kmh"], dtype=np.float64)
            body, mode = Body(meta["body"]), ImpactMode(meta["mode"])
            fitted = tuple(o for o in outputs if o != "p_iss15")
            pieces = tuple(
                _piece(arrays, fitted, f"piece{k}/", meta["pieces"][k])
                for k in range(edges.size - 1)
            )
        except KeyError as exc:
            raise ValueError(f"{meta.get('family', '?')}: member {exc} missing") from exc
        if "p_iss15" not in outputs:
            raise ValueError(f"{meta.get('family')}: p_iss15 missing from the outputs")
        measures = tuple(o for o in fitted if o != "iss")
        if [i["name"] for i in inputs] != list(INPUT_NAMES):
            raise ValueError(f"{meta.get('family')}: unexpected inputs")
        if len({p.n_bootstrap for p in pieces}) != 1:
            raise ValueError(f"{meta.get('family')}: pieces differ in bootstrap size")
        edges.flags.writeable = False
        sa = object.__setattr__
        sa(self, "name", str(meta["family"]))
        sa(self, "outputs", outputs)
        sa(self, "meta", MappingProxyType(dict(meta)))
        sa(self, "_lo", np.array([float(i["low"]) for i in inputs]))
        sa(self, "_hi", np.array([float(i["high"]) for i in inputs]))
        sa(self, "_edges", edges)
        sa(self, "_pieces", pieces)
        sa(self, "_body", body)
        sa(self, "_mode", mode)
        sa(self, "_fitted", fitted)
        sa(self, "_measures", measures)
        sa(self, "_meas_rows", np.array([fitted.index(m) for m in measures], dtype=np.int64))
        inflation = 1.0
        factors: dict[str, float] = {}
        if "heldout_x" in arrays and "heldout_y" in arrays:
            hx = np.asarray(arrays["heldout_x"], dtype=np.float64)
            hy = np.asarray(arrays["heldout_y"], dtype=np.float64)
            raw = self._raw_all(hx)  # once for both calibrations
            inflation = self._p_inflation(hx, hy[:, outputs.index("p_iss15")], raw=raw)
            factors = self._interval_factors(hx, hy, raw=raw)
        sa(self, "p_interval_inflation", inflation)
        sa(self, "interval_factors", MappingProxyType(factors))
        return self

    def _p_from_raw(self, raw_measures: FloatArray, age_years: float | None = None) -> FloatArray:
        """P(ISS >= 15) from fitted-scale measures through the risk curves.

        Parameters
        ----------
        raw_measures : ndarray, shape (n_measures, ...)
            Fitted-scale values of :attr:`_measures` (any trailing shape).
        age_years : float, optional
            Occupant age (the age-dependent chest curve), None: NCAP 2008.

        Returns
        -------
        ndarray, shape (...)
        """
        shape = raw_measures.shape[1:]
        values = {
            name: from_output_scale(name, raw_measures[i]).reshape(-1)
            for i, name in enumerate(self._measures)
        }
        p = p_iss15_batch(values, self._body, age_years, self._mode)
        return np.asarray(p.reshape(shape), dtype=np.float64)

    def _raw_all(self, x: FloatArray) -> FloatArray:
        """Fitted-scale outputs, point PCE and replicates, blended over the pieces.

        Parameters
        ----------
        x : ndarray, shape (n, 5)
            Raw inputs (not clamped).

        Returns
        -------
        ndarray, shape (n, n_fitted, B + 1)
            Rows of :attr:`_fitted` (every output but ``p_iss15``).
        """
        w = self._weights(x[:, 0])
        raw = np.zeros((x.shape[0], len(self._fitted), self.n_bootstrap + 1))
        for i, piece in enumerate(self._pieces):
            rows = w[:, i] > 0.0
            if np.any(rows):
                raw[rows] += w[rows, i, None, None] * piece.predict_raw_all(x[rows])
        return raw

    def _interval_factors(
        self, x: FloatArray, y: FloatArray, raw: FloatArray | None = None
    ) -> dict[str, float]:
        """Held-out calibration of the measure and ISS intervals (the surrogate's own error).

        The pooled sensor x bootstrap percentiles see the sensor spread and how
        the fit moves with the design, not the bias of the polynomial: where a
        measure hardly varies over the sensor distribution (most side cases),
        an error of a few per cent put every direct LPM outcome outside the
        bare interval (measured: 83-93 % of the outcomes inside, by measure,
        REPORT.md Table D). Split conformal with normalised residuals (Lei et al.
        2018, J. Am. Stat. Assoc. 113:1094, section 5.2) on the family's
        held-out LPM runs: r = |y_LPM - y_PCE| / s on the fitted scale (log for
        the measures, points for ISS), s the bootstrap standard deviation at the
        point floored at :data:`_FITTED_SD_FLOOR`; the factor is the
        ``ceil((n + 1) 0.95) / n`` empirical quantile of r. At a request the
        bound ``m = factor * s`` (s at the reading) is added in quadrature to
        each side of the percentile interval about the point value ``y0``:
        ``min(q_lo, y0 - hypot(max(y0 - q_lo, 0), m))`` and the mirror image
        above (the interval always holds the bare percentiles and ``y0``).

        Parameters
        ----------
        x : ndarray, shape (n, 5)
            Held-out inputs.
        y : ndarray, shape (n, n_outputs)
            Direct LPM outputs there (NaN where a run failed).
        raw : ndarray, shape (n, n_fitted, B + 1), optional
            :meth:`_raw_all` at `x`, when already computed.

        Returns
        -------
        dict
            Output name (every output but ``p_iss15``) -> factor (>= 0).
        """
        ok = np.all(np.isfinite(y), axis=1) & np.all(np.isfinite(x), axis=1)
        if int(ok.sum()) < _MIN_CALIBRATION_POINTS:
            return {}
        raw = (self._raw_all(x) if raw is None else raw)[ok]
        y = y[ok]
        n = y.shape[0]
        level = min(1.0, math.ceil((n + 1) * 0.95) / n)
        out: dict[str, float] = {}
        for kf, name in enumerate(self._fitted):
            truth = to_output_scale(name, y[:, self.outputs.index(name)])
            sd = _bootstrap_sd(raw[:, kf, 1:], name)
            # the served value is clipped to the physical range (>= 0, ISS <= 75)
            pred = to_output_scale(name, from_output_scale(name, raw[:, kf, 0]))
            r = np.abs(truth - pred) / sd
            out[name] = float(np.quantile(r, level, method="inverted_cdf"))
        return out

    def _p_inflation(
        self, x: FloatArray, p_lpm: FloatArray, raw: FloatArray | None = None
    ) -> float:
        """Held-out calibration factor of the P(ISS >= 15) bootstrap interval.

        The bootstrap replicates measure how much the fit moves with the design;
        they do not see the error of the polynomial itself, which is larger where
        the LPM response has kinks (coverage of the bare bootstrap interval: about
        84 % of non-saturated cases, REPORT.md). Split-conformal scaling with
        normalised residuals on the family's held-out LPM runs (uniform over the
        domain, never used in the fit): r = |logit P_LPM - logit P_s| / s, P_s
        the surrogate's P(ISS >= 15) (from its measures, :meth:`_p_from_raw`),
        s its bootstrap standard deviation at the point (floored at
        :data:`_P_SD_FLOOR`), both logits clipped at the fitted resolution; the
        factor is the 95 % quantile of r over 1.96, at least 1.

        Parameters
        ----------
        x : ndarray, shape (n, 5)
            Held-out inputs.
        p_lpm : ndarray, shape (n,)
            P(ISS >= 15) of the direct LPM runs there (NaN where a run failed).
        raw : ndarray, shape (n, n_fitted, B + 1), optional
            :meth:`_raw_all` at `x`, when already computed.

        Returns
        -------
        float
        """
        ok = np.isfinite(p_lpm) & np.all(np.isfinite(x), axis=1)
        if int(ok.sum()) < _MIN_CALIBRATION_POINTS:
            return 1.0
        raw_m = (self._raw_all(x) if raw is None else raw)[ok][:, self._meas_rows, :]
        p_s = self._p_from_raw(np.moveaxis(raw_m, 1, 0))  # (n, B + 1)
        p_lpm = p_lpm[ok]
        clipped = to_output_scale("p_iss15", p_s)  # logit, clipped at the fitted resolution
        truth = to_output_scale("p_iss15", p_lpm)
        sd = np.maximum(np.std(clipped[:, 1:], axis=1, ddof=1), _P_SD_FLOOR)
        r = np.abs(truth - clipped[:, 0]) / sd
        return max(1.0, float(np.quantile(r, 0.95)) / _Z95)

    @property
    def n_bootstrap(self) -> int:
        """Number of bootstrap replicates."""
        return self._pieces[0].n_bootstrap

    @property
    def ranges(self) -> tuple[tuple[float, float], ...]:
        """Domain of each input of :data:`INPUT_NAMES` (units in the names)."""
        return tuple((float(a), float(b)) for a, b in zip(self._lo, self._hi, strict=True))

    def _weights(self, dv: npt.ArrayLike) -> FloatArray:
        """Blend weights of the pieces at each delta-V, shape (n, n_pieces).

        Inside a piece's own interval its weight is 1; across an edge the two
        neighbours are blended with a smoothstep in log delta-V over the part
        of their design ranges that overlaps (both PCEs are inside their
        designs there), so the surrogate is continuous in delta-V.
        """
        v = np.log(np.atleast_1d(np.asarray(dv, dtype=np.float64)))
        n_p = len(self._pieces)
        k = np.clip(np.searchsorted(self._edges, np.exp(v), side="right") - 1, 0, n_p - 1)
        w = np.zeros((v.size, n_p))
        w[np.arange(v.size), k] = 1.0
        for j in range(1, n_p):
            e = math.log(float(self._edges[j]))
            half = min(
                e - math.log(self._pieces[j].delta_v_design[0]),
                math.log(self._pieces[j - 1].delta_v_design[1]) - e,
            )
            if half <= 0.0:
                continue
            u = np.clip((v - (e - half)) / (2.0 * half), 0.0, 1.0)
            zone = (u > 0.0) & (u < 1.0)
            up = _smoothstep(u)
            w[zone, j - 1] = 1.0 - up[zone]
            w[zone, j] = up[zone]
            others = np.ones(n_p, dtype=bool)
            others[[j - 1, j]] = False
            w[np.ix_(zone, others)] = 0.0
        return w

    def head_clearance(self, x: npt.ArrayLike) -> FloatArray:
        """The gate PCE of a split piece at raw inputs: predicted head clearance, mm.

        Parameters
        ----------
        x : array_like, shape (n, 5)
            Columns of :data:`INPUT_NAMES`; each point is given to the piece whose
            delta-V interval holds it (no blending).

        Returns
        -------
        ndarray, shape (n,)
            mm; NaN where that piece is not split.
        """
        xv = np.array(np.atleast_2d(np.asarray(x, dtype=np.float64)))
        xv[:, 1] = np.abs(xv[:, 1])
        n_p = len(self._pieces)
        k = np.clip(np.searchsorted(self._edges, xv[:, 0], side="right") - 1, 0, n_p - 1)
        out = np.full(xv.shape[0], np.nan)
        for i, piece in enumerate(self._pieces):
            rows = k == i
            base = piece.base if isinstance(piece, _KrigedPiece) else piece
            if isinstance(base, _SplitPiece) and np.any(rows):
                out[rows] = base.clearance(xv[rows])
        return out

    def predict(
        self, x: npt.ArrayLike, replicate: int = 0, age_years: float | None = None
    ) -> FloatArray:
        """Surrogate outputs at raw input points.

        Parameters
        ----------
        x : array_like, shape (n, 5)
            Columns of :data:`INPUT_NAMES` (km/h, deg, deg, mm, ms); the
            angle's magnitude is used; not clamped.
        replicate : int, optional
            0 the point PCE, 1..n_bootstrap a bootstrap replicate.
        age_years : float, optional
            Occupant age for P(ISS >= 15) (computed from the measures; None:
            the NCAP 2008 chest curve, as in the build's LPM runs).

        Returns
        -------
        ndarray, shape (n, n_outputs)
            Physical values of :attr:`outputs`.
        """
        xv = np.array(np.atleast_2d(np.asarray(x, dtype=np.float64)))
        xv[:, 1] = np.abs(xv[:, 1])
        raw = np.zeros((xv.shape[0], len(self._fitted)))
        w = self._weights(xv[:, 0])
        for i, piece in enumerate(self._pieces):
            rows = w[:, i] > 0.0
            if np.any(rows):
                raw[rows] += w[rows, i, None] * piece.predict_raw(xv[rows], replicate)
        cols = []
        for o in self.outputs:
            if o == "p_iss15":
                cols.append(self._p_from_raw(raw[:, self._meas_rows].T, age_years))
            else:
                cols.append(from_output_scale(o, raw[:, self._fitted.index(o)]))
        return np.stack(cols, axis=1)

    def propagate(
        self,
        *,
        delta_v_kmh: float,
        angle_deg: float,
        posture_deg: float,
        seat_track_mm: float,
        duration_ms: float,
        posture_sd_deg: float = DEFAULT_POSTURE_SD_DEG,
        seat_track_sd_mm: float = DEFAULT_SEAT_TRACK_SD_MM,
        age_years: float | None = None,
    ) -> UncertaintyResult:
        """Propagate Gaussian sensor errors through the point and bootstrap PCEs.

        Parameters
        ----------
        delta_v_kmh : float
            Resultant delta-V, km/h.
        angle_deg : float
            Signed PDOF - mode axis, deg (its magnitude is used).
        posture_deg : float
            Lumbar flexion reading, deg.
        seat_track_mm : float
            Seat track reading, mm forward of mid track.
        duration_ms : float
            Haversine duration T, ms.
        posture_sd_deg, seat_track_sd_mm : float, optional
            Sensor standard deviations (deg, mm); 0 gives a point input.
        age_years : float, optional
            Occupant age, years: selects the age-dependent frontal chest
            deflection curve in P(ISS >= 15), as the direct LPM assessment does.

        Returns
        -------
        UncertaintyResult

        Raises
        ------
        ValueError
            Non-finite inputs or negative standard deviations.
        """
        vals = (delta_v_kmh, angle_deg, posture_deg, seat_track_mm, duration_ms)
        if not all(math.isfinite(v) for v in vals):
            raise ValueError("propagate: inputs must be finite")
        if not (posture_sd_deg >= 0.0 and seat_track_sd_mm >= 0.0):
            raise ValueError("propagate: standard deviations must be >= 0")
        x = np.array([delta_v_kmh, abs(angle_deg), posture_deg, seat_track_mm, duration_ms])
        xc = np.clip(x, self._lo, self._hi)
        clamped = tuple(
            n
            for n, a, b in zip(INPUT_NAMES, x, xc, strict=True)
            if abs(a - b) > 1e-9 * (1.0 + abs(a))
        )
        # sensor samples, clipped to the domain; row 0 is the reading itself
        post = np.empty(N_SENSOR_SAMPLES + 1)
        seat = np.empty(N_SENSOR_SAMPLES + 1)
        post[0], seat[0] = xc[_POSTURE], xc[_SEAT]
        post[1:] = np.clip(
            xc[_POSTURE] + posture_sd_deg * _NORMALS[:, 0], self._lo[_POSTURE], self._hi[_POSTURE]
        )
        seat[1:] = np.clip(
            xc[_SEAT] + seat_track_sd_mm * _NORMALS[:, 1], self._lo[_SEAT], self._hi[_SEAT]
        )
        w = self._weights(xc[0])[0]
        parts = [
            w[i] * self._pieces[int(i)].samples(xc[None, :], post, seat)
            for i in np.flatnonzero(w > 0.0)
        ]
        raw: FloatArray = parts[0] if len(parts) == 1 else parts[0] + parts[1]
        measures: dict[str, float] = {}
        cis: dict[str, tuple[float, float]] = {}
        n_out, nb1 = int(raw.shape[0]), int(raw.shape[1])
        # P(ISS >= 15) from the measures: the point PCEs at every sensor sample,
        # the replicates at the subset (control variate: each replicate's
        # deviation from the point PCEs on the same subset)
        rm = raw[self._meas_rows]
        p_point = self._p_from_raw(rm[:, 0, 1:], age_years)  # (n,)
        p_sub = np.empty((nb1, _P_SUBSET.size))  # (B + 1, n_sub)
        p_sub[0] = p_point[_P_SUBSET]
        p_sub[1:] = self._p_from_raw(rm[:, 1:, 1 + _P_SUBSET], age_years)
        sub_means = p_sub.mean(axis=1)
        # 95% intervals of measures and ISS: order statistics of the pooled
        # (replicates x samples) values on the fitted scale, then transformed
        # (the transforms are monotone, so this equals transforming first)
        pooled = raw[:, 1:, 1:].reshape(n_out, -1)
        n = pooled.shape[1]
        k_lo = max(math.ceil(_PCT[0] / 100.0 * n) - 1, 0)
        k_hi = max(math.ceil(_PCT[1] / 100.0 * n) - 1, 0)
        part = np.partition(pooled, (k_lo, k_hi), axis=1)
        means = np.clip(float(p_point.mean()) + (sub_means - sub_means[0]), 0.0, 1.0)
        p = float(p_point.mean())
        lo, hi = np.percentile(means[1:], _PCT)
        # widened about its centre on the logit scale by the held-out
        # calibration factor (the surrogate's own error)
        g_lo, g_hi = to_output_scale("p_iss15", np.array([lo, hi]))
        c = 0.5 * (g_lo + g_hi)
        f = self.p_interval_inflation
        w_lo, w_hi = from_output_scale(
            "p_iss15", np.array([c - f * (c - g_lo), c + f * (g_hi - c)])
        )
        p_ci = (min(float(lo), float(w_lo)), max(float(hi), float(w_hi)))
        iss = 0.0
        iss_ci = (0.0, 0.0)
        for k, name in enumerate(self._fitted):
            point = float(from_output_scale(name, raw[k, 0, 0]))
            # the surrogate's own error (held-out calibrated 95% bound m at the
            # reading) added in quadrature to each side of the sensor x bootstrap
            # interval about the point value: independent errors; a measure the
            # sensors do not move gets +-m, one they move a lot little more
            m = self.interval_factors.get(name, 0.0) * float(_bootstrap_sd(raw[k, 1:, 0], name))
            mid, q_lo, q_hi = float(raw[k, 0, 0]), float(part[k, k_lo]), float(part[k, k_hi])
            g_lo = min(q_lo, mid - math.hypot(max(mid - q_lo, 0.0), m))
            g_hi = max(q_hi, mid + math.hypot(max(q_hi - mid, 0.0), m))
            lo, hi = (float(v) for v in from_output_scale(name, np.array([g_lo, g_hi])))
            if name == "iss":
                iss, iss_ci = point, (lo, hi)
            else:
                measures[name] = point
                cis[name] = (lo, hi)
        return UncertaintyResult(
            p_iss15=p,
            p_iss15_ci95=p_ci,
            iss=iss,
            iss_ci95=iss_ci,
            measures=MappingProxyType(measures),
            measures_ci95=MappingProxyType(cis),
            n_samples=N_SENSOR_SAMPLES,
            n_bootstrap=nb1 - 1,
            clamped_inputs=clamped,
            p_interval_inflation=self.p_interval_inflation,
        )


#: Families already assembled in this process, by the SHA-256 of their artifact
#: file (content-addressed: the same bytes give the same immutable family). A
#: load still reads and checks every file's checksum against the manifest; only
#: the assembly (about 0.1 s and 14 MB per family) is shared, e.g. between the
#: apps a test session creates.
_FAMILY_CACHE: dict[str, SurrogateFamily] = {}


class SurrogateLibrary:
    """The verified set of surrogate families (immutable).

    Attributes
    ----------
    name, version : str
        From the manifest.
    sha256 : str
        SHA-256 of ``manifest.json``.
    lpm_code_sha256, parameter_set_sha256 : str
        Checksums of the LPM code and parameter set the families were built from.
    engine_version : str
    """

    __slots__ = (
        "_families",
        "directory",
        "engine_version",
        "lpm_code_sha256",
        "manifest",
        "name",
        "parameter_set_sha256",
        "sha256",
        "version",
    )

    name: str
    version: str
    sha256: str
    lpm_code_sha256: str
    parameter_set_sha256: str
    engine_version: str
    directory: Path
    manifest: Mapping[str, Any]
    _families: Mapping[str, SurrogateFamily]

    def __setattr__(self, key: str, value: object) -> None:
        if hasattr(self, key):
            raise AttributeError(f"SurrogateLibrary is immutable ({key})")
        object.__setattr__(self, key, value)

    @classmethod
    def load(cls, directory: Path | None = None, *, require_all: bool = True) -> SurrogateLibrary:
        """Load and verify the artifacts of `directory` (default: the shipped ones).

        Parameters
        ----------
        directory : Path, optional
        require_all : bool, optional
            Require every family of :data:`models.surrogate.spec.FAMILIES`
            (False for partial test libraries).

        Raises
        ------
        ValueError
            With the reason: manifest missing or malformed, a file missing, a
            checksum mismatch, an artifact recording other LPM checksums than
            the manifest, or (``require_all``) a family missing.
        """
        d = default_artifact_dir() if directory is None else Path(directory)
        mpath = d / MANIFEST_NAME
        if not mpath.is_file():
            raise ValueError(f"surrogate manifest missing: {mpath}")
        try:
            manifest = json.loads(mpath.read_bytes())
            files: dict[str, str] = dict(manifest["files"])
            keys = ("name", "version", "lpm_code_sha256", "parameter_set_sha256", "engine_version")
            ident = {k: str(manifest[k]) for k in keys}
        except (ValueError, KeyError, TypeError) as exc:
            raise ValueError(f"surrogate manifest malformed: {exc}") from exc
        families: dict[str, SurrogateFamily] = {}
        for fname, digest in sorted(files.items()):
            path = d / fname
            if not path.is_file():
                raise ValueError(f"surrogate artifact missing: {fname}")
            actual = sha256_file(path)
            if actual != digest:
                raise ValueError(
                    f"surrogate artifact checksum mismatch: {fname} "
                    f"(manifest {digest[:12]}..., file {actual[:12]}...)"
                )
            fam = _FAMILY_CACHE.get(actual)
            if fam is None:
                arrays, meta = read_artifact(path)
                fam = SurrogateFamily.from_arrays(arrays, meta)
                _FAMILY_CACHE[actual] = fam
            for k in ("lpm_code_sha256", "parameter_set_sha256", "engine_version"):
                if str(fam.meta.get(k)) != ident[k]:
                    raise ValueError(f"surrogate artifact {fname}: {k} differs from the manifest")
            families[fam.name] = fam
        if require_all:
            missing = [s.name for s in FAMILIES if s.name not in families]
            if missing:
                raise ValueError(f"surrogate families missing: {', '.join(missing)}")
        self = cls.__new__(cls)
        for k, v in ident.items():
            object.__setattr__(self, k, v)
        object.__setattr__(self, "sha256", sha256_file(mpath))
        object.__setattr__(self, "directory", d)
        object.__setattr__(self, "manifest", MappingProxyType(manifest))
        object.__setattr__(self, "_families", MappingProxyType(families))
        return self

    def families(self) -> Mapping[str, SurrogateFamily]:
        """Every loaded family by name (read-only mapping)."""
        return self._families

    @property
    def family_names(self) -> tuple[str, ...]:
        """Names of the loaded families."""
        return tuple(sorted(self._families))

    def family(
        self, mode: ImpactMode, body: Body, belted: bool, airbag_deployed: bool
    ) -> SurrogateFamily:
        """The family for a mode, body and restraint configuration.

        ``airbag_deployed`` is the mode's airbag: the frontal airbag (frontal),
        the side and curtain airbags (near side). Rear and far-side families
        serve every airbag state (no airbag acts in those LPMs; see
        :mod:`models.surrogate.spec`).

        Raises
        ------
        KeyError
            When the family is not in the library.
        """
        mode = ImpactMode(mode)
        bag: bool | None = bool(airbag_deployed) if mode in AIRBAG_MODES else None
        return self._families[family_name(mode, Body(body), bool(belted), bag)]

    def stale_reason(self) -> str | None:
        """Why the library no longer fits the occupant models, or None.

        What the families depend on is checked by running it: the parameter
        values (their checksum) and the golden cases recorded in the manifest
        (:mod:`models.surrogate.golden`), rerun now. A docstring edit, a
        reformat or a refactor that keeps the numbers leaves the library
        current; a change of physics or of a parameter value does not.
        """
        from models import ENGINE_VERSION
        from models.lpm.params import load_parameter_set
        from models.surrogate.golden import golden_mismatch

        golden = self.manifest.get("golden")
        if not golden:
            return "the surrogate manifest records no golden cases; rebuild the surrogates"
        if self.engine_version != ENGINE_VERSION:
            return (
                f"surrogates were built by engine {self.engine_version}, running {ENGINE_VERSION}"
            )
        specs = {s.name: s for s in FAMILIES}
        reason = golden_mismatch(golden, specs, load_parameter_set())
        if reason is not None:
            return reason
        return None
