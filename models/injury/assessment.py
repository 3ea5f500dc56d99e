"""From injury measures to regional AIS distributions, ISS and P(ISS >= 15).

:func:`assess` maps each measure to P(AIS >= n) with the risk curves of
:mod:`models.injury.risk`, combines the measures of one ISS region, and turns
the result into a full distribution P(AIS = 0..6) per region, one AIS level per
region, the ISS of those levels, and the exact P(ISS >= 15) over the
distributions.

Curves used (``injury-criteria.md`` sections 2-3; measure -> ISS region):

============================  ===========  =======================================
measure                       region       curve (levels)
============================  ===========  =======================================
``hic15``                     head_neck    Prasad/Mertz 1999 (AIS 1-6), every mode
``nij``                       head_neck    Eppinger 1999 (AIS 2-5), every mode
``chest_deflection_mm``       chest        frontal/rear: NCAP 2008 (AIS 3), or the
                                           age-dependent Laituri 2005 form when
                                           `age_years` is given; side: NCAP 2008
                                           ES-2re thorax (AIS 3)
``chest_vc_m_s``              chest        frontal/rear: Lau & Viano 1986 (AIS 4);
                                           side: Viano 1989 lateral (AIS 4)
``chest_cti``                 chest        Kleinberger 1998 (AIS 3), every mode
``chest_a3ms_g``              chest        no curve of its own; enters through CTI
``abdomen_vc_m_s``            abdomen      frontal/rear: Lau & Viano 1986 (AIS 5);
                                           side: Viano 1989 lateral (AIS 4)
============================  ===========  =======================================

Rules, all documented choices:

* **Missing measures.** A measure that is None contributes no injury evidence.
  A region with no measure (always: face, extremities, external) is AIS 0
  with probability 1. If ``chest_cti`` is None but both ``chest_a3ms_g`` and
  ``chest_deflection_mm`` are given, CTI is computed from them
  (:func:`models.injury.criteria.cti`).
* **Combining measures of one region.** For each level n, P(AIS >= n) of the
  region is the largest P(AIS >= n) among its measures (the most pessimistic
  measure, as NCAP combines its neck measures by a maximum; HIC and Nij share
  the head/neck region and are combined by the maximum, not added).
* **Levels a curve does not publish.** A level below a published level gets
  the next published higher level's probability (a lower bound: AIS >= 2
  implies AIS >= 1); levels above the highest published level of every curve of
  the region get 0. So a region informed only by AIS3+ curves (the chest in
  practice) reaches at most AIS 3: the distributions are lower bounds on
  severity where no higher-level curve is published.
* **Rear impact** uses the frontal curves (no rear curves are published).
  **Near and far side** use the side curves where published (side thorax from
  rib deflection, lateral VC) and the frontal ones otherwise (head, neck,
  CTI). The ES-2re thorax curve is applied to both bodies (the SID-IIs thorax
  curve is not in the reference) [R].
* **One AIS level per region**: the median of its distribution, the highest n
  with P(AIS >= n) >= 0.5 (:data:`models.injury.scores.AIS_LEVEL_THRESHOLD`).
* **P(ISS >= 15)**: exact, regions independent
  (:func:`models.injury.scores.p_iss_at_least`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
import numpy.typing as npt

from models.impact_mode import ImpactMode
from models.injury.batch_compiled import region_blocks_compiled
from models.injury.measures import InjuryMeasures
from models.injury.scores import (
    _NO_RISK,
    AIS_LEVEL_THRESHOLD,
    ISS_REGIONS,
    ISS_TRIAGE_THRESHOLD,
    MAX_AIS,
    _ais_level,
    _distribution_from_cumulative,
    _iss_distribution,
    _p_iss_at_least,
    iss,
)
from models.notification import Body

__all__ = [
    "ISS_TRIAGE_THRESHOLD",
    "InjuryAssessment",
    "InjuryMeasures",
    "assess",
    "region_cumulative_risk",
]


@dataclass(frozen=True)
class InjuryAssessment:
    """Regional AIS distributions and the scores derived from them.

    Attributes
    ----------
    region_ais_probability : dict of str to tuple of float, each length 7
        P(AIS = 0..6) per ISS region (all six regions); each sums to 1.
    region_ais : dict of str to int
        One level per region: the median of its distribution.
    iss : int
        Baker ISS of `region_ais`.
    p_iss15 : float
        Exact P(ISS >= 15) over the regional distributions, regions independent.
    """

    region_ais_probability: dict[str, tuple[float, ...]]
    region_ais: dict[str, int]
    iss: int
    p_iss15: float


def _value(measures: InjuryMeasures, name: str) -> float | None:
    v = getattr(measures, name)
    if v is None:
        return None
    x = float(v)
    if not (math.isfinite(x) and x >= 0.0):
        raise ValueError(f"`measures.{name}` must be a finite non-negative number, got {v!r}.")
    return x


def region_cumulative_risk(
    measures: InjuryMeasures,
    body: Body,
    age_years: float | None = None,
    impact_mode: str = "frontal",
) -> dict[str, npt.NDArray[np.float64]]:
    """P(AIS >= 1..6) per ISS region, before conversion to distributions.

    Parameters are those of :func:`assess`.

    Returns
    -------
    dict of str to ndarray, each shape (6,)
        Non-increasing P(AIS >= n), n = 1..6, for every region of
        :data:`models.injury.scores.ISS_REGIONS`.
    """
    try:
        body = Body(body)
    except ValueError:
        raise ValueError(f"`body` must be a Body, got {body!r}.") from None
    try:
        mode = ImpactMode(impact_mode)
    except ValueError:
        raise ValueError(
            f"`impact_mode` must be one of {[m.value for m in ImpactMode]}, got {impact_mode!r}."
        ) from None
    age: float | None = None
    if age_years is not None:
        age = float(age_years)
        if not (math.isfinite(age) and age >= 0.0):
            raise ValueError(
                f"`age_years` must be a finite non-negative number, got {age_years!r}."
            )
    present = {
        f.name: np.array([v])
        for f in fields(InjuryMeasures)
        if (v := _value(measures, f.name)) is not None
    }
    if not present:  # no evidence: no risk in any region
        return {region: np.zeros(MAX_AIS) for region in ISS_REGIONS}
    # one curve selection and combination for the scalar and the batch paths
    blocks = region_blocks_compiled(present, 1, body, age, mode)  # checked by _value
    return {region: np.ascontiguousarray(b[:, 0]) for region, b in blocks.items()}


def assess(
    measures: InjuryMeasures,
    body: Body,
    age_years: float | None = None,
    impact_mode: str = "frontal",
) -> InjuryAssessment:
    """Regional AIS distributions, AIS levels, ISS and P(ISS >= 15).

    See the module docstring for the curves and the rules (missing measures,
    combination within a region, unpublished levels, side curves, the level
    rule).

    Parameters
    ----------
    measures : InjuryMeasures
        Scalar measures; None fields give no evidence.
    body : Body
        Hybrid III 50th male or 5th female (dummy-specific curves).
    age_years : float, optional
        Occupant age, years; selects the age-dependent chest deflection curve
        (frontal and rear). None uses the NCAP 2008 curve (= age 35).
    impact_mode : {"frontal", "rear", "near_side", "far_side"}, optional
        Selects side curves for the near and far side modes.

    Returns
    -------
    InjuryAssessment

    Raises
    ------
    ValueError
        For an unknown body or impact mode, a negative or non-finite measure or
        age.

    Examples
    --------
    >>> a = assess(InjuryMeasures(), Body.MALE_50TH)
    >>> a.iss, a.p_iss15
    (0, 0.0)
    """
    cumulative = region_cumulative_risk(measures, body, age_years, impact_mode)
    # the curves' combination is non-increasing in the level and within [0, 1]
    # (region_cumulative_risk_batch), so the checks of the public score functions
    # are skipped here: the same arithmetic, a third of the time
    probability = {r: _distribution_from_cumulative(c) for r, c in cumulative.items()}
    levels = {
        r: 0 if p == _NO_RISK else _ais_level(np.asarray(p), AIS_LEVEL_THRESHOLD)
        for r, p in probability.items()
    }
    return InjuryAssessment(
        region_ais_probability=probability,
        region_ais=levels,
        iss=iss(levels),
        p_iss15=_p_iss_at_least(_iss_distribution(probability), float(ISS_TRIAGE_THRESHOLD)),
    )
