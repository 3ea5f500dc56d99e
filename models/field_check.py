"""The occupant models' triage against real crashes: NASS-CDS frontal occupants.

The occupant models (LPMs) are built from dummy physics, not from crash
records, and their P(ISS >= 15) is not calibrated on field outcomes (README,
"Known limitation"). This check runs the service's own occupant-model answer
over the real front-seat occupants of frontal crashes in the shipped NASS-CDS
1997-2000 extract (`models/baseline/data`, the baseline's training data) and
asks how well it ranks and flags the outcome recorded there.

What is compared, per occupant of a frontal crash (NASS ``frontal`` = 1):

* the LPM's zero-load-corrected P(ISS >= 15), exactly as the service computes
  it for a summary notification (delta-V = the band midpoint of ``dvcat``,
  PDOF 0, the occupant's seat, belt, frontal airbag state, age; body from sex:
  male -> Hybrid III 50th male, female -> 5th female; posture and seat track
  unknown -> the service defaults);
* the statistical baseline's probability (fitted on these very rows, so its
  figures are in-sample and flattering);
* delta-V alone.

Outcome: ``injSeverity`` 3 or 4, the police rating "incapacitating or
killed", the proxy the baseline is fitted to. It is **not** ISS >= 15: it is
broader (weighted prevalence about 11 %), so the LPM's probabilities are not
expected to match its rates; the ranking (AUC) and the share of serious cases
the LPM's decision flags (sensitivity) are what the check is about.

Run::

    python -m models.field_check [--out DIR]

Writes ``field_check.md`` and ``field_check.png`` to ``DIR`` (default: this
package's directory) and prints the summary.
"""

from __future__ import annotations

import argparse
import csv
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt
from sklearn.metrics import roc_auc_score, roc_curve

from models.baseline.fit import (
    DELTA_V_BAND_MIDPOINTS_KMH,
    NOT_SERIOUS_SEVERITIES,
    SERIOUS_SEVERITIES,
    default_data_path,
    triage_rates,
)
from models.impact_mode import ImpactMode
from models.injury.assessment import assess
from models.notification import (
    AirbagState,
    Body,
    Occupant,
    Seat,
    summary_notification,
)
from models.risk_calibration import corrected_probability, zero_load_probability
from models.triage import LPM_THRESHOLDS, EngineModels, load_engine_models, simulate_notification

__all__ = ["FieldCase", "FieldCheck", "field_cases", "lpm_probabilities", "run_field_check"]

FloatArray = npt.NDArray[np.float64]

#: NASS ``dvcat`` bands in order (labels as in the data).
BANDS: tuple[str, ...] = tuple(DELTA_V_BAND_MIDPOINTS_KMH)
#: Frontal thresholds tabulated (the service's 0.10 among them; 0.02 Lubbe & Kiuchi,
#: 0.20 CDC 2008: crash-data-and-triage.md section 1).
THRESHOLDS: tuple[float, ...] = (0.02, 0.03, 0.05, 0.075, 0.10, 0.15, 0.20)


@dataclass(frozen=True)
class FieldCase:
    """One NASS-CDS front-seat occupant of a frontal crash."""

    band: str
    delta_v_kmh: float
    seat: Seat
    belted: bool
    frontal_airbag: AirbagState
    male: bool
    age_years: float
    serious: bool
    weight: float


def field_cases(csv_path: Path | None = None) -> list[FieldCase]:
    """The frontal-crash occupants of the NASS-CDS extract with a known outcome.

    Rows are excluded as the baseline excludes them (``injSeverity`` empty, 5
    or 6, weight 0), and so are non-frontal crashes.
    """
    path = default_data_path() if csv_path is None else csv_path
    out = []
    with path.open(newline="", encoding="utf-8") as fh:
        for rec in csv.DictReader(fh):
            sev_text = rec["injSeverity"].strip()
            if sev_text in ("", "NA") or rec["frontal"] != "1":
                continue
            sev = int(float(sev_text))
            weight = float(rec["weight"])
            if sev not in SERIOUS_SEVERITIES | NOT_SERIOUS_SEVERITIES or weight <= 0.0:
                continue
            if rec["airbag"] == "none":
                bag = AirbagState.ABSENT
            else:
                bag = AirbagState.DEPLOYED if rec["deploy"] == "1" else AirbagState.NOT_DEPLOYED
            out.append(
                FieldCase(
                    band=rec["dvcat"],
                    delta_v_kmh=DELTA_V_BAND_MIDPOINTS_KMH[rec["dvcat"]],
                    seat=Seat.DRIVER if rec["occRole"] == "driver" else Seat.FRONT_PASSENGER,
                    belted=rec["seatbelt"] == "belted",
                    frontal_airbag=bag,
                    male=rec["sex"] == "m",
                    age_years=float(rec["ageOFocc"]),
                    serious=sev in SERIOUS_SEVERITIES,
                    weight=weight,
                )
            )
    return out


