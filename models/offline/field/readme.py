"""The README's figures of the decision, written from the field model artifact (never by hand).

``aacn-triage fit-field`` rewrites the block between :data:`BEGIN` and
:data:`END` in ``README.md`` (:func:`update_readme`): the held-out table, the
temporal check, the default and ACS-COT operating points' held-out figures, the
vehicle answer, the extrapolation limit, the answer to the README's own
example notification and one example of each risk tier (a notification chosen to
land in it, with its answer). ``tests/models/field/test_readme_figures.py`` holds the
README to what :func:`readme_block` renders from the shipped artifact, so the
two cannot drift apart.
"""

from __future__ import annotations

import json
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Final

from models.lpm.params import DEFAULT_SET
from models.notification import (
    AirbagState,
    Body,
    CrashNotification,
    DriveSide,
    Occupant,
    Seat,
    SeatTrackSource,
    Sex,
    SummaryPulse,
    nearest_body,
)
from models.offline.field.risk_report_knowledge import (
    readme_knowledge_lines,
    readme_measured_lines,
)
from models.triage import load_engine_models, triage

__all__ = [
    "BEGIN",
    "END",
    "README_EXAMPLE",
    "TIER_EXAMPLES",
    "example_answer",
    "example_notification",
    "readme_block",
    "readme_path",
    "update_readme",
]

BEGIN: Final[str] = (
    "<!-- field-figures: written by `aacn-triage fit-field` "
    "(models/offline/field/readme.py); do not edit by hand -->"
)
END: Final[str] = "<!-- /field-figures -->"

#: The notification of the README's "Try it" (a belted 42-year-old driver, 40 km/h
#: frontal, airbag deployed).
README_EXAMPLE: Final[dict[str, Any]] = {
    "event_id": "tsp-0001",
    "occurred_at": "2026-11-23T08:15:30Z",
    "crash": {"pulse": {"kind": "summary", "delta_v_kmh": 40, "pdof_deg": 0}},
    "occupants": [
        {
            "seat": "driver",
            "stature_cm": 178,
            "mass_kg": 80,
            "age_years": 42,
            "sex": "male",
            "belted": True,
            "frontal_airbag": "deployed",
        }
    ],
}


#: One notification for each risk tier, chosen to land in it (the README shows each with
#: its answer; tests/models/field/test_readme_figures.py holds each to its tier): an
#: unbelted 70-year-old driver without an airbag at 70 km/h frontal (high), the README's
#: own driver at 60 km/h (moderate), a belted 30-year-old driver at 15 km/h frontal (none).
#: Each delta-V is sent as a vehicle measures it (the wire's default).
TIER_EXAMPLES: Final[dict[str, dict[str, Any]]] = {
    "high": {
        "event_id": "tsp-high",
        "occurred_at": "2026-11-23T08:15:30Z",
        "crash": {"pulse": {"kind": "summary", "delta_v_kmh": 70, "pdof_deg": 0}},
        "occupants": [
            {
                "seat": "driver",
                "stature_cm": 175,
                "mass_kg": 78,
                "age_years": 70,
                "sex": "male",
                "belted": False,
                "frontal_airbag": "absent",
            }
        ],
    },
    "moderate": {
        **README_EXAMPLE,
        "event_id": "tsp-moderate",
        "crash": {"pulse": {"kind": "summary", "delta_v_kmh": 60, "pdof_deg": 0}},
    },
    "none": {
        "event_id": "tsp-none",
        "occurred_at": "2026-11-23T08:15:30Z",
        "crash": {"pulse": {"kind": "summary", "delta_v_kmh": 15, "pdof_deg": 0}},
        "occupants": [
            {
                "seat": "driver",
                "stature_cm": 165,
                "mass_kg": 62,
                "age_years": 30,
                "sex": "female",
                "belted": True,
                "frontal_airbag": "not_deployed",
            }
        ],
    },
}


def readme_path() -> Path:
    """``README.md`` of the repository (two levels above this package)."""
    return Path(__file__).resolve().parents[3] / "README.md"


def _pct(x: float) -> str:
    return f"{100.0 * x:.1f} %"


def _pct_ci(ci: Any) -> str:
    return f"[{100.0 * ci[0]:.1f}, {100.0 * ci[1]:.1f}]"


