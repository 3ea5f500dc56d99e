"""The model card's and README's figures by what a notification knows (children, ages unknown).

From the artifact's ``unknowns.figures`` (:mod:`models.offline.field.risk_knowledge`):
held out by crash, each figure with its interval by resampling crashes.
Sensitivity is unweighted (the sample's ISS 15+ occupants), the weighted figure
beside it; the flagged share is weighted (the nation's occupants), the sample's
beside it; a calibration band applies to the point estimate and its interval is
reported.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from models.offline.field.risk_report_measured import (
    measured_check_lines,
    readme_measured_check_lines,
)

__all__ = [
    "knowledge_acceptance",
    "knowledge_lines",
    "measured_lines",
    "readme_knowledge_lines",
    "readme_measured_lines",
]

#: Subgroups shown, in order.
_GROUPS = (
    "children",
    "children 0-4",
    "children 5-9",
    "children 10-15",
    "children in a child seat",
    "adults",
    "adults 16-44",
    "adults 45-64",
    "adults 65+",
)


def _f(x: Any, nd: int = 3) -> str:
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{float(x):.{nd}f}"


def _ci(ci: Any, nd: int = 3) -> str:
    if not ci:
        return ""
    return f"[{_f(ci[0], nd)}, {_f(ci[1], nd)}]"


def _pct(x: Any) -> str:
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{100.0 * float(x):.1f} %"


def _pct_ci(ci: Any) -> str:
    if not ci:
        return ""
    return f"[{100.0 * ci[0]:.1f}, {100.0 * ci[1]:.1f}]"


def _fig(doc: Mapping[str, Any]) -> Mapping[str, Any]:
    out: Mapping[str, Any] = doc["unknowns"]["figures"]
    return out


def _op(doc: Mapping[str, Any], know: str, group: str, op: str = "sens85") -> Mapping[str, Any]:
    out: Mapping[str, Any] = _fig(doc)["thresholds_by_knowledge"][op][know]["figures"][group]
    return out


def _triage_cells(f: Mapping[str, Any]) -> str:
    return (
        f"{_f(f['sensitivity'], 2)} {_ci(f.get('sensitivity_ci95'), 2)} | "
        f"{_f(f['sensitivity_weighted'], 2)} | {_pct(f['flagged_weighted'])} "
        f"{_pct_ci(f.get('flagged_weighted_ci95'))} | {_pct(f['flagged'])} | {_f(f['ppv'], 3)}"
    )


def knowledge_lines(doc: Mapping[str, Any]) -> list[str]:
    """The card's section: children's model choice, age sent and sensed only, thresholds."""
    fig = _fig(doc)
    choice = fig["children_choice"]
    lines = [
        "Children (0-15 years) are in the fitted population with their own terms (feature set "
        "3, `models/field/risk_children.py`: age groups 0-4, 5-9, 10-15 and a child seat; a "
        "child seat counts as restrained)"
        + (" and, since 3.4.0, their own calibration (below)" if "criterion" in choice else "")
        + ". Cross-validation by crash (the same folds), on the children held out:",
        "",
        "| children's model | log loss | log loss weighted | AUC | AUC weighted | "
        "P/O weighted | 0-4 | 5-9 | 10-15 | child seat |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    calibrated = "by_group" if "criterion" in choice else ""
    names = {
        "shared_with_child_terms": "shared model with child terms"
        + (", children's calibration (served)" if calibrated else " (served)"),
        "separate_regression": "a regression of the same inputs fitted on children alone"
        + (", calibrated alike" if calibrated else ""),
        "plain_regression_on_children": "plain logistic regression fitted on children"
        + (", calibrated alike" if calibrated else ""),
        "shared_as_fitted": "shared model as fitted (one recalibration for everyone)",
        "plain_regression_on_children_as_fitted": "plain regression on children as fitted",
    }
    for key, label in names.items():
        if key not in choice:
            continue
        c = choice[key]
        by = c.get("p_over_o_weighted_by_group", {})
        cells = " | ".join(
            _f(by[g], 2) if g in by else "-"
            for g in ("children 0-4", "children 5-9", "children 10-15", "children in a child seat")
        )
        lines.append(
            f"| {label} | {_f(c['log_loss'], 4)} | "
            f"{_f(c['log_loss_weighted'], 5) if 'log_loss_weighted' in c else '-'} | "
            f"{_f(c['auc'])} | {_f(c['auc_weighted'])} | {_f(c['p_over_o_weighted'], 2)} | "
            f"{cells} |"
        )
    chosen = choice["chosen"].replace("_", " ")
    if calibrated:
        lines += [
            "",
            "Each way is calibrated alike on the children (`models/field/children_calibration.py`:"
            " the held-out logit, the age groups 5-9 and 10-15 and the child seat, by weighted "
            "maximum likelihood with the national weights; each fold's children with the "
            "coefficients of the other folds': cross-fitted). Chosen by the held-out weighted "
            f"log loss (the weighted population is the one answered for): **{chosen}**"
            + (
                ", served."
                if choice["chosen"] == "shared_with_child_terms"
                else " (not served: the shared model is served; the card says so as a limit)."
            )
            + (
                f" The shared model is refitted with the selection of {sel} (`fit-field "
                "--selection-from`: the same groups, penalty, trees, folds and seeds); refitted "
                f"on another machine, its trees differ from {sel}'s by the floating-point noise "
                "of the fit, and the adults' held-out figures and thresholds are "
                f"{sel}'s within that noise."
                if (sel := doc["outcomes"]["iss15"].get("selection_from"))
                else ""
            )
            + " As fitted, the shared model ranks the children a little better (AUC above) "
            "but its one recalibration for everyone leaves the age groups far apart; the "
            "children's calibration brings each group's weighted predicted/observed near 1 at "
            "that cost. Its coefficients rest on few weighted events: their refits (one per "
            "member of the bag, each on a resample of the children's crashes) widen the "
            "children's intervals accordingly.",
            "",
        ]
    else:
        lines += [
            "",
            f"Chosen by the held-out log loss: **{chosen}**"
            + (
                "."
                if choice["chosen"] == "shared_with_child_terms"
                else " (not served: the shared model is served; the card says so as a limit)."
            ),
            "",
        ]
    lines += [
        "**What a car senses.** A telematics unit rarely knows an occupant's age, sex, stature "
        "or mass. The service then answers the average over such occupants of the same seat "
        "(and restraint) in the fitted population (`models/field/unknowns.py`: a donor table of "
        "the population drawn by national weight), not the probability at the median age. "
        "Held out by crash, each fold's model with donors of its own training part "
        "(`sensed only`), beside the same occupants with their age, sex, stature and mass sent "
        "(`age sent`):",
        "",
        "| occupants | n (ISS 15+) | AUC age sent | AUC sensed only | P/O weighted age sent | "
        "P/O weighted sensed only |",
        "|---|---|---|---|---|---|",
    ]
    for g in _GROUPS:
        a, s = fig["age_sent"].get(g), fig["sensed_only"].get(g)
        if a is None or s is None:
            continue
        lines.append(
            f"| {g} | {a['n']:,} ({a['positives']:,}) | {_f(a['auc'])} {_ci(a.get('auc_ci95'))} | "
            f"{_f(s['auc'])} {_ci(s.get('auc_ci95'))} | {_f(a['p_over_o_weighted'], 2)} "
            f"{_ci(a.get('p_over_o_weighted_ci95'), 2)} | {_f(s['p_over_o_weighted'], 2)} "
            f"{_ci(s.get('p_over_o_weighted_ci95'), 2)} |"
        )
    lines += [
        "",
        "Without the age, the answer cannot tell the old from the young: it is calibrated for "
        "the occupants of a seat as a whole, and within an age group it is what the seat's "
        "average risk is (the old, whose risk is highest, are under-predicted; the young "
        "over-predicted). Only the age itself (or an input that carries it) can close that gap.",
        "",
        "**Thresholds by what is known.** Each operating point's threshold is set for adults "
        "with their age, for children with their age, and for ages unknown, each on its own "
        "held-out probabilities with the margin of one binomial standard error, so that the "
        "operating point's promise holds for the information at hand; the service decides each "
        "occupant at the threshold of what it knew and returns it (`triage.threshold`, "
        "`triage.knowledge`). Held out (the threshold's own held-out sample); sensitivity "
        "unweighted with the weighted figure beside it:",
        "",
        "| operating point | known | threshold | occupants | sensitivity [95 % CI] | "
        "sensitivity weighted | flagged weighted [95 % CI] | flagged (sample) | PPV (sample) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    by = fig["thresholds_by_knowledge"]
    for op in ("sens85", "acs_cot"):
        for know in ("adult", "child", "age_unknown"):
            entry = by[op][know]
            shown = {
                "adult": ("adults",),
                "child": ("children", "children 0-4", "children 5-9", "children 10-15"),
                "age_unknown": ("everyone", "adults", "adults 65+", "children"),
            }[know]
            for g in shown:
                f = entry["figures"].get(g)
                if f is None:
                    continue
                lines.append(
                    f"| `{op}` | {know.replace('_', ' ')} | {_f(entry['threshold'], 4)} | {g} | "
                    f"{_triage_cells(f)} |"
                )
    return lines


def _by_group_text(figures: Mapping[str, Any]) -> str:
    by = figures.get("p_over_o_weighted_by_group", {})
    return ", ".join(
        f"{g.removeprefix('children ')} {_f(by[g], 2)}"
        for g in ("children 0-4", "children 5-9", "children 10-15")
        if g in by
    )


def knowledge_acceptance(doc: Mapping[str, Any]) -> list[tuple[str, bool, str]]:
    """The children's and the sensed-only acceptance items, measured."""
    fig = _fig(doc)
    choice = fig["children_choice"]
    out = []
    served = choice["shared_with_child_terms"]
    plain = choice["plain_regression_on_children"]
    as_fitted = choice.get("plain_regression_on_children_as_fitted")
    out.append(
        (
            "children: AUC at least the plain regression fitted on children"
            + (" (each calibrated alike)" if "criterion" in choice else ""),
            served["auc"] >= plain["auc"],
            f"{_f(served['auc'], 4)} vs {_f(plain['auc'], 4)}"
            + (
                ""
                if as_fitted is None
                else f" (the plain regression as fitted, its age groups' weighted P/O "
                f"{_by_group_text(as_fitted)}: {_f(as_fitted['auc'], 4)})"
            ),
        )
    )
    for g in ("children", "children 0-4", "children 5-9", "children 10-15"):
        s = fig["age_sent"][g]
        po = s["p_over_o_weighted"]
        out.append(
            (
                f"{g}: weighted P/O 0.8-1.25",
                0.8 <= po <= 1.25,
                f"{_f(po, 2)} {_ci(s.get('p_over_o_weighted_ci95'), 2)}",
            )
        )
    c = _op(doc, "child", "children")
    out.append(
        (
            "children, `sens85`: sensitivity >= 0.85 with <= 8 % of the weighted children flagged",
            c["sensitivity"] >= 0.85 and c["flagged_weighted"] <= 0.08,
            f"{_f(c['sensitivity'], 3)} (weighted {_f(c['sensitivity_weighted'], 3)}), "
            f"{100.0 * c['flagged_weighted']:.2f} % flagged",
        )
    )
    a = _op(doc, "age_unknown", "adults")
    out.append(
        (
            "adults sensed only, `sens85`: sensitivity >= 0.85 with <= 14 % of the weighted "
            "population flagged",
            a["sensitivity"] >= 0.85 and a["flagged_weighted"] <= 0.14,
            f"{_f(a['sensitivity'], 3)} (weighted {_f(a['sensitivity_weighted'], 3)}), "
            f"{100.0 * a['flagged_weighted']:.2f} % flagged",
        )
    )
    for g in ("adults", "adults 65+"):
        s = fig["sensed_only"][g]
        po = s["p_over_o_weighted"]
        out.append(
            (
                f"{g} sensed only: weighted P/O 0.8-1.25",
                0.8 <= po <= 1.25,
                f"{_f(po, 2)} {_ci(s.get('p_over_o_weighted_ci95'), 2)}",
            )
        )
    return out


