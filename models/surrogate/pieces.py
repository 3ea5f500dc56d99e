"""The piece kinds of a surrogate family: one delta-V piece's point and bootstrap PCEs.

A family (:mod:`models.surrogate.family`) is a blend of delta-V pieces; each
piece is plain (:class:`_Piece`), split at the head's strike onset with a gate
(:class:`_SplitPiece`), or carries the Kriging of its residuals
(:class:`_KrigedPiece`). :func:`_piece` builds the right kind from an artifact.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Final

import numpy as np
import numpy.typing as npt

from models.arrays import FloatArray, IntArray
from models.surrogate.basis import design_matrix, evaluate_univariate, evaluate_univariate_at
from models.surrogate.family_constants import _POSTURE, _SEAT
from models.surrogate.kernels import add_correction, grouped_coefficients
from models.surrogate.kriging import ResidualKriging
from models.surrogate.spec import (
    HEAD_CLEARANCE,
    INPUT_NAMES,
    to_unit,
)

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
        "_coef_cols",
        "_coef_ptr",
        "_coef_t",
        "_coef_vals",
        "_group_ptr",
        "_hi",
        "_lo",
        "_maxdeg",
        "_nb1",
        "_pairs",
        "_ranges",
        "_recs",
        "_terms",
        "outputs",
    )

    outputs: tuple[str, ...]
    _coef_t: FloatArray
    #: `_coef_t` in compressed sparse rows (row pointers, columns, values)
    _coef_ptr: IntArray
    _coef_cols: IntArray
    _coef_vals: FloatArray
    #: CSR row pointers of the (posture, seat track) groups over the sorted terms
    _group_ptr: IntArray
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
        # each candidate term's row in the sorted order; the coefficients are
        # scattered straight into (terms, outputs x replicates), column k (B + 1) + r
        # for output k and replicate r (0: the point PCE)
        row = np.full(cand.shape[0], -1, dtype=np.int64)
        row[used[order]] = np.arange(used.size)
        coef_t = np.zeros((used.size, len(outputs) * (nb + 1)))
        for k, ((pt, pc), (off, bt, bc)) in enumerate(zip(point, boots, strict=True)):
            coef_t[row[pt], k * (nb + 1)] = pc
            reps = np.repeat(np.arange(1, nb + 1), np.diff(off))
            coef_t[row[bt], k * (nb + 1) + reps] = bc
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
        group_ptr = np.append(starts, n_terms).astype(np.int64)
        group_ptr.flags.writeable = False
        sa(self, "_group_ptr", group_ptr)
        nz_rows, nz_cols = np.nonzero(coef_t)  # row-major: columns increasing per row
        coef_ptr = np.searchsorted(nz_rows, np.arange(n_terms + 1)).astype(np.int64)
        coef_cols = nz_cols.astype(np.int64)
        coef_vals = np.ascontiguousarray(coef_t[nz_rows, nz_cols])
        for arr in (coef_ptr, coef_cols, coef_vals):
            arr.flags.writeable = False
        sa(self, "_coef_ptr", coef_ptr)
        sa(self, "_coef_cols", coef_cols)
        sa(self, "_coef_vals", coef_vals)

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
        fixed = tuple(evaluate_univariate_at(float(z[j]), self._recs[j], md) for j in _FIXED_INPUTS)
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
        # other factor, (M, O(B+1)), over the coefficients' non-zeros only
        # (models.surrogate.kernels: the numbers of scipy's CSR product of a
        # one-entry-per-term (M, terms) matrix with the dense coefficients)
        c2 = grouped_coefficients(
            s,
            self._group_ptr,
            self._coef_ptr,
            self._coef_cols,
            self._coef_vals,
            self._coef_t.shape[1],
        )
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
        fixed, up, us = basis
        for side, w in ((self._contact, wc), (self._free, 1.0 - wc)):
            if np.all(w == 1.0):
                # one side only: 0.0 + 1.0 * x == x (the fitted values are never -0.0)
                return side.samples(xc, post, seat, basis)
        out = np.zeros((len(self.outputs), self.n_bootstrap + 1, post.size))
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
        out = self.base.samples(xc, post, seat)  # a fresh array: corrected in place
        add_correction(out, self.correction(pts))  # out += correction.T[:, None, :]
        return out


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
