"""The field model's card: what it is, how well it does on real crashes, where it stops.

Written by ``aacn-triage fit-field`` (:func:`write_model_card`) beside its plots,
under ``docs/field/mais3/`` by default. Every number in it comes from the fit's
cross-validation (:mod:`.fit`); its validation sections are the
``aacn-triage evaluate`` report (:mod:`.evaluate`) of the cross-validated
predictions.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from models.field.features import FEATURE_NAMES, FieldInputs, FieldMode, Imputation, design_matrix
from models.field.model import FieldModel
from models.offline.field.evaluate import evaluation_markdown, reliability_plot
from models.offline.field.fit import FieldFit
from models.offline.field.published import (
    AUGENSTEIN_DELTA_V_MPH,
    AUGENSTEIN_MAIS3_AT_30_MPH,
    NHTSA_ALL,
    NHTSA_CHECK_SPEEDS_MPH,
    NHTSA_FRONTAL,
    augenstein_check,
    curve_check,
)
from models.offline.paths import docs_dir
from models.units import mph_to_kmh

__all__ = ["default_report_dir", "risk_curve_plot", "write_model_card"]


def default_report_dir() -> Path:
    """``docs/field/mais3`` of the repository when run from a checkout (the MAIS 3+ model
    2.0.0, kept for recalls; ``docs/field`` holds the decision's ISS 15+ model card)."""
    return docs_dir("field", "mais3")


def _f(x: float, nd: int = 3) -> str:
    return "n/a" if not math.isfinite(x) else f"{x:.{nd}f}"


def _ci(ci: Any, nd: int = 3) -> str:
    lo, hi = ci
    return f"[{_f(lo, nd)}, {_f(hi, nd)}]"


def _pct(x: float) -> str:
    return "n/a" if not math.isfinite(x) else f"{100.0 * x:.1f} %"


def _pct_ci(ci: Any) -> str:
    lo, hi = ci
    return f"[{100.0 * lo:.1f}, {100.0 * hi:.1f}]"


def risk_curve_plot(path: Path, fit: FieldFit) -> Path:
    """P(MAIS 3+) against delta-V per crash mode, belted and unbelted, with the 95 % band."""
    doc = fit.artifact
    beta = np.array(doc["coefficients"])
    boot = np.array(doc["bootstrap_coefficients"])
    imp = Imputation(**doc["imputation"])
    delta_v_kmh = np.linspace(2.0, 120.0, 119)
    fig = Figure(figsize=(10.0, 6.0))
    axes = fig.subplots(2, 3, sharex=True, sharey=True).ravel()
    for ax, mode in zip(axes, FieldMode, strict=False):
        for belted, colour in ((True, "tab:blue"), (False, "tab:red")):
            inputs = [
                FieldInputs(delta_v_kmh=float(v), mode=mode, belted=belted, multiple_impacts=False)
                for v in delta_v_kmh
            ]
            x, _ = design_matrix(inputs, imp)
            eta = x @ beta
            sd = (x @ boot.T).std(axis=1, ddof=1)
            p = 1 / (1 + np.exp(-eta))
            lo = 1 / (1 + np.exp(-(eta - 1.96 * sd)))
            hi = 1 / (1 + np.exp(-(eta + 1.96 * sd)))
            ax.plot(delta_v_kmh, p, color=colour, label="belted" if belted else "unbelted")
            ax.fill_between(delta_v_kmh, lo, hi, color=colour, alpha=0.2)
        default = doc["default_operating_point"]
        t = doc["operating_points"][default]["thresholds"][mode.value]
        ax.axhline(t, color="black", linestyle=":", linewidth=1, label=f"{default} threshold")
        ax.set_title(mode.value)
        ax.set_ylim(0.0, 1.0)
        ax.grid(alpha=0.3)
    axes[-1].axis("off")
    axes[0].legend(fontsize=8)
    for ax in axes[3:5]:
        ax.set_xlabel("delta-V, km/h")
    axes[0].set_ylabel("P(MAIS 3+)")
    axes[3].set_ylabel("P(MAIS 3+)")
    fig.suptitle(
        f"Field model: age {imp.age_years:g}, body mass index {imp.bmi:.1f}, single impact, "
        "sex unknown (95 % band: bootstrap refits)"
    )
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    return path


def _scores_table(fit: FieldFit) -> list[str]:
    lines = [
        "| model | AUC (mean of repeats) | AUC [95 % CI] of the averaged predictions "
        "| field model minus this [95 % CI] | calibration intercept | slope | Brier |",
        "|---|---|---|---|---|---|---|",
    ]
    for s in fit.scores:
        diff = (
            "-"
            if s.difference_to_field is None
            else f"{s.difference_to_field[0]:+.3f} {_ci(s.difference_to_field[1])}"
        )
        cal = (
            "- | - | -"
            if s.calibration is None
            else f"{s.calibration['intercept']:+.2f} | {s.calibration['slope']:.2f} | "
            f"{s.calibration['brier']:.4f}"
        )
        lines.append(
            f"| {s.description} | {_f(s.auc)} | {_f(fit_auc_point(fit, s.name))} {_ci(s.auc_ci95)} "
            f"| {diff} | {cal} |"
        )
    return lines


def fit_auc_point(fit: FieldFit, name: str) -> float:
    """AUC of the repeat-averaged out-of-fold predictions of model `name`."""
    from models.offline.field.metrics import auc

    return auc(fit.y, fit.oof[name].mean(axis=0))


def _mode_table(fit: FieldFit) -> list[str]:
    names = list(fit.scores)
    header = "| crash mode | occupants | positives | " + " | ".join(s.name for s in names) + " |"
    lines = [header, "|---|---|---|" + "---|" * len(names)]
    modes = np.array([m.value for m in fit.modes])
    for m in FieldMode:
        sel = modes == m.value
        cells = [
            f"{_f(s.auc_by_mode[m.value][0])} {_ci(s.auc_by_mode[m.value][1], 2)}" for s in names
        ]
        lines.append(
            f"| {m.value} | {int(sel.sum())} | {int(fit.y[sel].sum())} | "
            + " | ".join(cells)
            + " |"
        )
    return lines


def _operating_points(fit: FieldFit) -> list[str]:
    lines = []
    doc_ops = fit.artifact["operating_points"]
    doc_default = fit.artifact["default_operating_point"]
    for name, figs in fit.operating_points.items():
        th = figs["thresholds"]
        lines += [
            f"### `{name}`" + (" (default)" if name == doc_default else ""),
            "",
            doc_ops[name]["description"][0].upper() + doc_ops[name]["description"][1:] + ".",
            "",
            "Thresholds on P(MAIS 3+): "
            + ", ".join(f"{m} {100.0 * t:.2f} %" for m, t in th.items())
            + ".",
            "",
            "| crash mode | occupants | positives | sensitivity [95 % CI] "
            "| flagged [95 % CI] | PPV |",
            "|---|---|---|---|---|---|",
        ]
        for group in ["overall", *(m.value for m in FieldMode)]:
            r = figs[group]
            lines.append(
                f"| {group} | {r['n']} | {r['positives']} | {_pct(r['sensitivity'])} "
                f"{_pct_ci(r['sensitivity_ci95'])} | {_pct(r['flagged'])} "
                f"{_pct_ci(r['flagged_ci95'])} | {_pct(r['ppv'])} |"
            )
        lines.append("")
    return lines


def _coefficients(fit: FieldFit) -> list[str]:
    doc = fit.artifact
    boot = np.array(doc["bootstrap_coefficients"])
    sd = boot.std(axis=0, ddof=1)
    units = {
        "intercept": "",
        "delta_v_kmh": "per km/h",
        "log_delta_v": "per ln(km/h)",
        "belted": "",
        "near_side": "vs frontal",
        "far_side": "vs frontal",
        "rear": "vs frontal",
        "rollover": "vs frontal",
        "age_years": "per year",
        "multiple_impacts": "",
        "bmi": "per kg/m2",
    }
    lines = [
        "| term | logit coefficient | bootstrap SD | odds ratio | unit |",
        "|---|---|---|---|---|",
    ]
    for name, b, s in zip(FEATURE_NAMES, doc["coefficients"], sd, strict=True):
        orr = "-" if name == "intercept" else f"{math.exp(b):.3f}"
        lines.append(f"| {name} | {b:+.4f} | {s:.4f} | {orr} | {units[name]} |")
    sex = doc["sex_offset"]
    lines.append(
        f"| female (offset, borrowed) | {sex['log_odds_ratio_female']:+.4f} | "
        f"{np.std(sex['bootstrap'], ddof=1):.4f} | {math.exp(sex['log_odds_ratio_female']):.3f} "
        f"| centred on {100.0 * sex['female_share']:.1f} % women |"
    )
    return lines


def _police(fit: FieldFit) -> list[str]:
    pol = fit.police
    lines = [
        f"{pol['n']} frontal occupants of NASS-CDS 1997-2000 with a known police-reported "
        f"outcome, {pol['positives']} incapacitating or fatal (A+K; weighted rate "
        f"{100.0 * pol['weighted_rate']:.1f} %). Delta-V is the band midpoint; no stature, "
        "mass or multiple-impact flag. A+K is broader and noisier than MAIS 3+ (about half of "
        "police A injuries are minor by AIS), so the level differs; the ranking compares.",
        "",
        "| score | AUC survey-weighted | AUC unweighted |",
        "|---|---|---|",
    ]
    for row in pol["auc"].values():
        lines.append(
            f"| {row['description']} | {_f(row['auc_weighted'])} | {_f(row['auc_unweighted'])} |"
        )
    return lines


def _validation_sections(fit: FieldFit, out_dir: Path) -> tuple[str, str]:
    """The plots and the ``evaluate`` reports of the cross-validated predictions.

    Returns
    -------
    (str, str)
        The markdown of the MAIS 3+ validation and of the police-outcome one.
    """
    doc = fit.artifact
    field_oof = fit.oof["field"].mean(axis=0)
    rel = reliability_plot(
        out_dir / "reliability.png",
        {
            "field model": (fit.y, field_oof),
            "plain logistic": (fit.y, fit.oof["plain"].mean(axis=0)),
        },
        title="Cross-validated calibration, MAIS 3+ (NASS-CDS 2000-2014)",
    )
    pol = fit.police
    pol_rel = reliability_plot(
        out_dir / "reliability_police.png",
        {"field model (P(MAIS 3+)) vs A+K": (pol["y"], pol["cv_probability"])},
        title="Field model on NASS-CDS 1997-2000 frontal (police A+K)",
    )
    thresholds = {
        name: np.array([op["thresholds"][m.value] for m in fit.modes])
        for name, op in doc["operating_points"].items()
    }
    flags = {name: field_oof >= t for name, t in thresholds.items()}
    validation = evaluation_markdown(
        "Validation: MAIS 3+, NASS-CDS 2000-2014 (cross-validated)",
        fit.y,
        field_oof,
        [m.value for m in fit.modes],
        flags,
        plot_name=rel.name,
        heading="###",
    )
    th_front = {name: op["thresholds"]["frontal"] for name, op in doc["operating_points"].items()}
    pol_validation = evaluation_markdown(
        "Validation: police A+K, NASS-CDS 1997-2000 frontal (survey-weighted)",
        pol["y"],
        pol["cv_probability"],
        ["frontal"] * pol["n"],
        {name: pol["cv_probability"] >= t for name, t in th_front.items()},
        w=pol["w"],
        plot_name=pol_rel.name,
        heading="###",
    )
    return validation, pol_validation


def _what_it_is(fit: FieldFit, curves_name: str) -> list[str]:
    """The model, its inputs, its interval and its coefficients."""
    doc = fit.artifact
    cfg = doc["fit"]["config"]
    data = doc["data"]
    return [
        "## What it is",
        "",
        "The probability the service decides on (`triage.probability`): **P(MAIS 3+)**, the "
        "probability that the occupant has at least one injury of AIS 3 or more, from what "
        "a crash notification carries. MAIS 3+ is the stand-in for ISS 15+ (the trauma-center "
        "criterion), and a conservative one: one AIS 3 injury alone is ISS 9, so MAIS 3+ is "
        "broader than ISS 15+ and a model of it flags more occupants than an ISS 15+ model "
        "would.",
        "",
        "A penalised logistic regression (scikit-learn, L2 on standardised features, penalty "
        f"C = {doc['fit']['penalty_c']:g} chosen by cross-validated log loss) fitted on "
        f"{data['rows']} real occupants ({data['positives']} MAIS 3+) of NASS-CDS 2000-2014, "
        "all crash modes, with one intercept per crash mode and slopes shared across modes "
        "(the L2 penalty shrinks the sparse modes toward the pooled fit: rear has 3 "
        "positives, far side 11, rollover 16). Served with numpy only "
        "(`models/field/model.py`).",
        "",
        "Inputs, built by the same code for the fit and for a request "
        "(`models/field/features.py`): delta-V (linear and log), belt, crash mode "
        "(frontal, near side, far side, rear from the PDOF and the seat; rollover when "
        "reported), age, multiple impacts, body mass index (stature and mass), and sex "
        "through a borrowed offset. Unknown age or body mass index takes the calibration "
        f"median ({doc['imputation']['age_years']:g} years, "
        f"{doc['imputation']['bmi']:.1f} kg/m2), and the answer says so.",
        "",
        "Not inputs, and why: the airbag state (the MAIS file has no airbag column, and in the "
        "1997-2000 file deployment within a delta-V band marks a harder crash, not a "
        "transportable airbag effect); the seat (no seat column: second-row occupants get the "
        "same model); posture and seat position (not in the data). The occupant models "
        "(lumped-parameter models, injury criteria) are **not** inputs either: see below.",
        "",
        "The 95 % interval of the probability is the model's own uncertainty: the logit's "
        f"spread over {cfg['n_bootstrap']} bootstrap refits (rows resampled within outcome, "
        "the whole fit repeated; the 1997-2000 rows resampled for the sex offset). It always "
        "holds the point estimate. Posture and seat position do not enter the model, so their "
        "sensor uncertainty does not widen it (it widens the occupant models' intervals).",
        "",
        "### Coefficients",
        "",
        *_coefficients(fit),
        "",
        "Risk rises with delta-V everywhere in 1-200 km/h and belted is not worse than "
        "unbelted (checked by the fit, which refuses to write an artifact otherwise).",
        "",
        f"![risk curves]({curves_name})",
        "",
    ]


def _physics_section(fit: FieldFit) -> list[str]:
    """Does physics help: the compared models' cross-validated figures."""
    cfg = fit.artifact["fit"]["config"]
    return [
        "The validation sections below are the `aacn-triage evaluate` report of the "
        "repeat-averaged cross-validated probabilities (decided at the shipped thresholds).",
        "",
        "## Does physics help?",
        "",
        f"Repeated stratified cross-validation ({cfg['n_splits']} folds x "
        f"{cfg['n_repeats']} repeats; the penalty chosen inside each training part); "
        f"95 % intervals from {cfg['n_metric_bootstrap']} bootstrap resamples of the rows "
        "(within outcome) of the repeat-averaged out-of-fold predictions. "
        "The occupant models' P is the probability the service decided on before this model "
        "(after the zero-load correction; the statistical baseline where no occupant model "
        "applies), not fitted here.",
        "",
        *_scores_table(fit),
        "",
        f"**{fit.physics_verdict}**",
        "",
        "By crash mode (AUC [95 % CI]):",
        "",
        *_mode_table(fit),
        "",
    ]


def _odds_ratio_to_nhtsa_frontal() -> float:
    """Odds of Augenstein et al.'s frontal level over NHTSA's frontal curve at their speed."""
    aug = AUGENSTEIN_MAIS3_AT_30_MPH[FieldMode.FRONTAL]
    nhtsa = NHTSA_FRONTAL.probability(AUGENSTEIN_DELTA_V_MPH)
    return (aug / (1.0 - aug)) / (nhtsa / (1.0 - nhtsa))


def _published_section(fit: FieldFit) -> list[str]:
    """The model against published field curves given in mph (:mod:`.published`)."""
    model = FieldModel.from_document(fit.artifact)
    occupants = list(fit.inputs)
    lines = [
        "## Against published field curves (mph, converted explicitly)",
        "",
        "The model standardised over the calibration occupants (each occupant's delta-V set "
        "to the speed, probabilities averaged; sex unknown), against published curves given "
        "in mph (`models/offline/field/published.py`; tolerances and their reasons there; "
        "held by `tests/models/field/test_published_curves.py`).",
        "",
        "| curve | "
        + " | ".join(f"{v:g} mph ({mph_to_kmh(v):.0f} km/h)" for v in NHTSA_CHECK_SPEEDS_MPH)
        + " | logit slope per mph (published) | within tolerance |",
        "|---|" + "---|" * (len(NHTSA_CHECK_SPEEDS_MPH) + 2),
    ]
    for curve in (NHTSA_ALL, NHTSA_FRONTAL):
        c = curve_check(model, occupants, curve)
        cells = [f"{m:.3f} ({p:.3f})" for m, p in zip(c.model, c.published, strict=True)]
        lines.append(
            f"| {curve.name}: model (published) | "
            + " | ".join(cells)
            + f" | {c.slope_per_mph:.4f} ({curve.slope_per_mph}) | {'yes' if c.passed else 'NO'} |"
        )
    a = augenstein_check(model, occupants)
    lines += [
        "",
        f"Crash modes at {AUGENSTEIN_DELTA_V_MPH:g} mph ({mph_to_kmh(AUGENSTEIN_DELTA_V_MPH):.1f} "
        "km/h), every calibration occupant put in the mode, against Augenstein et al. (2003). "
        "Their population's covariates are not stated (NASS-CDS with CIREN trauma-center "
        f"cases; their frontal level is {_odds_ratio_to_nhtsa_frontal():.1f} times NHTSA's "
        "frontal curve in odds at that speed), so they check the model's relative risks "
        "across modes, not its level:",
        "",
        "| crash mode | model P | published P | log odds ratio vs frontal: model | published |",
        "|---|---|---|---|---|",
    ]
    for mode, p in a.model.items():
        pub = AUGENSTEIN_MAIS3_AT_30_MPH[mode]
        if mode in a.log_odds_ratios:
            ors = f"{a.log_odds_ratios[mode]:+.2f} | {a.published_log_odds_ratios[mode]:+.2f}"
        else:
            ors = "- | -"
        lines.append(f"| {mode.value} | {p:.3f} | {pub:.3f} | {ors} |")
    lines += [
        "",
        "Modes ordered as published and every odds ratio within tolerance: "
        + ("yes." if a.passed else "NO: " + "; ".join(a.failures)),
        "",
    ]
    return lines


def _limits_and_provenance(doc: dict[str, Any]) -> list[str]:
    """What the model does not cover, and the checksums of what it was fitted on."""
    data = doc["data"]
    return [
        "## Limits",
        "",
        "- **MAIS 3+ is not ISS 15+.** It is broader (one AIS 3 injury is ISS 9): the "
        "probability is of the broader outcome; thresholds were set for MAIS 3+ "
        "sensitivity.",
        "- **Reconstructed, not EDR, delta-V.** NASS delta-V is reconstructed from crush and "
        "runs about 19 % below EDR-measured delta-V (SD 8.6 km/h, n = 228): fed EDR delta-V "
        "the model over-predicts somewhat (errs toward the trauma center).",
        "- **US fleet 2000-2014, vehicles under 10 years old, adults.** Newer vehicles "
        "protect better; children are outside the data.",
        f"- **Delta-V above {data['delta_v_max_kmh']:.0f} km/h** (the largest in the data) is "
        "extrapolated; the answer says so.",
        "- **Sparse modes.** Rear (3 positives), far side (11) and rollover (16) borrow "
        "strength from the pooled fit; their per-mode figures have wide intervals.",
        "- **Sex** comes from the police-outcome data, and **airbag state** is not used.",
        "",
        "## Provenance",
        "",
        f"- Calibration data: `models/offline/data/nass-cds-mais-2000-2014-calibration.csv`, "
        f"sha256 `{data['calibration_csv_sha256']}` (PROVENANCE.md beside it).",
        f"- Police-outcome data: `models/offline/data/nass-cds-1997-2000.csv`, sha256 "
        f"`{data['police_csv_sha256']}`.",
        f"- Feature code checksum (normalised syntax tree): `{doc['feature_code_sha256']}`.",
        f"- Artifact content checksum: `{doc['content_sha256']}`.",
        "",
    ]


def write_model_card(fit: FieldFit, out_dir: Path) -> Path:
    """Write ``MODEL_CARD.md`` and its plots into `out_dir`; returns the card's path."""
    out_dir.mkdir(parents=True, exist_ok=True)
    doc = fit.artifact
    validation, pol_validation = _validation_sections(fit, out_dir)
    curves = risk_curve_plot(out_dir / "risk_curves.png", fit)
    lines = [
        "# Model card: field risk model `field_mais3`",
        "",
        "Generated by `aacn-triage fit-field` (`models/offline/field/fit.py`); do not edit by "
        "hand. Artifact: `models/field/artifacts/field_mais3.json`, "
        f"version {doc['model']['version']}, fitted {doc['fit_date']}.",
        "",
        *_what_it_is(fit, curves.name),
        *_physics_section(fit),
        *_published_section(fit),
        "## The decision: operating points",
        "",
        "Set on the out-of-fold predictions of the whole file; the figures below are "
        "held-out: in each fold the threshold is chosen on the training part's inner "
        "out-of-fold predictions and applied to the held-out part (mean over repeats; 95 % "
        "intervals from the bootstrap). Sensitivity = 1 - under-triage; over-triage = "
        "1 - PPV. Select with `AACN_OPERATING_POINT`.",
        "",
        *_operating_points(fit),
        validation,
        "",
        "## On the police-reported outcome (NASS-CDS 1997-2000, frontal)",
        "",
        *_police(fit),
        "",
        pol_validation,
        "",
        *_limits_and_provenance(doc),
    ]
    path = out_dir / "MODEL_CARD.md"
    path.write_text("\n".join(lines), encoding="utf-8")
    return path