def readme_knowledge_lines(doc: Mapping[str, Any]) -> list[str]:
    """The README's lines: children and adults sent with only what the car senses."""
    fig = _fig(doc)
    ch, ad = fig["age_sent"]["children"], fig["sensed_only"]["adults"]
    old = fig["sensed_only"]["adults 65+"]
    c = _op(doc, "child", "children")
    u = _op(doc, "age_unknown", "adults")
    choice = fig["children_choice"]
    plain = choice["plain_regression_on_children"]
    as_fitted = choice.get("plain_regression_on_children_as_fitted")
    plain_text = (
        f"a plain regression fitted on children: {_f(plain['auc'])}"
        if as_fitted is None
        else f"a plain regression fitted on children, calibrated alike: {_f(plain['auc'])}; "
        f"as fitted {_f(as_fitted['auc'])}, its age groups' weighted predicted/observed "
        f"{_by_group_text(as_fitted)}"
    )
    by_age = ", ".join(
        f"{g.removeprefix('children ')} {_f(fig['age_sent'][g]['p_over_o_weighted'], 2)}"
        for g in ("children 0-4", "children 5-9", "children 10-15")
        if g in fig["age_sent"]
    )
    return [
        f"Children (0-15, age sent; {ch['n']:,} held out, {ch['positives']:,} ISS 15+): AUC "
        f"{_f(ch['auc'])} {_ci(ch.get('auc_ci95'))} ({plain_text}), weighted "
        f"predicted/observed {_f(ch['p_over_o_weighted'], 2)} "
        f"{_ci(ch.get('p_over_o_weighted_ci95'), 2)} (by age group: {by_age}); at `sens85` "
        "(their own threshold): "
        f"sensitivity {_f(c['sensitivity'], 2)} {_ci(c.get('sensitivity_ci95'), 2)} (weighted "
        f"{_f(c['sensitivity_weighted'], 2)}) with {_pct(c['flagged_weighted'])} "
        f"{_pct_ci(c.get('flagged_weighted_ci95'))} of the weighted children flagged. Adults "
        "sent with only what the car senses (no age, sex, stature or mass: integrated over, "
        f"not imputed): AUC {_f(ad['auc'])} {_ci(ad.get('auc_ci95'))}, weighted "
        f"predicted/observed {_f(ad['p_over_o_weighted'], 2)} "
        f"{_ci(ad.get('p_over_o_weighted_ci95'), 2)} (65+: {_f(old['p_over_o_weighted'], 2)} "
        f"{_ci(old.get('p_over_o_weighted_ci95'), 2)}: without the age the old cannot be told "
        f"apart); at `sens85` (the threshold for ages unknown): sensitivity "
        f"{_f(u['sensitivity'], 2)} {_ci(u.get('sensitivity_ci95'), 2)} (weighted "
        f"{_f(u['sensitivity_weighted'], 2)}) with {_pct(u['flagged_weighted'])} "
        f"{_pct_ci(u.get('flagged_weighted_ci95'))} flagged.",
    ]


