"""The scalar injury measures of one occupant (the input of the injury assessment)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["InjuryMeasures"]


@dataclass(frozen=True)
class InjuryMeasures:
    """Scalar injury measures of one occupant; None where not available.

    Attributes
    ----------
    hic15 : float or None
        HIC15, dimensionless.
    nij : float or None
        Peak Nij, dimensionless.
    chest_deflection_mm : float or None
        Peak chest (frontal) or rib (side) deflection, mm.
    chest_vc_m_s : float or None
        Chest VCmax, m/s.
    chest_a3ms_g : float or None
        3 ms clip chest acceleration, g.
    chest_cti : float or None
        Combined thoracic index, dimensionless.
    abdomen_vc_m_s : float or None
        Abdominal VCmax, m/s.
    """

    hic15: float | None = None
    nij: float | None = None
    chest_deflection_mm: float | None = None
    chest_vc_m_s: float | None = None
    chest_a3ms_g: float | None = None
    chest_cti: float | None = None
    abdomen_vc_m_s: float | None = None
