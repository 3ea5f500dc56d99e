"""The README's figures of the decision, written from the field model artifact (never by hand).

``aacn-triage fit-field`` rewrites the block between :data:`BEGIN` and
:data:`END` in ``README.md`` (:func:`update_readme`): the cross-validated table,
the default operating point's held-out figures, the police-outcome check, the
physics ablation, the extrapolation limit and the answer to the README's own
example notification. ``tests/models/field/test_readme_figures.py`` holds the
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
from models.triage import load_engine_models, triage

__all__ = [
    "BEGIN",
    "END",
    "README_EXAMPLE",
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

_ROWS: Final[tuple[tuple[str, str], ...]] = (
    ("field", "the decision (field model)"),
    ("plain", "plain logistic regression on the telematics fields"),
    ("delta_v", "delta-V alone"),
    ("occupant_models", "the occupant models' P(ISS >= 15), decided on before"),
)


def readme_path() -> Path:
    """``README.md`` of the repository (two levels above this package)."""
    return Path(__file__).resolve().parents[3] / "README.md"


def _pct(x: float) -> str:
    return f"{100.0 * x:.1f} %"


def _pct_ci(ci: Any) -> str:
    return f"[{100.0 * ci[0]:.1f}, {100.0 * ci[1]:.1f}]"


def example_notification() -> CrashNotification:
    """:data:`README_EXAMPLE` as the engine receives it from the service.

    The wire defaults written out (the service's ``CrashNotificationIn.to_engine``):
    the default vehicle, a left-hand-drive car, single impact, no rollover, the
    body from stature and mass, posture and seat position not sensed. A service
    test holds the README block to the answer of the real HTTP path.
    """
    occ = README_EXAMPLE["occupants"][0]
    pulse = README_EXAMPLE["crash"]["pulse"]
    body = nearest_body(occ["stature_cm"], occ["mass_kg"]) or Body.MALE_50TH
    return CrashNotification(
        event_id=README_EXAMPLE["event_id"],
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


def example_answer(doc: Mapping[str, Any]) -> dict[str, Any]:
    """The engine's decision on :data:`README_EXAMPLE` with the field model of `doc`.

    Runs the whole engine (occupant models and surrogates) with the field model
    of the artifact document `doc`, as the service would.

    Returns
    -------
    dict
        ``probability``, ``probability_ci95``, ``threshold``, ``model``,
        ``operating_point``, ``recommendation`` of the case's decision.
    """
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "field.json"
        path.write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n", encoding="utf-8")
        models = load_engine_models(field_artifact=path, warm=False)
    decision = triage(example_notification(), models).triage
    return {
        "probability": decision.probability,
        "probability_ci95": list(decision.probability_ci95),
        "threshold": decision.threshold,
        "model": decision.model,
        "operating_point": decision.operating_point,
        "recommendation": decision.recommendation,
    }


def readme_block(doc: Mapping[str, Any], example: Mapping[str, Any]) -> str:
    """The README's generated block (markers included) from an artifact and the example's answer.

    Parameters
    ----------
    doc : mapping
        The field model artifact document.
    example : mapping
        :func:`example_answer` of `doc`.
    """
    cv = doc["cross_validated"]
    cfg = doc["fit"]["config"]
    name = doc["default_operating_point"]
    op = doc["operating_points"][name]["cross_validated"]
    overall = op["overall"]
    police = doc["police_validation"]
    phys = cv["field_physics"]["auc"] - cv["field"]["auc"]
    meas = cv["field_measures"]["auc"] - cv["field"]["auc"]
    lines = [
        BEGIN,
        f"Field model `{doc['model']['name']}` {doc['model']['version']}, cross-validated on "
        f"the calibration data ({cfg['n_splits']} folds x {cfg['n_repeats']} repeats, penalty "
        "and thresholds chosen inside the training parts, 95 % intervals by bootstrap; "
        "`docs/field/MODEL_CARD.md`):",
        "",
        "| score | AUC, mean of the repeats [95 % CI] | calibration slope |",
        "|---|---|---|",
    ]
    for key, label in _ROWS:
        s = cv[key]
        slope = "-" if s["calibration"] is None else f"{s['calibration']['slope']:.2f}"
        lines.append(
            f"| {label} | {s['auc']:.3f} [{s['auc_ci95'][0]:.3f}, {s['auc_ci95'][1]:.3f}] "
            f"| {slope} |"
        )
    cal = cv["field"]["calibration"]
    lines += [
        "",
        f"Mean predicted P(MAIS 3+) {_pct(cal['mean_predicted'])} against "
        f"{_pct(cal['observed_rate'])} observed. At `{name}` (the default), held out: "
        f"sensitivity {_pct(overall['sensitivity'])} {_pct_ci(overall['sensitivity_ci95'])} "
        f"with {_pct(overall['flagged'])} {_pct_ci(overall['flagged_ci95'])} of occupants "
        f"flagged (PPV {_pct(overall['ppv'])}). On the police-reported outcome of NASS-CDS "
        "1997-2000 (frontal), the survey-weighted AUC is "
        f"{police['field_model_cv']['auc_weighted']:.3f} against "
        f"{police['baseline_cv']['auc_weighted']:.3f} for the statistical baseline refitted "
        "in the same folds. Adding the occupant models' P(ISS >= 15) or their injury "
        "measures as features, with the models run at the true delta-V, changes the "
        f"cross-validated AUC by {phys:+.3f} and {meas:+.3f} (intervals in the model card): "
        "physics is not an input of the decision.",
        "",
        "The example above answers "
        f"P(MAIS 3+) = {example['probability']:.3f} "
        f"[{example['probability_ci95'][0]:.3f}, {example['probability_ci95'][1]:.3f}] "
        f"against the threshold {example['threshold']:.4f} (`{example['model']}`, "
        f"`{example['operating_point']}`): {example['recommendation']} Delta-V above "
        f"{doc['data']['delta_v_max_kmh']:.0f} km/h (the data's largest) is extrapolated "
        "and said so (`delta_v_extrapolated`).",
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
