"""Occupant inputs of the field risk model's tests: a belted adult front passenger, varied."""

from __future__ import annotations

from models.field.risk_children import ChildRiskInputs, Restraint
from models.field.risk_features import AirbagCode, SeatSide


def occupant_inputs(**kw: object) -> ChildRiskInputs:
    """A belted 42-year-old man in the front right seat, 45 km/h frontal; `kw` overrides."""
    base: dict[str, object] = {
        "delta_v_kmh": 45.0,
        "pdof_deg": 0.0,
        "seat_row": 1,
        "seat_side": SeatSide.RIGHT,
        "driver": False,
        "belted": True,
        "frontal_airbag": AirbagCode.DEPLOYED,
        "rollover": False,
        "multiple_impacts": False,
        "restraint": Restraint.BELTED,
        "age_years": 42.0,
        "female": False,
        "stature_cm": 178.0,
        "mass_kg": 80.0,
        "model_year": 2010,
    }
    base.update(kw)
    return ChildRiskInputs(**base)  # type: ignore[arg-type]
