"""The published limit or tolerance of each injury measure, with its source.

What a measure is compared with where it is shown: the FMVSS 208 limits for HIC15,
Nij, chest deflection and 3 ms chest acceleration (``models.injury.criteria``), and
the viscous-criterion tolerances of Lau & Viano 1986 (frontal) and Viano et al. 1989
(lateral) (``models.injury.risk``). Plain data in, a frozen dataclass out.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

from models.impact_mode import ImpactMode
from models.injury.criteria import (
    FMVSS208_CHEST_A3MS_LIMIT_G,
    FMVSS208_CHEST_DEFLECTION_LIMIT_MM,
    FMVSS208_HIC15_LIMIT,
    FMVSS208_NIJ_LIMIT,
)
from models.injury.risk import (
    VC_TOLERANCE_LAU_VIANO_1986_ABDOMEN,
    VC_TOLERANCE_LAU_VIANO_1986_CHEST,
    VC_TOLERANCE_VIANO_1989_ABDOMEN,
    VC_TOLERANCE_VIANO_1989_CHEST,
)
from models.notification import Body

__all__ = ["SIDE_MODES", "InjuryLimit", "injury_limit"]


@dataclass(frozen=True, slots=True)
class InjuryLimit:
    """A published limit or tolerance of an injury measure.

    Attributes
    ----------
    value : float
        The limit, in the measure's own unit (HIC15 and Nij: none; deflection: mm;
        viscous criterion: m/s; 3 ms acceleration: g).
    source : str
        Where it is published.
    """

    value: float
    source: str


#: The side impact modes: the occupant models measure rib deflection there, whose
#: limits the engine does not hold, and the lateral VC tolerance applies.
SIDE_MODES: Final[frozenset[ImpactMode]] = frozenset({ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE})

_VC_FRONTAL_CHEST = "Lau & Viano 1986 frontal tolerance (25 % risk of AIS 4+)"
_VC_FRONTAL_ABDOMEN = "Lau & Viano 1986 frontal tolerance (25 % risk of AIS 5+)"
_VC_SIDE = "Viano et al. 1989 lateral tolerance (25 % risk)"


def injury_limit(measure: str, impact_mode: ImpactMode, body: Body) -> InjuryLimit | None:
    """The engine's published limit for a measure, or None where it has none.

    Parameters
    ----------
    measure : str
        The measure's key in an occupant's measures (``hic15``, ``nij``,
        ``chest_deflection_mm``, ``chest_a3ms_g``, ``chest_vc_m_s``,
        ``abdomen_vc_m_s``, ``chest_cti``).
    impact_mode : ImpactMode
        The occupant's impact mode.
    body : Body
        The dummy class the engine used.

    Returns
    -------
    InjuryLimit or None
        HIC15 and Nij: the FMVSS 208 limits. Chest deflection and 3 ms chest
        acceleration: the FMVSS 208 Hybrid III limits, in frontal and rear modes only
        (:data:`SIDE_MODES` measure rib deflection). VC: the Lau & Viano frontal and
        Viano lateral tolerances. CTI and any other measure: None.
    """
    side = impact_mode in SIDE_MODES
    if measure == "hic15":
        return InjuryLimit(FMVSS208_HIC15_LIMIT, "FMVSS 208 (49 CFR 571.208 S6.2)")
    if measure == "nij":
        return InjuryLimit(FMVSS208_NIJ_LIMIT, "FMVSS 208 (49 CFR 571.208 S6.6)")
    if measure == "chest_deflection_mm" and not side:
        limit_mm = FMVSS208_CHEST_DEFLECTION_LIMIT_MM.get(body)
        return None if limit_mm is None else InjuryLimit(limit_mm, "FMVSS 208 Hybrid III")
    if measure == "chest_a3ms_g" and not side:
        return InjuryLimit(FMVSS208_CHEST_A3MS_LIMIT_G, "FMVSS 208 (3 ms clip)")
    if measure == "chest_vc_m_s":
        if side:
            return InjuryLimit(VC_TOLERANCE_VIANO_1989_CHEST, _VC_SIDE)
        return InjuryLimit(VC_TOLERANCE_LAU_VIANO_1986_CHEST, _VC_FRONTAL_CHEST)
    if measure == "abdomen_vc_m_s":
        if side:
            return InjuryLimit(VC_TOLERANCE_VIANO_1989_ABDOMEN, _VC_SIDE)
        return InjuryLimit(VC_TOLERANCE_LAU_VIANO_1986_ABDOMEN, _VC_FRONTAL_ABDOMEN)
    return None
