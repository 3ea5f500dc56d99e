"""A surrogate family: its pieces blended over delta-V, and the propagation of sensor errors.

:meth:`SurrogateFamily.propagate` turns the occupant sensor uncertainty into
95% intervals (the method: :mod:`models.surrogate.evaluate`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

import numpy as np
import numpy.typing as npt
from threadpoolctl import threadpool_limits  # type: ignore[import-untyped]

from models.arrays import FloatArray, IntArray
from models.impact_mode import ImpactMode
from models.injury.batch_compiled import p_iss15_trusted
from models.notification import Body
from models.surrogate.family_constants import (
    _MIN_CALIBRATION_POINTS,
    _NORMALS,
    _P_SD_FLOOR,
    _P_SUBSET,
    _PCT,
    _POSTURE,
    _SEAT,
    _Z95,
    DEFAULT_POSTURE_SD_DEG,
    DEFAULT_SEAT_TRACK_SD_MM,
    N_SENSOR_SAMPLES,
    UncertaintyResult,
    _bootstrap_sd,
    _sd_floor,
)
from models.surrogate.kernels import gather_p_sets, pooled_order_statistics
from models.surrogate.pieces import _KrigedPiece, _Piece, _piece, _smoothstep, _SplitPiece
from models.surrogate.spec import (
    INPUT_NAMES,
    MEASURE_FLOORS,
    from_output_scale,
    measures_from_output_scale,
    to_output_scale,
)


def linear_percentiles(x: FloatArray, percents: tuple[float, ...]) -> tuple[float, ...]:
    """``np.percentile(x, percents)`` of finite 1-D `x` (the default linear method).

    The same numbers, bit for bit: numpy's virtual index ``(n - 1) q``, its
    neighbours and its interpolation ``a + (b - a) g`` (``b - (b - a)(1 - g)``
    from ``g = 0.5`` up), in Python floats, which are numpy's doubles. Why
    written out: ``np.percentile`` spends about 25 us on two percentiles of
    150 values in its general machinery (measured 2026-12-05); held equal to it
    by tests/models/surrogate/test_kernels.py.
    """
    s = np.sort(x)
    n = s.size
    out = []
    for pct in percents:
        vi = (n - 1) * (pct / 100)
        if vi >= n - 1:
            out.append(float(s[-1]))
            continue
        if vi < 0:
            out.append(float(s[0]))
            continue
        prev = math.floor(vi)
        a, b = float(s[prev]), float(s[prev + 1])
        g = vi - prev
        diff = b - a
        out.append(b - diff * (1 - g) if g >= 0.5 else a + diff * g)
    return tuple(out)


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
        "_blends",
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
    #: (j, centre, half width) of the blend zone about inner edge j, log km/h
    _blends: tuple[tuple[int, float, float], ...]
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
        # the blend zone about each inner edge (log delta-V): centre e, half width
        # half, over the part of the neighbours' design ranges that overlaps
        blends = []
        for j in range(1, len(pieces)):
            e = math.log(float(edges[j]))
            half = min(
                e - math.log(pieces[j].delta_v_design[0]),
                math.log(pieces[j - 1].delta_v_design[1]) - e,
            )
            if half > 0.0:
                blends.append((j, e, half))
        sa = object.__setattr__
        sa(self, "_blends", tuple(blends))
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
            # one BLAS thread, whatever the caller's setting: OpenBLAS splits these
            # products (hundreds of held-out runs) by thread count, which moved the
            # factors in the last bits, and with them the intervals of every answer
            # (tests/service/cases/test_determinism.py: a process that loaded the models
            # before capping its threads answered differently from one that did not)
            with threadpool_limits(limits=1, user_api="blas"):
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
        physical = measures_from_output_scale(self._measures, raw_measures)
        values = {name: physical[i].reshape(-1) for i, name in enumerate(self._measures)}
        p = p_iss15_trusted(values, self._body, age_years, self._mode)
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
        for j, e, half in self._blends:
            u = np.clip((v - (e - half)) / (2.0 * half), 0.0, 1.0)
            zone = (u > 0.0) & (u < 1.0)
            if not zone.any():
                continue  # no point in this edge's blend zone: w stays as set
            up = _smoothstep(u)
            w[zone, j - 1] = 1.0 - up[zone]
            w[zone, j] = up[zone]
            others = np.ones(n_p, dtype=bool)
            others[[j - 1, j]] = False
            w[np.ix_(zone, others)] = 0.0
        return w

    def _weights_at(self, dv: float) -> list[float]:
        """:meth:`_weights` at one delta-V (km/h), as floats: the same numbers.

        The request path asks for one point; numpy's scalar functions give the
        bits of its array loops (Python's :mod:`math` would not), without the
        array method's dozen small-array calls.
        """
        v = np.log(np.float64(dv))
        n_p = len(self._pieces)
        k = int(np.searchsorted(self._edges, np.exp(v), side="right")) - 1
        w = [0.0] * n_p
        w[min(max(k, 0), n_p - 1)] = 1.0
        for j, e, half in self._blends:
            u = min(max(float((v - (e - half)) / (2.0 * half)), 0.0), 1.0)
            if not 0.0 < u < 1.0:
                continue  # outside this edge's blend zone: w stays as set
            up = u * u * (3.0 - 2.0 * u)  # _smoothstep
            w = [0.0] * n_p
            w[j - 1], w[j] = 1.0 - up, up
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
        raw = self._sensor_outputs(xc, posture_sd_deg, seat_track_sd_mm)
        p, p_ci = self._p_and_interval(raw, age_years)
        points, cis = self._output_intervals(raw)
        iss, iss_ci = points.pop("iss", 0.0), cis.pop("iss", (0.0, 0.0))
        return UncertaintyResult(
            p_iss15=p,
            p_iss15_ci95=p_ci,
            iss=iss,
            iss_ci95=iss_ci,
            measures=MappingProxyType(points),
            measures_ci95=MappingProxyType(cis),
            n_samples=N_SENSOR_SAMPLES,
            n_bootstrap=int(raw.shape[1]) - 1,
            clamped_inputs=clamped,
            p_interval_inflation=self.p_interval_inflation,
        )

    def _sensor_outputs(
        self, xc: FloatArray, posture_sd_deg: float, seat_track_sd_mm: float
    ) -> FloatArray:
        """Fitted-scale outputs at the reading and its sensor samples, blended over the pieces.

        Parameters
        ----------
        xc : ndarray, shape (5,)
            Inputs clamped to the domain (:data:`INPUT_NAMES`).
        posture_sd_deg, seat_track_sd_mm : float
            Sensor standard deviations, deg and mm.

        Returns
        -------
        ndarray, shape (n_fitted, B + 1, N_SENSOR_SAMPLES + 1)
            Rows of :attr:`_fitted`; replicate 0 the point PCE; sample 0 the reading.
        """
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
        w = self._weights_at(float(xc[0]))
        # a weight of exactly 1 (inside one piece) multiplies nothing: x * 1.0 == x;
        # in a blend zone each piece's fresh array is weighted and summed in place
        # (the same products and sum as ``w0 * a + w1 * b``, without two temporaries)
        out: FloatArray | None = None
        for i, wi in enumerate(w):
            if wi > 0.0:
                part = self._pieces[i].samples(xc[None, :], post, seat)
                if wi != 1.0:
                    np.multiply(part, wi, out=part)
                if out is None:
                    out = part
                else:
                    np.add(out, part, out=out)
        assert out is not None, "every delta-V has a piece of positive weight"
        return out

    def _p_and_interval(
        self, raw: FloatArray, age_years: float | None
    ) -> tuple[float, tuple[float, float]]:
        """P(ISS >= 15) over the sensor spread and its 95% interval over the replicates.

        The point PCEs give P at every sensor sample (their mean is the
        estimate); the replicates at the subset :data:`_P_SUBSET` (control
        variate: each replicate's deviation from the point PCEs on the same
        subset). The interval is widened about its centre on the logit scale by
        the held-out calibration factor (the surrogate's own error).
        """
        nb1 = int(raw.shape[1])
        mr = self._meas_rows
        n_s = N_SENSOR_SAMPLES
        # one pass through the risk curves for both sets (each set's P is its own:
        # the batch is elementwise), [point PCE at every sample | replicates at the
        # subset], gathered from `raw` in one copy
        p_both = self._p_from_raw(gather_p_sets(raw, mr, _P_SUBSET), age_years)
        p_point = p_both[:n_s]  # (n,)
        p_sub = np.empty((nb1, _P_SUBSET.size))  # (B + 1, n_sub)
        p_sub[0] = p_point[_P_SUBSET]
        p_sub[1:] = p_both[n_s:].reshape(nb1 - 1, _P_SUBSET.size)
        sub_means = p_sub.mean(axis=1)
        p = float(p_point.mean())
        means = np.clip(p + (sub_means - sub_means[0]), 0.0, 1.0)
        lo, hi = linear_percentiles(means[1:], _PCT)  # np.percentile's numbers
        g_lo, g_hi = to_output_scale("p_iss15", np.array([lo, hi]))
        c = 0.5 * (g_lo + g_hi)
        f = self.p_interval_inflation
        w_lo, w_hi = from_output_scale(
            "p_iss15", np.array([c - f * (c - g_lo), c + f * (g_hi - c)])
        )
        return p, (min(float(lo), float(w_lo)), max(float(hi), float(w_hi)))

    def _output_intervals(
        self, raw: FloatArray
    ) -> tuple[dict[str, float], dict[str, tuple[float, float]]]:
        """Each fitted output (measures and ISS) at the reading and its 95% interval.

        Order statistics of the pooled (replicates x samples) values on the
        fitted scale, then transformed (the transforms are monotone, so this
        equals transforming first); the surrogate's own error (held-out
        calibrated 95% bound m at the reading) added in quadrature to each side
        about the point value: independent errors; an output the sensors do not
        move gets +-m, one they move a lot little more.
        """
        n_out = int(raw.shape[0])
        n = (int(raw.shape[1]) - 1) * (int(raw.shape[2]) - 1)
        k_lo = max(math.ceil(_PCT[0] / 100.0 * n) - 1, 0)
        k_hi = max(math.ceil(_PCT[1] / 100.0 * n) - 1, 0)
        # exact order statistics of each output's pooled (replicates x samples)
        # values, read in place (models.surrogate.kernels)
        q_los, q_his, finite = pooled_order_statistics(raw, k_lo, k_hi)
        if not finite:  # numpy's order (NaN last) for a pool that holds a NaN
            pooled = np.array(raw[:, 1:, 1:]).reshape(n_out, -1)
            q_los = np.partition(pooled, k_lo, axis=1)[:, k_lo]
            q_his = np.partition(pooled, k_hi, axis=1)[:, k_hi]
        # the replicates' spread at the reading, every output in one call (the same
        # bits as one call per output: pairwise sums over the same 150 values)
        sds = np.std(raw[:, 1:, 0], axis=1, ddof=1)
        fitted = np.empty((n_out, 3))  # [reading, low, high] per output, fitted scale
        for k, name in enumerate(self._fitted):
            m = self.interval_factors.get(name, 0.0) * max(float(sds[k]), _sd_floor(name))
            mid, q_lo, q_hi = float(raw[k, 0, 0]), float(q_los[k]), float(q_his[k])
            g_lo = min(q_lo, mid - math.hypot(max(mid - q_lo, 0.0), m))
            g_hi = max(q_hi, mid + math.hypot(max(q_hi - mid, 0.0), m))
            fitted[k] = (mid, g_lo, g_hi)
        # to physical values: the measures' rows in one pass (element-wise, the same
        # numbers as one call per output), the others one by one
        physical = np.empty_like(fitted)
        rows = [k for k, name in enumerate(self._fitted) if name in MEASURE_FLOORS]
        physical[rows] = measures_from_output_scale([self._fitted[k] for k in rows], fitted[rows])
        for k, name in enumerate(self._fitted):
            if name not in MEASURE_FLOORS:
                physical[k] = from_output_scale(name, fitted[k])
        values = physical.tolist()
        points = {name: values[k][0] for k, name in enumerate(self._fitted)}
        cis = {name: (values[k][1], values[k][2]) for k, name in enumerate(self._fitted)}
        return points, cis
