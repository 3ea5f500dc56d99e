"""The body map's two layers: field region risk (default) and the occupant model's region AIS.

The first layer colours each AIS 1990 body region by the occupant's
field-calibrated probability of an injury of AIS 3+ there (AIS 2+ where the
answer says so: face, neck), ``occupants[].region_risk.<region> =
{probability, probability_ci95, ais_level}``, with its 95 % interval on hover
(an SVG ``<title>``) and in the table beside it. A stored answer without
``region_risk`` (decided before the field region models) shows the first layer
as unavailable and says so.

The second layer is the occupant model's region AIS per ISS region, as before,
labelled "occupant model" and stated with its measured skill on real crashes
(``models/injury/data/occupant_model_field_skill.json``, written by
``python -m models.offline.regions.report``). An AIS 6 from a model (stored
before the engine capped it at AIS 5) is shown with how often the field
agreed.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any, Final

from service.pages.drawing import RegionShape, Shape

__all__ = [
    "RISK_BANDS",
    "RISK_REGION_SHAPES",
    "PhysicsSkill",
    "RiskRegionView",
    "physics_skill",
    "risk_regions",
]

#: Field region-risk regions in drawing order, with their labels.
RISK_REGION_LABELS: Final[dict[str, str]] = {
    "upper_extremity": "Upper extremities",
    "lower_extremity": "Lower extremities",
    "thorax": "Thorax",
    "abdomen": "Abdomen",
    "spine": "Spine",
    "neck": "Neck",
    "head": "Head",
    "face": "Face",
}

#: Colour bands of a region's probability: (lower bound, css class, words). [R]
#: Spaced about a factor of three apart from the 1 % a region's AIS 3+ risk
#: rarely exceeds in an average towaway crash (NASS-CDS weighted rates 0.2-1.2 %,
#: docs/occupant-models.md) up to the 30 % of the most severe crashes.
RISK_BANDS: Final[tuple[tuple[float, str, str], ...]] = (
    (0.0, "risk-0", "under 1 %"),
    (0.01, "risk-1", "1-3 %"),
    (0.03, "risk-2", "3-10 %"),
    (0.10, "risk-3", "10-30 %"),
    (0.30, "risk-4", "30 % or more"),
)


def _rect(x: int, y: int, w: int, h: int, rx: int = 0) -> Shape:
    attrs = (("x", str(x)), ("y", str(y)), ("width", str(w)), ("height", str(h)))
    return ("rect", attrs + ((("rx", str(rx)),) if rx else ()))


#: Front-view map of the AIS regions, viewBox 200 x 340 (the same frame as the
#: occupant-model map); the spine is the strip down the midline of the trunk.
RISK_REGION_SHAPES: Final[tuple[RegionShape, ...]] = (
    RegionShape(
        "upper_extremity", (_rect(34, 82, 20, 122, 9), _rect(146, 82, 20, 122, 9)), 44.0, 150.0
    ),
    RegionShape(
        "lower_extremity", (_rect(70, 208, 27, 124, 10), _rect(103, 208, 27, 124, 10)), 83.5, 274.0
    ),
    RegionShape("thorax", (_rect(58, 78, 84, 70, 12),), 78.0, 118.0),
    RegionShape("abdomen", (_rect(62, 150, 76, 56, 10),), 80.0, 183.0),
    RegionShape("spine", (_rect(95, 80, 10, 124, 4),), 100.0, 216.0),
    RegionShape("neck", (_rect(89, 58, 22, 20),), 122.0, 72.0),
    RegionShape("head", (("circle", (("cx", "100"), ("cy", "34"), ("r", "27"))),), 100.0, 16.0),
    RegionShape(
        "face",
        (("ellipse", (("cx", "100"), ("cy", "39"), ("rx", "13"), ("ry", "15"))),),
        100.0,
        44.0,
    ),
)


def _num(x: Any) -> float | None:
    if isinstance(x, bool) or not isinstance(x, int | float):
        return None
    v = float(x)
    return v if math.isfinite(v) else None


def _pct(p: float) -> str:
    return f"{100 * p:.1f} %" if p >= 0.001 else "under 0.1 %"


@dataclass(frozen=True)
class RiskRegionView:
    """One region of the field region-risk layer."""

    key: str
    label: str
    probability: float
    low: float
    high: float
    ais_level: int
    band: str
    band_words: str

    @property
    def probability_text(self) -> str:
        return _pct(self.probability)

    @property
    def interval_text(self) -> str:
        return f"{_pct(self.low)} to {_pct(self.high)}"

    @property
    def title(self) -> str:
        """The hover text: region, outcome, probability and interval."""
        return (
            f"{self.label}: P(AIS {self.ais_level}+) {self.probability_text} "
            f"(95 % interval {self.interval_text})"
        )


def _band(p: float) -> tuple[str, str]:
    css, words = RISK_BANDS[0][1], RISK_BANDS[0][2]
    for lower, c, w in RISK_BANDS:
        if p >= lower:
            css, words = c, w
    return css, words


def risk_regions(occ: Mapping[str, Any]) -> tuple[RiskRegionView, ...]:
    """The occupant's field region risks, in :data:`RISK_REGION_LABELS` order; () when absent."""
    given = occ.get("region_risk")
    if not isinstance(given, Mapping):
        return ()
    out = []
    for key, label in RISK_REGION_LABELS.items():
        item = given.get(key)
        if not isinstance(item, Mapping):
            continue
        p = _num(item.get("probability"))
        ci = item.get("probability_ci95")
        if p is None or not isinstance(ci, Sequence) or len(ci) != 2:
            continue
        lo, hi = _num(ci[0]), _num(ci[1])
        if lo is None or hi is None:
            continue
        level = item.get("ais_level")
        css, words = _band(p)
        out.append(
            RiskRegionView(
                key=key,
                label=label,
                probability=p,
                low=lo,
                high=hi,
                ais_level=level if isinstance(level, int) and not isinstance(level, bool) else 3,
                band=css,
                band_words=words,
            )
        )
    return tuple(out)


