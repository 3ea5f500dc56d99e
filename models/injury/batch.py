"""P(ISS >= 15) of many measure sets at once: the batch counterpart of ``assess`` (numpy).

:func:`models.injury.assessment.assess` scores one occupant: risk curves per
measure, combined per ISS region, regional AIS distributions, then the exact
P(ISS >= 15) by dynamic programming over the six regions. The surrogate
evaluation (``models.surrogate.evaluate``) needs the same probability for
every sensor sample of every bootstrap replicate, about 15,000 measure sets
per occupant inside a 5 ms budget, which the scalar path cannot give (tens of
microseconds per call). This module computes the same numbers over arrays:

* the curves and the region each feeds are those of
  :func:`models.injury.assessment.region_cumulative_risk` (same functions of
  :mod:`models.injury.risk`, same levels, same choice by impact mode and age);
* the combination within a region is the same rule (per level the highest
  curve that publishes it, then the running maximum from AIS 6 down, from 0);
* P(ISS >= t) is summed in closed form over the regions that carry any risk:
  the LPM measures inform three regions (head and neck, chest, abdomen), so
  ``P = sum_(b, c) P(chest = b) P(abdomen = c) P(head_neck >= a_min(b, c))``
  with ``a_min`` the least head-neck level that brings the ISS to t
  (:data:`models.injury.scores` rules: sum of squares of the three highest
  regional levels, any AIS 6 gives 75). Level pairs with zero probability over
  the whole batch are skipped.

Why hand-written: no library scores ISS; the scalar functions are the
reference, and ``tests/injury/test_injury_batch.py`` holds the two paths equal
(relative 1e-12) over random measures of every mode, body and age option.
The request path runs the compiled form (:mod:`models.injury.batch_compiled`:
the region blocks of ``assess`` and the surrogate's P(ISS >= t)), held equal
to this module bit for bit; this module stays its reference.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import fields
from functools import lru_cache
from typing import Final

import numpy as np
import numpy.typing as npt

from models.arrays import FloatArray
from models.impact_mode import ImpactMode
from models.injury import risk
from models.injury.criteria import CTI_INTERCEPTS
from models.injury.measures import InjuryMeasures
from models.injury.scores import ISS_MAX, ISS_REGIONS, ISS_TRIAGE_THRESHOLD, MAX_AIS
from models.notification import Body

__all__ = [
    "MEASURE_NAMES",
    "p_iss_at_least_batch",
    "p_iss15_batch",
    "region_blocks_checked",
    "region_cumulative_risk_batch",
]


#: Measures the batch path reads (the fields of ``InjuryMeasures``).
MEASURE_NAMES: Final[tuple[str, ...]] = tuple(f.name for f in fields(InjuryMeasures))
_SIDE_MODES: Final[frozenset[ImpactMode]] = frozenset({ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE})


#: A curve of one measure: P(AIS >= level) by published level, each shape (n,).
Curve = dict[int, FloatArray]


def _monotone(curve: Curve) -> Curve:
    """``risk.force_monotone``: the cumulative minimum over the published levels."""
    out: Curve = {}
    run: FloatArray | None = None
    for level in sorted(curve):
        run = curve[level] if run is None else np.minimum(run, curve[level])
        out[level] = run
    return out


#: Highest AIS level up to which the Prasad/Mertz HIC curves are nested for
#: every HIC > 0: for n < n' <= 4, alpha_n < alpha_n' and beta_n > beta_n' (the
#: argument of level n exceeds that of level n' by more than 1.5 at any HIC), so
#: their cumulative minimum at level k is the level-k curve itself; AIS5+ and
#: AIS6 cross the lower levels above HIC of about 3250 (``risk.hic_prasad_mertz_1999``).
_HIC_NESTED_TOP: Final[int] = 4


def _hic_curves(hic: FloatArray, top: int = MAX_AIS) -> Curve:
    """``risk.hic_prasad_mertz_1999`` per level, AIS 1 to `top`."""
    return _monotone(risk.hic_prasad_mertz_1999_levels(hic, range(1, top + 1)))


def _hic_curves_at(hic: FloatArray, levels: set[int]) -> Curve:
    """:func:`_hic_curves` at the `levels` asked: the same numbers.

    Up to :data:`_HIC_NESTED_TOP` the curves are nested, so only the levels
    asked are evaluated (tests/injury/test_injury_batch.py holds this equal to
    the cumulative minimum, bit for bit); above it, every level up to the top.
    """
    if max(levels) > _HIC_NESTED_TOP:
        curves = _hic_curves(hic, max(levels))
        return {k: curves[k] for k in levels}
    return risk.hic_prasad_mertz_1999_levels(hic, sorted(levels))


def _nij_curves(nij: FloatArray, top: int = MAX_AIS) -> Curve:
    """``risk.nij_eppinger_1999`` per published level (AIS 2-5), up to the first one >= `top`."""
    raw: Curve = {}
    for level in sorted(risk.NIJ_EPPINGER_1999):
        raw[level] = risk.nij_eppinger_1999_level(nij, level)
        if level >= top:
            break
    return _monotone(raw)


def _combine(curves: list[Curve]) -> Curve:
    """Per level the highest curve that publishes it, then the running maximum
    from AIS 6 down starting at 0 (``assessment._combine``).

    Returns
    -------
    dict of int to ndarray
        P(AIS >= k) for k = 1 up to the highest level any curve publishes
        (higher levels are 0); empty without curves.
    """
    out: Curve = {}
    run: FloatArray | None = None
    for level in range(MAX_AIS, 0, -1):
        for c in curves:
            if level in c:
                run = c[level] if run is None else np.maximum(run, c[level])
        if run is not None:
            out[level] = np.minimum(np.maximum(run, 0.0), 1.0)
    return out


def _block(c: Curve, n: int) -> FloatArray:
    """A combined curve as a (6, n) block (row k - 1: P(AIS >= k))."""
    out = np.zeros((MAX_AIS, n))
    for level, v in c.items():
        out[level - 1] = v
    return out


def _values(values: Mapping[str, npt.ArrayLike]) -> tuple[dict[str, FloatArray], int]:
    unknown = set(values) - set(MEASURE_NAMES)
    if unknown:
        raise ValueError(f"unknown measures {sorted(unknown)}")
    out: dict[str, FloatArray] = {}
    sizes = set()
    for name, v in values.items():
        a = np.asarray(v, dtype=np.float64).reshape(-1)
        if not (np.all(np.isfinite(a)) and np.all(a >= 0.0)):
            raise ValueError(f"`{name}` must be finite and non-negative")
        out[name] = a
        sizes.add(a.size)
    if len(sizes) > 1:
        raise ValueError("every measure must have the same number of values")
    return out, (sizes.pop() if sizes else 0)


def _at(level: int, p: FloatArray) -> Curve:
    return {level: np.asarray(p, dtype=np.float64)}


def region_cumulative_risk_batch(
    values: Mapping[str, npt.ArrayLike],
    body: Body,
    age_years: float | None = None,
    impact_mode: ImpactMode | str = ImpactMode.FRONTAL,
) -> dict[str, FloatArray]:
    """P(AIS >= 1..6) per ISS region for n measure sets.

    Parameters
    ----------
    values : mapping of str to array_like, each shape (n,)
        Measures by name (:data:`MEASURE_NAMES`; units as in ``InjuryMeasures``:
        mm, m/s, g); an absent name gives no evidence, as None does in ``assess``.
    body : Body
    age_years : float, optional
        Selects the age-dependent frontal chest deflection curve (None: NCAP 2008).
    impact_mode : ImpactMode or str, optional

    Returns
    -------
    dict of str to ndarray, each shape (6, n)
        Every region of :data:`models.injury.scores.ISS_REGIONS`; row k - 1
        holds P(AIS >= k) (levels first, so that the per-level operations run
        over contiguous rows of n values).
    """
    v, n = _values(values)
    return region_blocks_checked(v, n, body, age_years, impact_mode)


def region_blocks_checked(
    values: Mapping[str, FloatArray],
    n: int,
    body: Body,
    age_years: float | None = None,
    impact_mode: ImpactMode | str = ImpactMode.FRONTAL,
) -> dict[str, FloatArray]:
    """:func:`region_cumulative_risk_batch` of measures the caller has checked.

    Each value a 1-D float64 array of size `n`, finite and >= 0, named in
    :data:`MEASURE_NAMES` (``models.injury.assessment`` checks its scalars
    itself). The same numbers.
    """
    return {r: _block(c, n) for r, c in _regions(values, n, body, age_years, impact_mode).items()}


def _regions(
    v: Mapping[str, FloatArray],
    n: int,
    body: Body,
    age_years: float | None,
    impact_mode: ImpactMode | str,
) -> dict[str, Curve]:
    body = Body(body)
    mode = ImpactMode(impact_mode)
    curves: dict[str, list[Curve]] = {r: [] for r in ISS_REGIONS}
    if "hic15" in v:
        curves["head_neck"].append(_hic_curves(v["hic15"]))
    if "nij" in v:
        curves["head_neck"].append(_nij_curves(v["nij"]))
    d = v.get("chest_deflection_mm")
    if mode in _SIDE_MODES:
        if d is not None:
            curves["chest"].append(_at(3, risk.thorax_rib_deflection_ais3_ncap_2008_es2re(d)))
        if "chest_vc_m_s" in v:
            vc = v["chest_vc_m_s"]
            curves["chest"].append(_at(4, risk.chest_vc_ais4_viano_1989_lateral(vc)))
        if "abdomen_vc_m_s" in v:
            va = v["abdomen_vc_m_s"]
            curves["abdomen"].append(_at(4, risk.abdomen_vc_ais4_viano_1989_lateral(va)))
    else:
        if d is not None:
            if age_years is None:
                p3 = risk.chest_deflection_ais3_ncap_2008(d, body)
            else:
                age = float(age_years)
                if not (math.isfinite(age) and age >= 0.0):
                    raise ValueError("`age_years` must be a finite non-negative number")
                p3 = risk.chest_deflection_ais3_laituri_2005(d, age, body)
            curves["chest"].append(_at(3, p3))
        if "chest_vc_m_s" in v:
            curves["chest"].append(_at(4, risk.chest_vc_ais4_lau_viano_1986(v["chest_vc_m_s"])))
        if "abdomen_vc_m_s" in v:
            va = v["abdomen_vc_m_s"]
            curves["abdomen"].append(_at(5, risk.abdomen_vc_ais5_lau_viano_1986(va)))
    cti = v.get("chest_cti")
    if cti is None and "chest_a3ms_g" in v and d is not None:
        ic = CTI_INTERCEPTS[body]
        cti = v["chest_a3ms_g"] / ic.acceleration_g + d / ic.deflection_mm
    if cti is not None:
        curves["chest"].append(_at(3, risk.chest_cti_ais3_kleinberger_1998(cti)))
    return {r: _combine(c) for r, c in curves.items()}


@lru_cache(maxsize=8)
def _a_min(threshold: float) -> npt.NDArray[np.int64]:
    """Least head-neck level a with ISS(a, b, c) >= threshold, per (b, c), shape (7, 7).

    6 when no level reaches it (a head-neck AIS 6 gives ISS 75, the largest).
    Cached and read-only: the request path asks for it twice per occupant.
    """
    out = np.full((MAX_AIS + 1, MAX_AIS + 1), MAX_AIS, dtype=np.int64)
    for b in range(MAX_AIS + 1):
        for c in range(MAX_AIS + 1):
            for a in range(MAX_AIS + 1):
                score = ISS_MAX if MAX_AIS in (a, b, c) else a * a + b * b + c * c
                if score >= threshold:
                    out[b, c] = a
                    break
    out.flags.writeable = False
    return out


def _levels(c: Curve, n: int) -> dict[int, FloatArray]:
    """P(AIS = k) of a combined curve, only the levels with probability anywhere.

    Unnormalised (``scores.ais_distribution_from_cumulative`` divides by a sum
    that is 1 within rounding: the differences of a non-increasing sequence).
    """
    if not c:
        return {0: np.ones(n)}
    top = max(c)
    out = {0: np.maximum(1.0 - c[1], 0.0)}
    for k in range(1, top + 1):
        out[k] = np.maximum(c[k] - c[k + 1], 0.0) if k < top else c[k]
    return {k: v for k, v in out.items() if np.any(v > 0.0)}


def _head_neck_at(
    values: Mapping[str, FloatArray], levels: set[int], n: int
) -> dict[int, FloatArray]:
    """P(head_neck AIS >= k) for the levels k asked, computing no level above them.

    The head-neck curves (HIC15, Nij) are non-increasing over their published
    levels after :func:`_monotone`, so the running maximum from AIS 6 down at
    level k is the larger of the HIC curve at k and the Nij curve at its
    lowest published level >= k (0 above AIS 5): the same numbers as
    :func:`region_cumulative_risk_batch` without the higher levels' exponentials.
    """
    top = max(levels) if levels else 0
    out = {k: np.zeros(n) for k in levels}
    curves: list[Curve] = []
    if "hic15" in values and top:
        curves.append(_hic_curves_at(values["hic15"], levels))
    if "nij" in values and top:
        curves.append(_nij_curves(values["nij"], top))
    for k in levels:
        for c in curves:
            first = next((j for j in sorted(c) if j >= k), None)
            if first is not None:
                out[k] = np.maximum(out[k], c[first])
    return {k: np.minimum(np.maximum(v, 0.0), 1.0) for k, v in out.items()}


def p_iss_at_least_batch(
    values: Mapping[str, npt.ArrayLike],
    body: Body,
    age_years: float | None = None,
    impact_mode: ImpactMode | str = ImpactMode.FRONTAL,
    threshold: float = ISS_TRIAGE_THRESHOLD,
) -> FloatArray:
    """Exact P(ISS >= threshold) of n measure sets, as ``scores.p_iss_at_least`` of each.

    Parameters are those of :func:`region_cumulative_risk_batch`, and
    `threshold` (at most 75). The head and neck enter only through
    P(AIS >= k) at the levels k that the chest and abdomen levels leave to
    reach the threshold (:func:`_head_neck_at`), which saves the exponentials
    of the other levels; regions other than head and neck, chest and abdomen
    carry no risk from the LPM measures.

    Returns
    -------
    ndarray, shape (n,)
        In [0, 1]; regions independent.
    """
    t = float(threshold)
    if not (math.isfinite(t) and t <= ISS_MAX):
        raise ValueError("`threshold` must be finite and at most 75")
    v, n = _values(values)
    return _p_iss_at_least(v, n, body, age_years, impact_mode, t)


def _p_iss_at_least(
    v: Mapping[str, FloatArray],
    n: int,
    body: Body,
    age_years: float | None,
    impact_mode: ImpactMode | str,
    t: float,
) -> FloatArray:
    """:func:`p_iss_at_least_batch` of checked values (`n` sets)."""
    others = {k: x for k, x in v.items() if k not in ("hic15", "nij")}
    cum = _regions(others, n, body, age_years, impact_mode)
    pb, pc = _levels(cum["chest"], n), _levels(cum["abdomen"], n)
    a_min = _a_min(t)
    pairs = [(b, c) for b in pb for c in pc]
    head = _head_neck_at(v, {int(a_min[b, c]) for b, c in pairs} - {0}, n)
    total = np.zeros(n)
    for b, c in pairs:
        k = int(a_min[b, c])
        total += pb[b] * pc[c] * (head[k] if k else 1.0)
    return np.minimum(np.maximum(total, 0.0), 1.0)


def p_iss15_batch(
    values: Mapping[str, npt.ArrayLike],
    body: Body,
    age_years: float | None = None,
    impact_mode: ImpactMode | str = ImpactMode.FRONTAL,
) -> FloatArray:
    """P(ISS >= 15) of n measure sets; equals ``assess(...).p_iss15`` of each set.

    :func:`p_iss_at_least_batch` at the triage threshold.

    Returns
    -------
    ndarray, shape (n,)
    """
    return p_iss_at_least_batch(values, body, age_years, impact_mode, ISS_TRIAGE_THRESHOLD)