def example_notification(wire: Mapping[str, Any] = README_EXAMPLE) -> CrashNotification:
    """A one-occupant summary-pulse notification of the README (:data:`README_EXAMPLE`, or
    one of :data:`TIER_EXAMPLES`) as the engine receives it from the service.

    The wire defaults written out (the service's ``CrashNotificationIn.to_engine``):
    the default vehicle, a left-hand-drive car, single impact, no rollover, the
    body from stature and mass, posture and seat position not sensed. A service
    test holds the README block to the answer of the real HTTP path.
    """
    occ = wire["occupants"][0]
    pulse = wire["crash"]["pulse"]
    body = nearest_body(occ["stature_cm"], occ["mass_kg"]) or Body.MALE_50TH
    return CrashNotification(
        event_id=wire["event_id"],
        vehicle_model=DEFAULT_SET,  # the wire default vehicle
        drive_side=DriveSide.LEFT,
        pulse=SummaryPulse(
            delta_v_kmh=float(pulse["delta_v_kmh"]), pdof_deg=float(pulse["pdof_deg"])
        ),
        multiple_impacts=False,
        rollover=False,
        occupants=(
            Occupant(
                seat=Seat(occ["seat"]),
                body=body,
                belted=occ["belted"],
                frontal_airbag=AirbagState(occ["frontal_airbag"]),
                age_years=float(occ["age_years"]),
                sex=Sex(occ["sex"]),
                posture_sensed=False,
                seat_track_source=SeatTrackSource.NOT_SENSED,
                stature_cm=float(occ["stature_cm"]),
                mass_kg=float(occ["mass_kg"]),
            ),
        ),
    )


def _decision_doc(decision: Any) -> dict[str, Any]:
    return {
        "probability": decision.probability,
        "probability_ci95": list(decision.probability_ci95),
        "threshold": decision.threshold,
        "model": decision.model,
        "operating_point": decision.operating_point,
        "recommendation": decision.recommendation,
        "tier": decision.tier.value if decision.tier is not None else None,
        "high_threshold": decision.high_threshold,
    }


def example_answer(doc: Mapping[str, Any]) -> dict[str, Any]:
    """The engine's decision on :data:`README_EXAMPLE` and on each of :data:`TIER_EXAMPLES`
    with the field model of `doc`.

    Runs the whole engine (occupant models and surrogates) with the field model
    of the artifact document `doc`, as the service would.

    Returns
    -------
    dict
        ``probability``, ``probability_ci95``, ``threshold``, ``model``,
        ``operating_point``, ``recommendation``, ``tier``, ``high_threshold`` of the
        case's decision; ``tiers``: the same of each tier's example, by tier.
    """
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "field.json"
        path.write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n", encoding="utf-8")
        models = load_engine_models(field_artifact=path, warm=False)
    answer = _decision_doc(triage(example_notification(), models).triage)
    answer["tiers"] = {
        tier: _decision_doc(triage(example_notification(wire), models).triage)
        for tier, wire in TIER_EXAMPLES.items()
    }
    return answer


def _who(wire: Mapping[str, Any]) -> str:
    """A tier example's notification in words."""
    occ = wire["occupants"][0]
    airbag = {"deployed": "airbag deployed", "not_deployed": "airbag not deployed"}.get(
        occ["frontal_airbag"], "no airbag"
    )
    return (
        f"{'belted' if occ['belted'] else 'unbelted'} {occ['age_years']}-year-old "
        f"{'man' if occ['sex'] == 'male' else 'woman'}, {airbag}, "
        f"{wire['crash']['pulse']['delta_v_kmh']} km/h frontal"
    )


def _tier_lines(example: Mapping[str, Any]) -> list[str]:
    """The README's table of one example per tier (nothing when the answer has none)."""
    tiers = example.get("tiers")
    if not tiers:
        return []
    lines = [
        "",
        "One notification chosen for each risk tier (the `triage` of its answer; "
        "`models/offline/field/readme.py` holds the notifications):",
        "",
        "| tier | notification (driver) | P(ISS 15+) [95 % CI] | recommendation |",
        "|---|---|---|---|",
    ]
    for tier, wire in TIER_EXAMPLES.items():
        a = tiers[tier]
        lines.append(
            f"| `{a['tier']}` | {_who(wire)} | {a['probability']:.4f} "
            f"[{a['probability_ci95'][0]:.4f}, {a['probability_ci95'][1]:.4f}] | "
            f"{a['recommendation']} |"
        )
    high = tiers["high"]
    lines += [
        "",
        'The three notifications, to POST as in "Try it":',
        "",
        "```json",
        *(
            json.dumps(TIER_EXAMPLES[t], separators=(", ", ": "))
            for t in ("high", "moderate", "none")
        ),
        "```",
        "",
        f"`high`: at or above the high-risk threshold ({high['high_threshold']:.2f}, "
        "`AACN_HIGH_RISK_THRESHOLD`, the CDC 2008 expert panel's 20 %); `moderate`: at or "
        f"above the operating point's threshold ({high['threshold']:.4f}, "
        f"`{high['operating_point']}`), vehicle telemetry consistent with severe injury, a "
        "moderate-risk criterion of the 2021 field triage guideline; `none`: below it.",
    ]
    return lines


def _score(s: Mapping[str, Any], label: str) -> str:
    ci = s.get("auc_ci95")
    auc = f"{s['auc']:.3f}" + (f" [{ci[0]:.3f}, {ci[1]:.3f}]" if ci else "")
    po = s.get("p_over_o_weighted_ci95")
    ratio = f"{s['p_over_o_weighted']:.2f}" + (f" [{po[0]:.2f}, {po[1]:.2f}]" if po else "")
    return f"| {label} | {auc} | {s['auc_weighted']:.3f} | {ratio} | {s['slope_weighted']:.2f} |"