#: Where the report writes the occupant models' measured skill.
SKILL_PATH: Final[Path] = (
    Path(__file__).resolve().parents[2]
    / "models"
    / "injury"
    / "data"
    / "occupant_model_field_skill.json"
)


@dataclass(frozen=True)
class PhysicsSkill:
    """What the page says of the occupant model's body map, from the shipped skill file."""

    text: str
    ais6_text: str


@lru_cache(maxsize=1)
def _skill_document() -> dict[str, Any] | None:
    try:
        doc = json.loads(SKILL_PATH.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return doc if isinstance(doc, dict) else None


def physics_skill() -> PhysicsSkill:
    """The measured skill of the occupant-model layer, in words."""
    doc = _skill_document()
    if doc is None:
        return PhysicsSkill(
            text="Its skill on real crashes has not been measured for this build.",
            ais6_text="An AIS 6 from the occupant model has not been checked against real crashes.",
        )
    aucs = doc.get("auc_weighted", {})
    parts = [
        f"{name} {r['auc_body_map']:.2f} (delta-V alone {r['auc_delta_v']:.2f})"
        for name, r in aucs.items()
        if isinstance(r, Mapping)
    ]
    six = doc.get("curves_ais6", {})
    text = (
        f"Measured on {int(doc.get('occupants', 0)):,} real occupants (NASS-CDS 1997-2014), "
        "this map ranks who really had an AIS 3+ injury in a region with an AUC of "
        + "; ".join(parts)
        + ": it explains the physics, it does not locate injuries better than the crash "
        "severity does. Its levels are never above AIS 5."
    )
    ais6 = (
        "AIS 6 here comes from the occupant model's risk curves (a case stored before they "
        "were capped at AIS 5). Of real occupants the curves put at AIS 6, "
        f"{100 * six['real_mais5']:.0f} % had any AIS 5+ injury and "
        f"{100 * six['died']:.0f} % died (median ISS {six['median_iss']:.0f})."
        if isinstance(six, Mapping) and "real_mais5" in six
        else "An AIS 6 from the occupant model has not been checked against real crashes."
    )
    return PhysicsSkill(text=text, ais6_text=ais6)
