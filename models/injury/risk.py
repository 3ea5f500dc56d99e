"""Injury risk curves: P(AIS >= n) from an injury measure.

Every curve is named after its source and returns probabilities in [0, 1].
Coefficients: ``injury-criteria.md`` section 2, with the reference's
confidence labels ([V] verified, [S] secondary sources agree, [U] single or
unconfirmed source, [R] engineering choice, not a published figure).

Two shapes of result:

* single-level curves (name contains ``ais2``, ``ais3`` ...) return an array of
  the shape of the input;
* multi-level curves return an array of shape ``x.shape + (6,)`` holding
  P(AIS >= 1), ..., P(AIS >= 6); levels the source does not publish are NaN.
  Where the published curves of one source cross (P(AIS >= n+1) > P(AIS >= n)
  for some inputs), the result is **forced monotone** by a cumulative minimum
  over n: P(AIS >= n+1) is lowered to P(AIS >= n). The affected curves say so.

Notation: ``logistic(alpha, beta x) = 1 / (1 + exp(alpha - beta x))``; Phi is the
standard normal CDF.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Final

import numpy as np
import numpy.typing as npt
from scipy.special import expit, ndtr

from models.notification import Body

__all__ = [
    "AIS_LEVELS",
    "CHEST_DEFLECTION_NCAP_2008_ALPHA",
    "CHEST_DEFLECTION_NCAP_2008_BETA",
    "CHEST_DEFLECTION_NCAP_2008_EXPONENT",
    "CTI_KLEINBERGER_1998_ALPHA",
    "CTI_KLEINBERGER_1998_BETA",
    "ES2RE_ABDOMEN_NCAP_2008",
    "ES2RE_PELVIS_NCAP_2008",
    "ES2RE_THORAX_NCAP_2008",
    "FEMUR_NCAP_2008",
    "HIC15_NCAP_2008_MU",
    "HIC15_NCAP_2008_SIGMA",
    "HIC_PRASAD_MERTZ_ALPHA",
    "HIC_PRASAD_MERTZ_BETA",
    "KUPPA_ES2RE_THORAX_ALPHA",
    "KUPPA_ES2RE_THORAX_BETA_PER_MM",
    "LAITURI_2005_AGE_COEFFICIENT",
    "LAITURI_2005_INTERCEPT",
    "NCAP_2008_BASELINE_RISK",
    "NECK_AXIAL_NCAP_2008",
    "NIJ_EPPINGER_1999",
    "NIJ_NCAP_2008",
    "SID_IIS_PELVIS_NCAP_2008",
    "VC_RISK_SLOPE_RATIO",
    "VC_TOLERANCE_LAU_VIANO_1986_ABDOMEN",
    "VC_TOLERANCE_LAU_VIANO_1986_CHEST",
    "VC_TOLERANCE_VIANO_1989_ABDOMEN",
    "VC_TOLERANCE_VIANO_1989_CHEST",
    "abdomen_force_ais3_ncap_2008_es2re",
    "abdomen_vc_ais4_viano_1989_lateral",
    "abdomen_vc_ais5_lau_viano_1986",
    "chest_cti_ais3_kleinberger_1998",
    "chest_deflection_ais3_laituri_2005",
    "chest_deflection_ais3_ncap_2008",
    "chest_vc_ais4_lau_viano_1986",
    "chest_vc_ais4_viano_1989_lateral",
    "femur_ais2_ncap_2008",
    "force_monotone",
    "hic15_ais3_ncap_2008",
    "hic_prasad_mertz_1999",
    "hic_prasad_mertz_1999_level",
    "hic_prasad_mertz_1999_levels",
    "ncap_2008_joint_risk",
    "ncap_2008_relative_risk",
    "neck_ais3_ncap_2008",
    "neck_axial_force_ais3_ncap_2008",
    "nij_ais3_ncap_2008",
    "nij_eppinger_1999",
    "nij_eppinger_1999_level",
    "pelvis_force_ais3_ncap_2008_es2re",
    "pelvis_force_ais3_ncap_2008_sid_iis",
    "thorax_rib_deflection_ais3_ncap_2008_es2re",
    "thorax_rib_deflection_kuppa_es2re",
]

#: AIS levels of the multi-level curves, in the order of their last axis.
AIS_LEVELS: Final[tuple[int, ...]] = (1, 2, 3, 4, 5, 6)

# --------------------------------------------------------------------------------------
# Coefficients
# --------------------------------------------------------------------------------------

#: Prasad/Mertz HIC curves (NHTSA 1999 report): P(AIS >= n) =
#: 1 / (1 + exp(alpha_n + 200/HIC - beta_n HIC)), n = 1..6. [S] public MATLAB
#: ``pAIS.m`` (Paez-G. 2020) and a Python AIS mapper; within about 2 points of
#: the "HIC 1000 -> 18 % / 55 % / 90 %" (AIS4+/3+/2+) quoted by Wikipedia.
HIC_PRASAD_MERTZ_ALPHA: Final[tuple[float, ...]] = (1.54, 2.49, 3.39, 4.90, 7.82, 12.24)
#: See :data:`HIC_PRASAD_MERTZ_ALPHA`; 1/HIC units.
HIC_PRASAD_MERTZ_BETA: Final[tuple[float, ...]] = (
    0.0065,
    0.00483,
    0.00372,
    0.00351,
    0.00429,
    0.00565,
)
#: Constant of the 200/HIC term of the Prasad/Mertz curves. [S] same sources.
_PRASAD_MERTZ_HYPERBOLIC: Final[float] = 200.0

#: NCAP 2008 head AIS3+ lognormal: Phi((ln HIC15 - mu) / sigma). [S] three
#: independent public codes (73 FR 40016 not yet checked, reference section 7).
HIC15_NCAP_2008_MU: Final[float] = 7.45231
#: See :data:`HIC15_NCAP_2008_MU`.
HIC15_NCAP_2008_SIGMA: Final[float] = 0.73998

#: Eppinger et al. 1999 Nij curves, level -> (alpha, beta) of
#: logistic(alpha, beta Nij). [S] reference section 2. Not nested (AIS4+ above
#: AIS3+ for Nij < 0.69); see :func:`nij_eppinger_1999`.
NIJ_EPPINGER_1999: Final[dict[int, tuple[float, float]]] = {
    2: (2.054, 1.195),
    3: (3.227, 1.969),
    4: (2.693, 1.195),
    5: (3.817, 1.195),
}
#: NCAP 2008 neck AIS3+ Nij curve (alpha, beta), Hybrid III 50M and 5F. [S]
NIJ_NCAP_2008: Final[tuple[float, float]] = (3.2269, 1.9688)
#: NCAP 2008 neck AIS3+ peak tension/compression curves (alpha, beta per kN). [S]
NECK_AXIAL_NCAP_2008: Final[dict[Body, tuple[float, float]]] = {
    Body.MALE_50TH: (10.9745, 2.375),
    Body.FEMALE_5TH: (10.958, 3.770),
}

#: NCAP 2008 chest AIS3+: logistic(alpha, beta D**0.4612), D in mm. [S]
CHEST_DEFLECTION_NCAP_2008_ALPHA: Final[float] = 10.5456
#: Beta per dummy. 5F: 1.7212 chosen over the 1.721 of one code (more digits,
#: two codes agree) [S].
CHEST_DEFLECTION_NCAP_2008_BETA: Final[dict[Body, float]] = {
    Body.MALE_50TH: 1.568,
    Body.FEMALE_5TH: 1.7212,
}
#: Exponent of deflection in the NCAP 2008 chest curve. [S]
CHEST_DEFLECTION_NCAP_2008_EXPONENT: Final[float] = 0.4612
#: Age-dependent chest curve, P = 1/(1 + exp(-(c0 + c_age Age + beta D**0.4612))):
#: intercept c0 = -12.597. [S/U] public script attributed to Laituri et al. 2005
#: (SAE 2005-01-0297) [U]. At Age 35 it equals the NCAP 2008 curve.
LAITURI_2005_INTERCEPT: Final[float] = -12.597
#: Age coefficient of the age-dependent chest curve, 1/year. [S/U]
LAITURI_2005_AGE_COEFFICIENT: Final[float] = 0.05861

#: CTI AIS3+ curve logistic(8.224, 7.125 CTI). [U] single public MATLAB NCAP
#: script attributed to Kleinberger et al. 1998; check against the report.
CTI_KLEINBERGER_1998_ALPHA: Final[float] = 8.224
#: See :data:`CTI_KLEINBERGER_1998_ALPHA`.
CTI_KLEINBERGER_1998_BETA: Final[float] = 7.125

#: Lau & Viano 1986 (SAE 861882) frontal tolerance: VCmax = 1.0 m/s at 25 %
#: risk of severe thoracic injury (AIS >= 4). [V] abstract.
VC_TOLERANCE_LAU_VIANO_1986_CHEST: Final[float] = 1.0
#: Lau & Viano 1986 frontal tolerance: VCmax = 1.2 m/s at 25 % risk of critical
#: abdominal injury (AIS >= 5). [V] abstract.
VC_TOLERANCE_LAU_VIANO_1986_ABDOMEN: Final[float] = 1.2
#: Viano et al. 1989 (Accid Anal Prev 21:553) lateral tolerance: VC = 1.47 m/s,
#: chest, 25 % risk. [V] abstract.
VC_TOLERANCE_VIANO_1989_CHEST: Final[float] = 1.47
#: Viano et al. 1989 lateral tolerance: VC = 1.98 m/s, abdomen, 25 % risk. [V]
VC_TOLERANCE_VIANO_1989_ABDOMEN: Final[float] = 1.98
#: Shape of the VC risk curves [R]. Only the 25 % points above are published
#: (the abstracts do not give the logistic coefficients), so each VC curve is a
#: logistic in VC through (VC25, 0.25) whose 50 % point is
#: ``VC_RISK_SLOPE_RATIO * VC25``; slope beta = ln 3 / ((ratio - 1) VC25).
#: 1.3 is an engineering choice (frontal chest: 50 % at 1.3 m/s), to be
#: replaced by the published regressions when obtained.
VC_RISK_SLOPE_RATIO: Final[float] = 1.3

#: NCAP 2008 femur / knee-thigh-hip AIS2+ (alpha, beta per kN). [S]
FEMUR_NCAP_2008: Final[dict[Body, tuple[float, float]]] = {
    Body.MALE_50TH: (5.7949, 0.5196),
    Body.FEMALE_5TH: (5.7949, 0.7619),
}

#: NCAP 2008 side, ES-2re thorax: logistic(5.3895, 0.0919 D_rib), mm. [S]
ES2RE_THORAX_NCAP_2008: Final[tuple[float, float]] = (5.3895, 0.0919)
#: NCAP 2008 side, ES-2re abdomen: logistic(6.04044, 0.002133 F), N. [S]
ES2RE_ABDOMEN_NCAP_2008: Final[tuple[float, float]] = (6.04044, 0.002133)
#: NCAP 2008 side, ES-2re pelvis: logistic(7.5969, 0.0011 F), N. [S]
ES2RE_PELVIS_NCAP_2008: Final[tuple[float, float]] = (7.5969, 0.0011)
#: NCAP 2008 side, SID-IIs pelvis (rear seat / pole): logistic(6.3055, 0.00094 F), N. [S]
SID_IIS_PELVIS_NCAP_2008: Final[tuple[float, float]] = (6.3055, 0.00094)
#: Kuppa ES-2re thorax: level -> alpha of logistic(alpha, beta D_rib). [U]
KUPPA_ES2RE_THORAX_ALPHA: Final[dict[int, float]] = {3: 2.0975, 4: 3.4335}
#: Kuppa ES-2re thorax slope, 1/mm, both levels. [U]
KUPPA_ES2RE_THORAX_BETA_PER_MM: Final[float] = 0.0482

#: Baseline risk of the NCAP 2008 relative risk (P_joint / 0.15). [S] public
#: PyTorch NCAP-rating code after the carhs Safety Companion.
NCAP_2008_BASELINE_RISK: Final[float] = 0.15


# --------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------


def _measure(x: npt.ArrayLike, name: str) -> npt.NDArray[np.float64]:
    a = np.asarray(x, dtype=np.float64)
    if np.any(np.isnan(a)):
        raise ValueError(f"`{name}` must not contain NaN.")
    return a


def _logistic(alpha: float, beta: float, x: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """``1 / (1 + exp(alpha - beta x))``, overflow-free."""
    return np.asarray(expit(beta * x - alpha), dtype=np.float64)


def _body(dummy: Body) -> Body:
    try:
        return Body(dummy)
    except ValueError:
        raise ValueError(f"`dummy` must be a Body, got {dummy!r}.") from None


def force_monotone(cumulative: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Force P(AIS >= n) non-increasing in n by a cumulative minimum.

    NaN entries (levels a source does not publish) are skipped and stay NaN.

    Parameters
    ----------
    cumulative : array_like, shape (..., k)
        P(AIS >= n) over increasing n along the last axis.

    Returns
    -------
    ndarray, shape (..., k)
    """
    p = np.array(cumulative, dtype=np.float64)
    filled = np.where(np.isnan(p), np.inf, p)
    out = np.minimum.accumulate(filled, axis=-1)
    return np.where(np.isnan(p), np.nan, out)