def _body(case: FieldCase) -> Body:
    return Body.MALE_50TH if case.male else Body.FEMALE_5TH


def lpm_probabilities(cases: Sequence[FieldCase], models: EngineModels) -> FloatArray:
    """The service's occupant-model P(ISS >= 15) for each case.

    One LPM run per distinct (delta-V, seat, belt, airbag, body), assessed at
    each occupant's age and corrected for the zero-load floor, as
    :func:`models.triage.triage` does for a summary notification.

    Returns
    -------
    ndarray, shape (n,)
    """
    runs = {}
    for case in cases:
        key = (case.delta_v_kmh, case.seat, case.belted, case.frontal_airbag, _body(case))
        if key in runs:
            continue
        occupant = Occupant(
            seat=case.seat, body=key[4], belted=case.belted, frontal_airbag=case.frontal_airbag
        )
        notification = summary_notification(
            (occupant,), case.delta_v_kmh, 0.0, event_id="field-check"
        )
        _, sims, _ = simulate_notification(notification, models)
        result = sims[0].result
        if result is None or result.assessment is None:
            raise RuntimeError(f"occupant model failed for {key}")
        runs[key] = result.measures
    p = np.empty(len(cases))
    for i, case in enumerate(cases):
        body = _body(case)
        measures = runs[(case.delta_v_kmh, case.seat, case.belted, case.frontal_airbag, body)]
        raw = assess(measures, body, case.age_years, ImpactMode.FRONTAL.value).p_iss15
        p0 = zero_load_probability(measures, body, case.age_years, ImpactMode.FRONTAL)
        p[i] = corrected_probability(raw, p0)
    return p


@dataclass(frozen=True)
class FieldCheck:
    """Weighted figures of the occupant models against the NASS frontal outcomes."""

    n: int
    prevalence: float
    auc_lpm: float
    auc_baseline: float
    auc_delta_v: float
    threshold: float
    sensitivity: float
    flagged_share: float
    over_triage: float
    #: per dvcat band: (n, observed weighted serious rate, mean LPM P, mean baseline P)
    by_band: dict[str, tuple[int, float, float, float]]
    #: per frontal threshold on the LPM's corrected P: (flagged share, sensitivity,
    #: over-triage), weighted
    by_threshold: dict[float, tuple[float, float, float]]
    y: FloatArray
    weight: FloatArray
    p_lpm: FloatArray
    p_baseline: FloatArray
    delta_v: FloatArray


def run_field_check(models: EngineModels, csv_path: Path | None = None) -> FieldCheck:
    """Run the check (about 120 occupant-model runs and 8,000 assessments)."""
    cases = field_cases(csv_path)
    y = np.array([1.0 if c.serious else 0.0 for c in cases])
    w = np.array([c.weight for c in cases])
    dv = np.array([c.delta_v_kmh for c in cases])
    p_lpm = lpm_probabilities(cases, models)
    x = np.array(
        [
            [
                c.delta_v_kmh,
                1.0 if c.belted else 0.0,
                1.0 if c.frontal_airbag is AirbagState.DEPLOYED else 0.0,
                1.0,
                c.age_years,
                1.0 if c.male else 0.0,
            ]
            for c in cases
        ]
    )
    p_base = np.asarray(models.baseline.predict_many(x).probability, dtype=np.float64)
    threshold = LPM_THRESHOLDS[ImpactMode.FRONTAL]
    ut, ot = triage_rates(y, p_lpm, w, threshold)
    by_band = {}
    for band in BANDS:
        m = np.array([c.band == band for c in cases])
        if m.any():
            by_band[band] = (
                int(m.sum()),
                float(np.average(y[m], weights=w[m])),
                float(np.average(p_lpm[m], weights=w[m])),
                float(np.average(p_base[m], weights=w[m])),
            )
    by_threshold = {}
    for t in THRESHOLDS:
        ut_t, ot_t = triage_rates(y, p_lpm, w, t)
        by_threshold[t] = (float(np.average(p_lpm >= t, weights=w)), 1.0 - ut_t, ot_t)
    return FieldCheck(
        n=len(cases),
        prevalence=float(np.average(y, weights=w)),
        auc_lpm=float(roc_auc_score(y, p_lpm, sample_weight=w)),
        auc_baseline=float(roc_auc_score(y, p_base, sample_weight=w)),
        auc_delta_v=float(roc_auc_score(y, dv, sample_weight=w)),
        threshold=threshold,
        sensitivity=1.0 - ut,
        flagged_share=float(np.average(p_lpm >= threshold, weights=w)),
        over_triage=ot,
        by_band=by_band,
        by_threshold=by_threshold,
        y=y,
        weight=w,
        p_lpm=p_lpm,
        p_baseline=p_base,
        delta_v=dv,
    )