def measured_lines(doc: Mapping[str, Any], check: Mapping[str, Any] | None = None) -> list[str]:
    """The card's section on measured delta-V (artifacts with a measurement model).

    `check`: the held-out consistency check of the served reading
    (:mod:`models.offline.field.risk_measured`), when it was run for `doc`.
    """
    mm = doc["measurement_model"]
    (lon, _), (side, _) = mm["longitudinal"][0], mm["side"][0]
    return [
        "A notification carries the delta-V the vehicle measured; the data's is reconstructed "
        f"from crush. The delta-V measurement model `{mm['name']}@{mm['version']}` "
        "(`models/field/measurement.py`, every coefficient with its source) relates them: "
        f"reconstructed = f x measured + N(0, {mm['sd_kmh']:g} km/h), f = {lon:g} for a frontal "
        "or rear crash (Niehoff & Gabler 2006, 121 NASS-CDS cases with an EDR, 23 % under, and "
        "Funk, Cormier & Gabler 2008, 228 frontal cases, 19 % under, weighted by their cases) "
        f"and {side:g} for a side crash (Johnson & Gabler: WinSMASH over the EDR's "
        "common-velocity delta-V by 12.9 % for cars struck by cars and 2.4 % by light trucks "
        "and vans, the EDR's 10 % restitution put back). No comparison of the revised "
        "reconstruction code of the later years with EDRs was found, and a notification names "
        "no body class: one ratio per direction. A measured delta-V is read as the "
        "reconstruction it stands for, f x measured, averaged over the measurement's own "
        f"tolerance (SD {100.0 * mm['measured_tolerance_sd']:g} % of it, Part 563's +/-10 % as "
        f"two SDs; {mm['quadrature_points']} Gauss-Hermite points), and decided at the "
        "threshold of the same knowledge.",
        "",
        "**Which reading is the noisier.** Part 563 holds the EDR within +/-10 %; the "
        f"reconstruction scatters by {mm['sd_kmh']:g} km/h around it, so the reconstruction is "
        "the noisier reading and the risk curves, fitted on it, already carry its noise (they "
        "are flatter in delta-V than a curve of the measurement would be). Averaging them once "
        "more over that scatter flattens them further and, the curves being convex where most "
        "crashes lie, raises the average probability: in the first fit of field model 3.3.0, with "
        "each held-out delta-V drawn as a vehicle would have measured it, that reading "
        "over-predicted the weighted observed rate 1.7 times. It is not served.",
        "",
        *(
            measured_check_lines(check, _fig(doc))
            if check is not None
            else [
                "A held-out check of the served reading (measurements drawn from the relation "
                "above, a consistency check, not a validation: it passes through the model it "
                "checks) was not run for this artifact."
            ]
        ),
    ]


def readme_measured_lines(
    doc: Mapping[str, Any], check: Mapping[str, Any] | None = None
) -> list[str]:
    """The README's lines on measured delta-V (`check`: as :func:`measured_lines`)."""
    mm = doc["measurement_model"]
    return [
        f"A measured delta-V (what a vehicle sends) is read through `{mm['name']}@"
        f"{mm['version']}` as the reconstruction it stands for ({mm['longitudinal'][0][0]:g} "
        f"times the measurement in a frontal or rear crash, {mm['side'][0][0]:g} in a side "
        "crash)"
        + (
            "; its held-out consistency check was not run for this artifact."
            if check is None
            else "."
        ),
        *([] if check is None else ["", *readme_measured_check_lines(check)]),
    ]