def readme_block(
    doc: Mapping[str, Any],
    example: Mapping[str, Any],
    measured_check: Mapping[str, Any] | None = None,
) -> str:
    """The README's generated block (markers included) from an artifact and the example's answer.

    Parameters
    ----------
    doc : mapping
        The field risk model artifact document (``models/field/artifacts/field_iss15.json``).
    example : mapping
        :func:`example_answer` of `doc`.
    measured_check : mapping, optional
        The held-out measured-delta-V check of `doc`
        (:func:`models.offline.field.risk_measured.load_check`).
    """
    iss = doc["outcomes"]["iss15"]
    data = doc["data"]
    name = doc["default_operating_point"]
    op = doc["operating_points"][name]["figures"]["heldout"]
    acs = doc["operating_points"]["acs_cot"]["figures"]["heldout"]
    t = iss["temporal"]
    v = doc["vehicle"]["heldout"]
    lines = [
        BEGIN,
        f"Field risk model `{doc['model']['name']}` {doc['model']['version']}: P(ISS 15+) "
        f"fitted on NASS-CDS {data['years'][0]}-{data['years'][1]} ({data['rows']:,} "
        + ("occupants, children included, " if "unknowns" in doc else "adult occupants ")
        + f"of {data['crashes']:,} crashes), calibrated with the national weights; "
        f"held out by crash ({doc['config']['n_splits']} folds, the occupants of a crash never on "
        "both sides; 95 % intervals by resampling crashes; `docs/field/MODEL_CARD.md`):",
        "",
        "| score | AUC [95 % CI] | AUC weighted | P/O weighted | slope weighted |",
        "|---|---|---|---|---|",
        _score(iss["heldout"], "the decision (field risk model)"),
        _score(iss["plain"], "plain logistic regression, same fields"),
        _score(iss["delta_v_alone"], "delta-V alone"),
        _score(doc["comparisons"]["legacy_2_0_0"], "field model 2.0.0 (P(MAIS 3+))"),
        "",
        f"Fitted on 1997-{doc['config']['temporal_cut']} and scored on the latest years "
        f"({t['n']:,} occupants of {doc['config']['temporal_cut'] + 1}-{data['years'][1]}): AUC "
        f"{t['auc']:.3f}, weighted predicted/observed {t['p_over_o_weighted']:.2f} "
        f"[{t['p_over_o_weighted_ci95'][0]:.2f}, {t['p_over_o_weighted_ci95'][1]:.2f}]. At "
        f"`{name}` (the default), held out: sensitivity {_pct(op['sensitivity'])} "
        f"{_pct_ci(op['sensitivity_ci95'])} with {_pct(op['flagged_weighted'])} "
        f"{_pct_ci(op['flagged_weighted_ci95'])} of US towaway-crash occupants flagged "
        f"({_pct(op['flagged'])} of the NASS-CDS sample); `acs_cot` (under-triage <= 5 %): "
        f"sensitivity {_pct(acs['sensitivity'])}, {_pct(acs['flagged_weighted'])} flagged. "
        f"P(anyone in the vehicle ISS 15+): AUC {v['auc']:.3f} "
        f"[{v['auc_ci95'][0]:.3f}, {v['auc_ci95'][1]:.3f}] on held-out vehicles (OnStar's "
        "published vehicle-level figure, an anchor: 0.84).",
        "",
        *([*readme_knowledge_lines(doc), ""] if "unknowns" in doc else []),
        *([*readme_measured_lines(doc, measured_check), ""] if "measurement_model" in doc else []),
        "The example above answers "
        f"P(ISS 15+) = {example['probability']:.4f} "
        f"[{example['probability_ci95'][0]:.4f}, {example['probability_ci95'][1]:.4f}] "
        f"against the threshold {example['threshold']:.4f} (`{example['model']}`, "
        f"`{example['operating_point']}`)"
        + (f", tier `{example['tier']}`" if example.get("tier") else "")
        + f": {example['recommendation']} Delta-V above "
        f"{data['delta_v_max_kmh']:.0f} km/h (the data's largest) is extrapolated "
        "and said so (`delta_v_extrapolated`).",
        *_tier_lines(example),
        END,
    ]
    return "\n".join(lines)


def update_readme(block: str, path: Path | None = None) -> Path | None:
    """Replace the generated block of the README; None when there is no README with markers."""
    target = path or readme_path()
    if not target.is_file():
        return None
    text = target.read_text(encoding="utf-8")
    start, end = text.find(BEGIN), text.find(END)
    if start < 0 or end < start:
        return None
    target.write_text(text[:start] + block + text[end + len(END) :], encoding="utf-8")
    return target