# --------------------------------------------------------------------------------------
# Head
# --------------------------------------------------------------------------------------


def hic_prasad_mertz_1999(hic: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Prasad/Mertz head risk curves, P(AIS >= n) for n = 1..6.

    ``P(AIS >= n) = 1 / (1 + exp(alpha_n + 200/HIC - beta_n HIC))`` ([S],
    NHTSA 1999 report, coefficients :data:`HIC_PRASAD_MERTZ_ALPHA` /
    :data:`HIC_PRASAD_MERTZ_BETA`). HIC <= 0 gives 0 at every level (the limit
    of the formula).

    Forced monotone: the published AIS5+ and AIS6 curves are steeper than the
    AIS4+ / AIS5+ curves and cross them above HIC of about 3250 (AIS6 over
    AIS5+) and 3740 (AIS5+ over AIS4+); there the higher level is lowered to the
    lower one (cumulative minimum over n).

    Parameters
    ----------
    hic : array_like, shape (...)
        HIC (HIC15 or HIC36; the curves were fitted to HIC36-era data).

    Returns
    -------
    ndarray, shape (..., 6)
        P(AIS >= 1), ..., P(AIS >= 6).
    """
    h = _measure(hic, "hic")
    levels = hic_prasad_mertz_1999_levels(h, range(1, len(HIC_PRASAD_MERTZ_ALPHA) + 1))
    return force_monotone(np.stack(list(levels.values()), axis=-1))


def hic_prasad_mertz_1999_level(
    hic: npt.NDArray[np.float64], level: int
) -> npt.NDArray[np.float64]:
    """One level of :func:`hic_prasad_mertz_1999` before it is forced monotone.

    The formula itself, for callers that evaluate some levels over many
    values (``models.injury.batch``); the input is not checked.

    Parameters
    ----------
    hic : ndarray, shape (...)
        Finite, non-negative HIC values.
    level : int
        AIS level n, 1..6.

    Returns
    -------
    ndarray, shape (...)
        The published P(AIS >= n) curve.
    """
    return hic_prasad_mertz_1999_levels(hic, (level,))[level]


def hic_prasad_mertz_1999_levels(
    hic: npt.NDArray[np.float64], levels: Iterable[int]
) -> dict[int, npt.NDArray[np.float64]]:
    """Several levels of :func:`hic_prasad_mertz_1999` before it is forced monotone.

    :func:`hic_prasad_mertz_1999_level` of each level, the same numbers; the
    terms that do not depend on the level (which HIC are positive, 200/HIC)
    computed once. The input is not checked.

    Parameters
    ----------
    hic : ndarray, shape (...)
        Finite, non-negative HIC values.
    levels : iterable of int
        AIS levels n, each 1..6.

    Returns
    -------
    dict of int to ndarray, each shape (...)
    """
    positive = hic > 0.0
    safe = np.where(positive, hic, 1.0)
    hyperbolic = _PRASAD_MERTZ_HYPERBOLIC / safe
    out: dict[int, npt.NDArray[np.float64]] = {}
    for level in levels:
        alpha = HIC_PRASAD_MERTZ_ALPHA[level - 1]
        beta = HIC_PRASAD_MERTZ_BETA[level - 1]
        p = np.asarray(expit(beta * safe - alpha - hyperbolic), dtype=np.float64)
        out[level] = np.where(positive, p, 0.0)
    return out


def hic15_ais3_ncap_2008(hic15: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """NCAP 2008 head curve, P(AIS >= 3) = Phi((ln HIC15 - 7.45231) / 0.73998).

    [S] three independent public codes (73 FR 40016). HIC15 <= 0 gives 0.

    Parameters
    ----------
    hic15 : array_like, shape (...)

    Returns
    -------
    ndarray, shape (...)
    """
    h = _measure(hic15, "hic15")
    positive = h > 0.0
    z = (np.log(np.where(positive, h, 1.0)) - HIC15_NCAP_2008_MU) / HIC15_NCAP_2008_SIGMA
    return np.where(positive, ndtr(z), 0.0).astype(np.float64)


# --------------------------------------------------------------------------------------
# Neck
# --------------------------------------------------------------------------------------


def nij_eppinger_1999(nij: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Eppinger et al. 1999 Nij curves, P(AIS >= n) for n = 2..5.

    ``logistic(alpha_n, beta_n Nij)`` with :data:`NIJ_EPPINGER_1999` [S].
    AIS1+ and AIS6 are not published and are NaN.

    Forced monotone: the published AIS4+ curve lies above the AIS3+ curve for
    Nij < 0.69 (6.3 % against 3.8 % at Nij = 0); it is lowered to AIS3+ there
    (cumulative minimum over n, as the reference advises). The curves give a
    non-zero risk at Nij = 0, and SAE 2010-22-0004 reports they over-predict
    neck injury about tenfold against NASS; they are used as published.

    Parameters
    ----------
    nij : array_like, shape (...)

    Returns
    -------
    ndarray, shape (..., 6)
        P(AIS >= 1..6); index 0 and 5 NaN.
    """
    x = _measure(nij, "nij")
    out = np.full(x.shape + (6,), np.nan)
    for level in NIJ_EPPINGER_1999:
        out[..., level - 1] = nij_eppinger_1999_level(x, level)
    return force_monotone(out)


def nij_eppinger_1999_level(nij: npt.NDArray[np.float64], level: int) -> npt.NDArray[np.float64]:
    """One published level of :func:`nij_eppinger_1999` before it is forced monotone.

    For callers that evaluate some levels over many values
    (``models.injury.batch``); the input is not checked.

    Parameters
    ----------
    nij : ndarray, shape (...)
        Finite, non-negative Nij values.
    level : int
        AIS level n, a key of :data:`NIJ_EPPINGER_1999` (2..5).

    Returns
    -------
    ndarray, shape (...)
    """
    alpha, beta = NIJ_EPPINGER_1999[level]
    return _logistic(alpha, beta, nij)


def nij_ais3_ncap_2008(nij: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """NCAP 2008 neck curve, P(AIS >= 3) = logistic(3.2269, 1.9688 Nij). [S]

    Parameters
    ----------
    nij : array_like, shape (...)

    Returns
    -------
    ndarray, shape (...)
    """
    return _logistic(*NIJ_NCAP_2008, _measure(nij, "nij"))


def neck_axial_force_ais3_ncap_2008(
    force_kn: npt.ArrayLike, dummy: Body
) -> npt.NDArray[np.float64]:
    """NCAP 2008 neck curve from peak tension or compression, P(AIS >= 3).

    50M: logistic(10.9745, 2.375 F); 5F: logistic(10.958, 3.770 F), F the
    peak upper-neck tension or compression magnitude in kN. [S]

    Parameters
    ----------
    force_kn : array_like, shape (...)
        Peak axial force magnitude, kN.
    dummy : Body

    Returns
    -------
    ndarray, shape (...)
    """
    alpha, beta = NECK_AXIAL_NCAP_2008[_body(dummy)]
    return _logistic(alpha, beta, np.abs(_measure(force_kn, "force_kn")))


def neck_ais3_ncap_2008(
    nij: npt.ArrayLike,
    tension_kn: npt.ArrayLike,
    compression_kn: npt.ArrayLike,
    dummy: Body,
) -> npt.NDArray[np.float64]:
    """NCAP 2008 neck risk, ``max(P_Nij, P_tension, P_compression)``, AIS3+. [S]

    Parameters
    ----------
    nij : array_like, shape (...)
    tension_kn, compression_kn : array_like, shape (...)
        Peak tension and peak compression magnitudes, kN.
    dummy : Body

    Returns
    -------
    ndarray, shape (...)
    """
    return np.maximum.reduce(
        [
            nij_ais3_ncap_2008(nij),
            neck_axial_force_ais3_ncap_2008(tension_kn, dummy),
            neck_axial_force_ais3_ncap_2008(compression_kn, dummy),
        ]
    )


# --------------------------------------------------------------------------------------
# Chest and abdomen, frontal
# --------------------------------------------------------------------------------------


def chest_deflection_ais3_ncap_2008(
    deflection_mm: npt.ArrayLike, dummy: Body
) -> npt.NDArray[np.float64]:
    """NCAP 2008 chest curve, P(AIS >= 3) = logistic(10.5456, beta D**0.4612).

    beta = 1.568 (50M) or 1.7212 (5F), D the peak chest deflection in mm. [S]
    Negative D is treated as 0.

    Parameters
    ----------
    deflection_mm : array_like, shape (...)
    dummy : Body

    Returns
    -------
    ndarray, shape (...)
    """
    d = np.maximum(_measure(deflection_mm, "deflection_mm"), 0.0)
    beta = CHEST_DEFLECTION_NCAP_2008_BETA[_body(dummy)]
    return _logistic(CHEST_DEFLECTION_NCAP_2008_ALPHA, beta, d**CHEST_DEFLECTION_NCAP_2008_EXPONENT)


def chest_deflection_ais3_laituri_2005(
    deflection_mm: npt.ArrayLike, age_years: npt.ArrayLike, dummy: Body
) -> npt.NDArray[np.float64]:
    """Age-dependent chest curve, P(AIS >= 3).

    ``P = 1 / (1 + exp(-(-12.597 + 0.05861 Age + beta D**0.4612)))`` [S/U],
    from a public script attributed to Laituri et al. 2005 (SAE 2005-01-0297,
    attribution [U]). At Age = 35 it is exactly the NCAP 2008 curve.
    The source gives beta = 1.568 (50M) only; for the 5F the NCAP 2008 5F beta
    1.7212 is used [R], which keeps the identity with the NCAP curve at 35.

    Parameters
    ----------
    deflection_mm : array_like, shape (...)
        Peak chest deflection, mm (negative treated as 0).
    age_years : array_like, shape (...)
        Occupant age, years (broadcast against `deflection_mm`).
    dummy : Body

    Returns
    -------
    ndarray, shape (...)
    """
    d = np.maximum(_measure(deflection_mm, "deflection_mm"), 0.0)
    age = _measure(age_years, "age_years")
    beta = CHEST_DEFLECTION_NCAP_2008_BETA[_body(dummy)]
    logit = (
        LAITURI_2005_INTERCEPT
        + LAITURI_2005_AGE_COEFFICIENT * age
        + beta * d**CHEST_DEFLECTION_NCAP_2008_EXPONENT
    )
    return np.asarray(expit(logit), dtype=np.float64)


def chest_cti_ais3_kleinberger_1998(cti: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """CTI curve, P(AIS >= 3) = logistic(8.224, 7.125 CTI).

    [U] single public MATLAB script attributed to Kleinberger et al. 1998
    (NHTSA); chosen because it is the only CTI curve in the reference. Used for
    the 5F as well (no 5F curve found) with the 5F intercepts of
    :data:`models.injury.criteria.CTI_INTERCEPTS`.

    Parameters
    ----------
    cti : array_like, shape (...)

    Returns
    -------
    ndarray, shape (...)
    """
    return _logistic(CTI_KLEINBERGER_1998_ALPHA, CTI_KLEINBERGER_1998_BETA, _measure(cti, "cti"))


def _vc_curve(vc: npt.ArrayLike, vc25: float) -> npt.NDArray[np.float64]:
    """Logistic through (vc25, 0.25) with 50 % at VC_RISK_SLOPE_RATIO * vc25 [R]."""
    x = np.maximum(_measure(vc, "vc_m_s"), 0.0)
    vc50 = VC_RISK_SLOPE_RATIO * vc25
    beta = math.log(3.0) / (vc50 - vc25)
    return _logistic(beta * vc50, beta, x)


def chest_vc_ais4_lau_viano_1986(vc_m_s: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Frontal chest VC curve, P(AIS >= 4), through Lau & Viano's 25 % at 1.0 m/s.

    The 25 % point is published ([V] SAE 861882 abstract); the slope is not in
    the sources at hand, so the curve is a logistic with its 50 % point at
    1.3 m/s ([R], :data:`VC_RISK_SLOPE_RATIO`). Negative VC is treated as 0.

    Parameters
    ----------
    vc_m_s : array_like, shape (...)
        VCmax, m/s.

    Returns
    -------
    ndarray, shape (...)
    """
    return _vc_curve(vc_m_s, VC_TOLERANCE_LAU_VIANO_1986_CHEST)


def abdomen_vc_ais5_lau_viano_1986(vc_m_s: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Frontal abdomen VC curve, P(AIS >= 5), through 25 % at 1.2 m/s.

    25 % point [V] SAE 861882 abstract ("critical abdominal injury (AIS >= 5)");
    logistic shape with 50 % at 1.56 m/s [R] (:data:`VC_RISK_SLOPE_RATIO`).

    Parameters
    ----------
    vc_m_s : array_like, shape (...)
        Abdominal VCmax, m/s.

    Returns
    -------
    ndarray, shape (...)
    """
    return _vc_curve(vc_m_s, VC_TOLERANCE_LAU_VIANO_1986_ABDOMEN)


def chest_vc_ais4_viano_1989_lateral(vc_m_s: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Lateral chest VC curve, P(AIS >= 4), through 25 % at 1.47 m/s.

    25 % point [V] Viano et al. 1989, Accid Anal Prev 21:553 abstract. The
    injury level is uncertain [U]: the journal abstract says "critical injury"
    (AIS 5 in AIS wording), the ESV 1989 version of the same study "serious
    injury" (AIS 3), and the injuries were mostly rib fractures. AIS >= 4 is
    chosen, between the two readings and the level Lau & Viano use for the
    chest. Logistic shape [R] (:data:`VC_RISK_SLOPE_RATIO`).

    Parameters
    ----------
    vc_m_s : array_like, shape (...)

    Returns
    -------
    ndarray, shape (...)
    """
    return _vc_curve(vc_m_s, VC_TOLERANCE_VIANO_1989_CHEST)


def abdomen_vc_ais4_viano_1989_lateral(vc_m_s: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Lateral abdomen VC curve, P(AIS >= 4), through 25 % at 1.98 m/s.

    Same source, level choice [U] and shape [R] as
    :func:`chest_vc_ais4_viano_1989_lateral`.

    Parameters
    ----------
    vc_m_s : array_like, shape (...)

    Returns
    -------
    ndarray, shape (...)
    """
    return _vc_curve(vc_m_s, VC_TOLERANCE_VIANO_1989_ABDOMEN)


def femur_ais2_ncap_2008(force_kn: npt.ArrayLike, dummy: Body) -> npt.NDArray[np.float64]:
    """NCAP 2008 knee-thigh-hip curve, P(AIS >= 2), peak femur force F in kN.

    50M logistic(5.7949, 0.5196 F); 5F logistic(5.7949, 0.7619 F). [S]

    Parameters
    ----------
    force_kn : array_like, shape (...)
        Peak axial femur force magnitude, kN.
    dummy : Body

    Returns
    -------
    ndarray, shape (...)
    """
    alpha, beta = FEMUR_NCAP_2008[_body(dummy)]
    return _logistic(alpha, beta, np.abs(_measure(force_kn, "force_kn")))


def ncap_2008_joint_risk(
    p_head: npt.ArrayLike, p_neck: npt.ArrayLike, p_chest: npt.ArrayLike, p_femur: npt.ArrayLike
) -> npt.NDArray[np.float64]:
    """NCAP 2008 combined risk ``1 - (1-Ph)(1-Pn)(1-Pc)(1-Pf)``. [S]

    Parameters
    ----------
    p_head, p_neck, p_chest, p_femur : array_like, shape (...)
        Regional risks (head and neck AIS3+, chest AIS3+, femur AIS2+).

    Returns
    -------
    ndarray, shape (...)
    """
    q = (
        (1.0 - np.asarray(p_head, dtype=np.float64))
        * (1.0 - np.asarray(p_neck, dtype=np.float64))
        * (1.0 - np.asarray(p_chest, dtype=np.float64))
        * (1.0 - np.asarray(p_femur, dtype=np.float64))
    )
    return 1.0 - q


def ncap_2008_relative_risk(p_joint: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """NCAP 2008 relative risk ``P_joint / 0.15``. [S]"""
    return np.asarray(p_joint, dtype=np.float64) / NCAP_2008_BASELINE_RISK


# --------------------------------------------------------------------------------------
# Side
# --------------------------------------------------------------------------------------


def thorax_rib_deflection_ais3_ncap_2008_es2re(
    rib_deflection_mm: npt.ArrayLike,
) -> npt.NDArray[np.float64]:
    """NCAP 2008 side, ES-2re thorax, P(AIS >= 3) = logistic(5.3895, 0.0919 D).

    D the peak rib deflection, mm. [S] (a PyTorch NCAP code and ``pAIS.m``
    agree). The injury level is AIS3+ as in the NCAP 2008 side rating [S].
    Negative D is treated as 0.

    Parameters
    ----------
    rib_deflection_mm : array_like, shape (...)

    Returns
    -------
    ndarray, shape (...)
    """
    d = np.maximum(_measure(rib_deflection_mm, "rib_deflection_mm"), 0.0)
    return _logistic(*ES2RE_THORAX_NCAP_2008, d)


def abdomen_force_ais3_ncap_2008_es2re(force_n: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """NCAP 2008 side, ES-2re abdomen, logistic(6.04044, 0.002133 F), F in N.

    [S] coefficients; the AIS level (3+) is as the NCAP 2008 side rating is
    usually described [U].
    """
    return _logistic(*ES2RE_ABDOMEN_NCAP_2008, np.abs(_measure(force_n, "force_n")))


def pelvis_force_ais3_ncap_2008_es2re(force_n: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """NCAP 2008 side, ES-2re pelvis, logistic(7.5969, 0.0011 F), F in N.

    [S] coefficients; AIS level 3+ [U].
    """
    return _logistic(*ES2RE_PELVIS_NCAP_2008, np.abs(_measure(force_n, "force_n")))


def pelvis_force_ais3_ncap_2008_sid_iis(force_n: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """NCAP 2008 side, SID-IIs pelvis, logistic(6.3055, 0.00094 F), F in N.

    [S] coefficients; AIS level 3+ [U].
    """
    return _logistic(*SID_IIS_PELVIS_NCAP_2008, np.abs(_measure(force_n, "force_n")))


def thorax_rib_deflection_kuppa_es2re(
    rib_deflection_mm: npt.ArrayLike,
) -> npt.NDArray[np.float64]:
    """Kuppa ES-2re thorax curves, P(AIS >= 3) and P(AIS >= 4).

    ``logistic(alpha_n, 0.0482 D)``, alpha = 2.0975 (AIS3+), 3.4335 (AIS4+),
    D in mm. [U] single source; not used by :func:`models.injury.assess`, which
    uses the NCAP 2008 [S] curve for the side thorax.

    Parameters
    ----------
    rib_deflection_mm : array_like, shape (...)

    Returns
    -------
    ndarray, shape (..., 6)
        P(AIS >= 1..6); only indices 2 and 3 are set, the rest NaN.
    """
    d = np.maximum(_measure(rib_deflection_mm, "rib_deflection_mm"), 0.0)
    out = np.full(d.shape + (6,), np.nan)
    for level, alpha in KUPPA_ES2RE_THORAX_ALPHA.items():
        out[..., level - 1] = _logistic(alpha, KUPPA_ES2RE_THORAX_BETA_PER_MM, d)
    return force_monotone(out)