def _markdown(fc: FieldCheck) -> str:
    lines = [
        "# The occupant models against real frontal crashes (NASS-CDS 1997-2000)",
        "",
        "Generated by `python -m models.field_check` (see its docstring for the method and",
        "the caveats). Outcome: police-reported incapacitating or fatal injury, a broader",
        "proxy for ISS >= 15; all figures survey-weighted.",
        "",
        f"- Occupants of frontal crashes: {fc.n:,}; weighted share with the outcome "
        f"{100 * fc.prevalence:.1f} %.",
        f"- Weighted AUC: occupant models {fc.auc_lpm:.3f}; statistical baseline "
        f"{fc.auc_baseline:.3f} (in-sample: fitted on these rows); delta-V band alone "
        f"{fc.auc_delta_v:.3f}.",
        f"- The service's frontal decision (corrected P >= {fc.threshold:.2f}) flags "
        f"{100 * fc.flagged_share:.1f} % of these occupants and "
        f"{100 * fc.sensitivity:.1f} % of those with the outcome (sensitivity); "
        f"{100 * fc.over_triage:.1f} % of those without it (over-triage).",
        "",
        "| delta-V band (km/h) | occupants | outcome rate (weighted) | mean LPM P(ISS>=15) |"
        " mean baseline P |",
        "|---|---:|---:|---:|---:|",
    ]
    for band, (n, obs, p_l, p_b) in fc.by_band.items():
        lines.append(f"| {band} | {n:,} | {obs:.3f} | {p_l:.3f} | {p_b:.3f} |")
    lines += [
        "",
        "The frontal decision at other thresholds on the same corrected P (a choice for the",
        "trauma system; sensitivity and over-triage against the police-serious outcome):",
        "",
        "| threshold | flagged | sensitivity | over-triage |",
        "|---:|---:|---:|---:|",
    ]
    for t, (flagged, se, ot) in fc.by_threshold.items():
        mark = " (service)" if t == fc.threshold else ""
        lines.append(
            f"| {t:.3f}{mark} | {100 * flagged:.1f} % | {100 * se:.1f} % | {100 * ot:.1f} % |"
        )
    lines += [
        "",
        "Reading: the LPM probability is of ISS >= 15 for a dummy in a 2010 compact sedan,",
        "the outcome is a police rating in 1997-2000 vehicles; only the ranking and the",
        "share flagged are comparable. The gap between the ranking by the LPM and by delta-V",
        "alone is what the occupant physics adds (belt, airbag, body, age) for these crashes.",
        "",
    ]
    return "\n".join(lines)


def _plot(fc: FieldCheck, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for label, score, auc in (
        ("occupant models", fc.p_lpm, fc.auc_lpm),
        ("baseline (in-sample)", fc.p_baseline, fc.auc_baseline),
        ("delta-V band", fc.delta_v, fc.auc_delta_v),
    ):
        fpr, tpr, _ = roc_curve(fc.y, score, sample_weight=fc.weight)
        ax1.plot(fpr, tpr, label=f"{label} (AUC {auc:.3f})")
    ax1.plot([0, 1], [0, 1], "k:", lw=0.8)
    ax1.set_xlabel("false positive rate (weighted)")
    ax1.set_ylabel("true positive rate (weighted)")
    ax1.set_title("NASS-CDS frontal occupants")
    ax1.legend(fontsize=8, loc="lower right")
    bands = list(fc.by_band)
    xs = np.arange(len(bands))
    ax2.plot(xs, [fc.by_band[b][1] for b in bands], "o-", label="outcome rate (police)")
    ax2.plot(xs, [fc.by_band[b][2] for b in bands], "s-", label="mean LPM P(ISS>=15)")
    ax2.plot(xs, [fc.by_band[b][3] for b in bands], "^-", label="mean baseline P")
    ax2.axhline(fc.threshold, color="k", lw=0.8)
    ax2.set_xticks(xs, bands)
    ax2.set_xlabel("delta-V band (km/h)")
    ax2.set_ylabel("probability / rate")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    """Command line entry point."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent)
    args = ap.parse_args(list(argv) if argv is not None else None)
    args.out.mkdir(parents=True, exist_ok=True)
    fc = run_field_check(load_engine_models(use_surrogates=False))
    text = _markdown(fc)
    (args.out / "field_check.md").write_text(text)
    _plot(fc, args.out / "field_check.png")
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
