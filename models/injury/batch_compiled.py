"""Risk curves and P(ISS >= t) of measure sets in one compiled pass: the request path's.

:func:`models.injury.batch.p_iss_at_least_batch` (numpy) is the reference:
risk curves per measure, combined per region, regional AIS distributions,
the closed-form sum over the chest and abdomen levels with the head-neck
level each pair leaves to reach the threshold. The surrogate's request path
asks for it on about 3,700 measure sets per occupant, where numpy's hundred
array operations (each a pass over the sets with a temporary) cost more than
the curves' exponentials. This module runs the same arithmetic set by set:

* the curves' arguments that need numpy's own power (``D ** 0.4612`` of the
  chest curves: numpy's power is not the C library's on every processor) and
  the clipped or combined measures are formed with numpy first, once per
  call (:func:`curve_inputs`); every logistic is then ``1 / (1 + exp(-z))``
  with the C library's exponential, which is scipy's ``expit`` (the same
  operations, so the same bits);
* within a region, per level the highest curve that publishes it, then the
  running maximum from AIS 6 down (maxima: exact in any order);
* a head-neck level is evaluated for a set only when a (chest, abdomen) pair
  of non-zero probability asks for it; a term of zero probability is left out
  of the sum (adding +0 changes no bit), and the sum runs over the pairs in
  the reference's order.

Why hand-written: no library scores ISS, and the numpy reference cannot be
fused; ``tests/models/injury/test_batch_compiled.py`` holds the two equal
bit for bit over random measures of every mode, body, age option and
threshold. [R] 3,696 sets of the frontal 50M: 0.38 -> 0.28 ms alone, 0.46 ->
0.37 ms in the request (measured 2026-12-05); about 0.15 ms of it is the C
library's exponential, eight per set.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

import numpy as np
from numba import njit

from models.arrays import FloatArray, IntArray
from models.impact_mode import ImpactMode
from models.injury import risk
from models.injury.batch import _HIC_NESTED_TOP, _a_min
from models.injury.criteria import CTI_INTERCEPTS
from models.injury.scores import ISS_REGIONS, ISS_TRIAGE_THRESHOLD, MAX_AIS
from models.notification import Body

__all__ = [
    "CurveInputs",
    "curve_inputs",
    "p_iss15_trusted",
    "p_iss_at_least_compiled",
    "region_blocks_compiled",
]

_SIDE_MODES: Final[frozenset[ImpactMode]] = frozenset({ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE})

#: Curve forms: the logistic's argument ``z`` from the row ``x`` and (alpha, beta).
_FORM_LOGISTIC: Final[int] = 0  # z = beta x - alpha (risk._logistic)
_FORM_INTERCEPT: Final[int] = 1  # z = alpha + beta x (the age-dependent chest curve)

_HIC_ALPHA: Final = np.array(risk.HIC_PRASAD_MERTZ_ALPHA)
_HIC_BETA: Final = np.array(risk.HIC_PRASAD_MERTZ_BETA)
#: The 200/HIC term's constant of the Prasad/Mertz curves (risk, [S]).
_HIC_HYPERBOLIC: Final[float] = risk._PRASAD_MERTZ_HYPERBOLIC
#: Eppinger Nij levels 2..5 as rows (level, alpha, beta), increasing level.
_NIJ: Final = np.array([[lv, *risk.NIJ_EPPINGER_1999[lv]] for lv in sorted(risk.NIJ_EPPINGER_1999)])

#: The chest and abdomen curves as the kernels take them (:meth:`CurveInputs.curves`).
_Curves = tuple[
    FloatArray, IntArray, FloatArray, FloatArray, IntArray, IntArray, IntArray, IntArray
]


@dataclass(frozen=True, slots=True)
class CurveInputs:
    """The measure sets as the compiled pass reads them (see :func:`curve_inputs`).

    Attributes
    ----------
    hic, nij : ndarray, shape (n,) or (0,)
        Empty when the measure is absent.
    rows : ndarray, shape (k, n)
        The argument ``x`` of each chest and abdomen curve.
    region, level, form : ndarray of int64, shape (k,)
        Per curve: region (0 chest, 1 abdomen), AIS level, form of its argument.
    alpha, beta : ndarray, shape (k,)
        Per curve: the logistic's coefficients.
    order : ndarray of int64, shape (k,)
        The curves by region, then from the highest level down: each region's
        running maximum takes them in one sweep, region r's are
        ``order[first[r]:first[r + 1]]``.
    first : ndarray of int64, shape (3,)
    top : ndarray of int64, shape (2,)
        Each region's highest level (0: no curve).
    n : int
        Number of sets.
    """

    hic: FloatArray
    nij: FloatArray
    rows: FloatArray
    region: IntArray
    level: IntArray
    form: IntArray
    alpha: FloatArray
    beta: FloatArray
    order: IntArray
    first: IntArray
    top: IntArray
    n: int

    def curves(self) -> _Curves:
        """The chest and abdomen curves as the kernels take them."""
        return (
            self.rows,
            self.form,
            self.alpha,
            self.beta,
            self.level,
            self.order,
            self.first,
            self.top,
        )


def _vc_spec(vc25: float) -> tuple[float, float]:
    """(alpha, beta) of ``risk._vc_curve``: the same two products."""
    vc50 = risk.VC_RISK_SLOPE_RATIO * vc25
    beta = math.log(3.0) / (vc50 - vc25)
    return beta * vc50, beta


def curve_inputs(
    values: Mapping[str, FloatArray],
    n: int,
    body: Body,
    age_years: float | None,
    impact_mode: ImpactMode | str,
) -> CurveInputs:
    """The curves of ``batch._regions`` for checked measures, as rows and a table.

    `values` as for ``batch.region_blocks_checked``: 1-D float64 arrays of
    size `n`, finite and >= 0. Absent measures give no curve.
    """
    body = Body(body)
    mode = ImpactMode(impact_mode)
    rows: list[FloatArray] = []
    spec: list[tuple[float, float, float, float, float]] = []
    d = values.get("chest_deflection_mm")
    if mode in _SIDE_MODES:
        if d is not None:
            alpha, beta = risk.ES2RE_THORAX_NCAP_2008
            rows.append(np.maximum(d, 0.0))
            spec.append((0, 3, _FORM_LOGISTIC, alpha, beta))
        if "chest_vc_m_s" in values:
            rows.append(np.maximum(values["chest_vc_m_s"], 0.0))
            spec.append((0, 4, _FORM_LOGISTIC, *_vc_spec(risk.VC_TOLERANCE_VIANO_1989_CHEST)))
        if "abdomen_vc_m_s" in values:
            rows.append(np.maximum(values["abdomen_vc_m_s"], 0.0))
            spec.append((1, 4, _FORM_LOGISTIC, *_vc_spec(risk.VC_TOLERANCE_VIANO_1989_ABDOMEN)))
    else:
        if d is not None:
            beta = risk.CHEST_DEFLECTION_NCAP_2008_BETA[body]
            powered = np.maximum(d, 0.0) ** risk.CHEST_DEFLECTION_NCAP_2008_EXPONENT
            rows.append(powered)
            if age_years is None:
                spec.append((0, 3, _FORM_LOGISTIC, risk.CHEST_DEFLECTION_NCAP_2008_ALPHA, beta))
            else:
                age = float(age_years)
                if not (math.isfinite(age) and age >= 0.0):
                    raise ValueError("`age_years` must be a finite non-negative number")
                intercept = risk.LAITURI_2005_INTERCEPT + risk.LAITURI_2005_AGE_COEFFICIENT * age
                spec.append((0, 3, _FORM_INTERCEPT, intercept, beta))
        if "chest_vc_m_s" in values:
            rows.append(np.maximum(values["chest_vc_m_s"], 0.0))
            spec.append((0, 4, _FORM_LOGISTIC, *_vc_spec(risk.VC_TOLERANCE_LAU_VIANO_1986_CHEST)))
        if "abdomen_vc_m_s" in values:
            rows.append(np.maximum(values["abdomen_vc_m_s"], 0.0))
            spec.append((1, 5, _FORM_LOGISTIC, *_vc_spec(risk.VC_TOLERANCE_LAU_VIANO_1986_ABDOMEN)))
    cti = values.get("chest_cti")
    if cti is None and "chest_a3ms_g" in values and d is not None:
        ic = CTI_INTERCEPTS[body]
        cti = values["chest_a3ms_g"] / ic.acceleration_g + d / ic.deflection_mm
    if cti is not None:
        rows.append(np.asarray(cti, dtype=np.float64))
        spec.append(
            (0, 3, _FORM_LOGISTIC, risk.CTI_KLEINBERGER_1998_ALPHA, risk.CTI_KLEINBERGER_1998_BETA)
        )
    table = np.array(spec, dtype=np.float64).reshape(len(spec), 5)
    region = table[:, 0].astype(np.int64)
    level = table[:, 1].astype(np.int64)
    top = np.zeros(2, dtype=np.int64)
    for r, lv in zip(region.tolist(), level.tolist(), strict=True):
        top[r] = max(top[r], lv)
    first = np.array([0, np.count_nonzero(region == 0), region.size], dtype=np.int64)
    empty = np.empty(0)
    return CurveInputs(
        hic=values.get("hic15", empty),
        nij=values.get("nij", empty),
        rows=np.array(rows, dtype=np.float64).reshape(len(rows), n),
        region=region,
        level=level,
        form=table[:, 2].astype(np.int64),
        alpha=np.ascontiguousarray(table[:, 3]),
        beta=np.ascontiguousarray(table[:, 4]),
        order=np.argsort(region * 8 - level, kind="stable").astype(np.int64),
        first=first,
        top=top,
        n=n,
    )


def p_iss_at_least_compiled(inputs: CurveInputs, threshold: float) -> FloatArray:
    """P(ISS >= threshold) of each set: ``batch._p_iss_at_least``'s numbers.

    Parameters
    ----------
    inputs : CurveInputs
    threshold : float
        At most 75.

    Returns
    -------
    ndarray, shape (n,)
    """
    return _p_iss_kernel(
        inputs.n, inputs.hic, inputs.nij, inputs.curves(), _a_min(float(threshold))
    )


#: Regions the LPM measures inform, in the order of the compiled blocks.
_BLOCK_REGIONS: Final[tuple[str, ...]] = ("head_neck", "chest", "abdomen")


def region_blocks_compiled(
    values: Mapping[str, FloatArray],
    n: int,
    body: Body,
    age_years: float | None = None,
    impact_mode: ImpactMode | str = ImpactMode.FRONTAL,
) -> dict[str, FloatArray]:
    """``batch.region_blocks_checked``: the same numbers, in one compiled pass.

    `values` as there (checked by the caller). Returns every region of
    ``ISS_REGIONS``, each shape (6, n), row k - 1 P(AIS >= k); the regions the
    measures do not inform are zeros. [R] one measure set (``assess``): 0.14
    -> 0.04 ms in the request (measured 2026-12-05), the numpy path's hundred
    array operations on one value each replaced by one call.
    """
    inputs = curve_inputs(values, n, body, age_years, impact_mode)
    blocks = _region_blocks_kernel(inputs.n, inputs.hic, inputs.nij, inputs.curves())
    out = {}
    for region in ISS_REGIONS:
        if region in _BLOCK_REGIONS:
            out[region] = blocks[_BLOCK_REGIONS.index(region)]
        else:
            out[region] = np.zeros((MAX_AIS, inputs.n))
    return out


def p_iss15_trusted(
    values: Mapping[str, FloatArray],
    body: Body,
    age_years: float | None = None,
    impact_mode: ImpactMode | str = ImpactMode.FRONTAL,
) -> FloatArray:
    """``batch.p_iss15_batch`` of measures the caller guarantees: the same numbers.

    For the surrogate's request path, whose measures come out of the inverse
    output transforms: each value a 1-D float64 array of one common size,
    finite and >= 0, named in ``batch.MEASURE_NAMES`` (not checked here).
    """
    n = next(iter(values.values())).size if values else 0
    inputs = curve_inputs(values, n, body, age_years, impact_mode)
    return p_iss_at_least_compiled(inputs, ISS_TRIAGE_THRESHOLD)


@njit(cache=True, nogil=True, inline="always")
def _expit(z: float) -> float:
    """scipy's ``expit``: ``1 / (1 + exp(-z))`` with the C library's exponential."""
    return 1.0 / (1.0 + math.exp(-z))


@njit(cache=True, nogil=True, inline="always")
def _hic_curve(h: float, j: int) -> float:
    """The published Prasad/Mertz curve of level j + 1 at HIC `h` (0 at HIC <= 0)."""
    if not h > 0.0:
        return 0.0
    return _expit(_HIC_BETA[j] * h - _HIC_ALPHA[j] - _HIC_HYPERBOLIC / h)


@njit(cache=True, nogil=True, inline="always")
def _hic_level(h: float, k: int) -> float:
    """The Prasad/Mertz curve at level k, forced monotone (risk.hic_prasad_mertz_1999)."""
    if k <= _HIC_NESTED_TOP:
        return _hic_curve(h, k - 1)
    run = 2.0
    for j in range(k):
        run = min(run, _hic_curve(h, j))
    return run


@njit(cache=True, nogil=True, inline="always")
def _nij_curve(x: float, j: int) -> float:
    """The published Eppinger curve of row j of :data:`_NIJ` at Nij `x`."""
    return _expit(_NIJ[j, 2] * x - _NIJ[j, 1])


@njit(cache=True, nogil=True, inline="always")
def _region_cumulative(i: int, curves: _Curves, cv: FloatArray, cum: FloatArray) -> None:
    """P(AIS >= level) of chest (row 0) and abdomen (row 1) of set `i` into `cum`.

    Per curve its logistic (into the workspace `cv`), then per region from its
    highest level down the running maximum of the curves that publish each
    level, clipped to [0, 1] (``batch._combine``); levels above a region's top
    are not written.
    """
    rows, form, alpha, beta, level, order, first, top = curves
    for j in range(rows.shape[0]):
        x = rows[j, i]
        z = beta[j] * x - alpha[j] if form[j] == _FORM_LOGISTIC else alpha[j] + beta[j] * x
        cv[j] = _expit(z)
    for r in range(2):
        run = -1.0  # below every curve value (each in [0, 1])
        pos = first[r]
        for lv in range(top[r], 0, -1):
            while pos < first[r + 1] and level[order[pos]] == lv:
                run = max(run, cv[order[pos]])
                pos += 1
            cum[r, lv] = min(max(run, 0.0), 1.0)


@njit(cache=True, nogil=True, error_model="numpy")
def _p_iss_kernel(
    n: int, hic: FloatArray, nij: FloatArray, curves: _Curves, a_min: IntArray
) -> FloatArray:
    """The pass over the sets (see the module notes)."""
    top = curves[7]
    has_hic = hic.shape[0] > 0
    has_nij = nij.shape[0] > 0
    out = np.empty(n)
    cv = np.empty(max(curves[0].shape[0], 1))
    cum = np.zeros((2, 8))  # P(AIS >= level) per region
    dist = np.zeros((2, 7))  # P(AIS = level) per region
    head = np.empty(7)
    nij_mono = np.empty(_NIJ.shape[0])
    for i in range(n):
        _region_cumulative(i, curves, cv, cum)
        for r in range(2):
            t = top[r]
            if t == 0:
                dist[r, 0] = 1.0
                continue
            dist[r, 0] = max(1.0 - cum[r, 1], 0.0)
            for lv in range(1, t):
                dist[r, lv] = max(cum[r, lv] - cum[r, lv + 1], 0.0)
            dist[r, t] = cum[r, t]
        for lv in range(7):
            head[lv] = -1.0  # not evaluated yet
        nij_done = 0
        total = 0.0
        for b in range(top[0] + 1):
            pb = dist[0, b]
            if pb == 0.0:
                continue  # a term of zero: +0 changes no bit of the sum
            for c in range(top[1] + 1):
                pc = dist[1, c]
                if pc == 0.0:
                    continue
                k = a_min[b, c]
                if k == 0:
                    total += pb * pc * 1.0
                    continue
                if head[k] < 0.0:
                    v = 0.0
                    if has_hic:
                        v = max(v, _hic_level(hic[i], k))
                    if has_nij:
                        # the monotone Nij curves at their first published level >= k
                        for j in range(_NIJ.shape[0]):
                            if j >= nij_done:
                                cj = _nij_curve(nij[i], j)
                                nij_mono[j] = cj if j == 0 else min(nij_mono[j - 1], cj)
                                nij_done = j + 1
                            if _NIJ[j, 0] >= k:
                                v = max(v, nij_mono[j])
                                break
                    head[k] = min(v, 1.0)
                total += pb * pc * head[k]
        out[i] = min(max(total, 0.0), 1.0)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def _region_blocks_kernel(n: int, hic: FloatArray, nij: FloatArray, curves: _Curves) -> FloatArray:
    """P(AIS >= k) of head and neck, chest and abdomen per set, shape (3, 6, n).

    ``batch._regions`` set by set: the HIC curves at every level and the Nij
    curves at theirs, each forced monotone (cumulative minimum up the levels),
    then per level from AIS 6 down the running maximum of the curves that
    publish it, clipped to [0, 1]; levels above a region's highest curve 0.
    """
    top = curves[7]
    has_hic = hic.shape[0] > 0
    has_nij = nij.shape[0] > 0
    n_hic = _HIC_ALPHA.shape[0]
    n_nij = _NIJ.shape[0]
    out = np.zeros((3, 6, n))
    hic_c = np.empty(n_hic)
    nij_c = np.empty(n_nij)
    cv = np.empty(max(curves[0].shape[0], 1))
    cum = np.zeros((2, 8))
    for i in range(n):
        if has_hic:
            run = 2.0
            for j in range(n_hic):
                run = min(run, _hic_curve(hic[i], j))
                hic_c[j] = run
        if has_nij:
            for j in range(n_nij):
                c = _nij_curve(nij[i], j)
                nij_c[j] = c if j == 0 else min(nij_c[j - 1], c)
        have = False
        run = -1.0
        for lv in range(6, 0, -1):
            if has_hic:
                run = hic_c[lv - 1] if not have else max(run, hic_c[lv - 1])
                have = True
            if has_nij:
                for j in range(n_nij):
                    if int(_NIJ[j, 0]) == lv:
                        run = nij_c[j] if not have else max(run, nij_c[j])
                        have = True
            if have:
                out[0, lv - 1, i] = min(max(run, 0.0), 1.0)
        _region_cumulative(i, curves, cv, cum)
        for r in range(2):
            for lv in range(1, top[r] + 1):
                out[1 + r, lv - 1, i] = cum[r, lv]
    return out


def warm_up() -> None:
    """Compile (or load from the numba cache) the pass."""
    inputs = curve_inputs(
        {"hic15": np.ones(1), "nij": np.ones(1), "chest_deflection_mm": np.ones(1)},
        1,
        Body.MALE_50TH,
        None,
        ImpactMode.FRONTAL,
    )
    p_iss_at_least_compiled(inputs, ISS_TRIAGE_THRESHOLD)
    region_blocks_compiled({"hic15": np.ones(1)}, 1, Body.MALE_50TH)
