"""What a VEDS case's own document adds to its NEMSIS record.

NEMSIS's ACN block is VEDS's, so a VEDS document carries more than the
notification it was triaged as: every crash pulse (the triage took the largest;
NEMSIS repeats eInjury.22 with an ordinal for each) and the seats reported empty
(a seat group with eInjury.27 "N"). The stored document is read again with the
service's safe reader (``service.cases.veds_xml``); it was accepted once, but a
document that cannot be read now adds nothing rather than failing the record.
"""

from __future__ import annotations

from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from typing import Final
from xml.etree.ElementTree import Element

from service.cases.veds import delta_v_to_kmh
from service.cases.veds_xml import NC_NAMESPACE, VEDS_NAMESPACES, is_xsd_decimal, parse_xml
from service.problems import DomainError

__all__ = ["VedsFacts", "veds_facts"]

#: VEDS delta-V units read (``nc:MeasureUnitText``), as the VEDS mapping reads them.
_UNITS: Final = frozenset({"KPH", "MPH"})


@dataclass(frozen=True)
class VedsFacts:
    """Facts of a VEDS document beyond its notification.

    Attributes
    ----------
    delta_v_kmh : tuple of float
        Each crash pulse's delta-V magnitude, km/h, in document order.
    empty_seats : tuple of str
        VEDS seat location codes reported not occupied, in document order.
    """

    delta_v_kmh: tuple[float, ...]
    empty_seats: tuple[str, ...]


def _text(parent: Element, tag: str) -> str | None:
    found = parent.find(tag)
    return found.text.strip() if found is not None and found.text else None


def veds_facts(document: str) -> VedsFacts | None:
    """The pulses and empty seats of a stored VEDS document; None when it cannot be read."""
    try:
        root = parse_xml(document.encode("utf-8"))
    except DomainError:
        return None
    ns = root.tag[1:].partition("}")[0] if root.tag.startswith("{") else ""
    if ns not in VEDS_NAMESPACES:
        return None
    veds, nc = f"{{{ns}}}", f"{{{NC_NAMESPACE}}}"
    vehicle = root.find(f"{veds}Crash/{veds}CrashVehicle")
    if vehicle is None:
        return None
    pulses: list[float] = []
    for pulse in vehicle.findall(f"{veds}VehicleCrashPulse"):
        measure = pulse.find(f"{veds}CrashPulseChangeInVelocityMeasure")
        if measure is None:
            return None
        value = _text(measure, f"{nc}MeasurePointValue")
        unit = (_text(measure, f"{nc}MeasureUnitText") or "").upper()
        if value is None or not is_xsd_decimal(value) or unit not in _UNITS:
            return None  # Decimal() would also take another script's digits
        try:
            pulses.append(delta_v_to_kmh(Decimal(value), unit))
        except InvalidOperation:
            return None
    empty = tuple(
        code
        for seat in vehicle.findall(f"{veds}VehicleSeat")
        if (code := _text(seat, f"{veds}VehicleSeatLocationCategoryCode")) is not None
        and (_text(seat, f"{veds}VehicleSeatOccupiedIndicator") or "").lower() in ("false", "0")
    )
    return VedsFacts(delta_v_kmh=tuple(pulses), empty_seats=empty)
