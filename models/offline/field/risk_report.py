"""The field risk models' card (``docs/field/MODEL_CARD.md``) and its plots, from a fit.

Written by ``aacn-triage fit-field`` (:func:`write_risk_model_card`). Every
number comes from the fit's held-out predictions (folds by crash) or its
temporal check, as the artifact records them.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Final

import numpy as np
from matplotlib.figure import Figure

from models.field.risk_features import AirbagCode, RiskInputs, SeatSide
from models.field.risk_model import REGION_NAMES, RiskModel
from models.offline.field.published import NHTSA_ALL
from models.offline.field.risk_report_knowledge import (
    knowledge_acceptance,
    knowledge_lines,
    measured_lines,
)
from models.offline.field.risk_run import RiskFit
from models.offline.paths import docs_dir
from models.units import kmh_to_mph

__all__ = [
    "ISP_SENSITIVITY",
    "ISP_SPECIFICITY",
    "ONSTAR_VEHICLE_AUC",
    "acceptance",
    "default_report_dir",
    "rewrite_card_text",
    "tier_lines",
    "write_risk_model_card",
]

#: OnStar's published vehicle-level injury severity prediction, AUC 0.84
#: (crash-data-and-triage.md, field anchors) [V]: a published anchor to compare
#: with, not a target.
ONSTAR_VEHICLE_AUC: Final[float] = 0.84

#: OnStar's injury severity prediction (ISP) at its 0.20 cut, vehicle level (anyone ISS
#: 15+): sensitivity 40 %, specificity 98 % (Kononen, Flannagan & Wang 2011, Accid Anal
#: Prev 43:112-122; crash-data-and-triage.md, field anchors) [V]: the published point the
#: vehicle answer at the CDC panel's 20 % stands beside.
ISP_SENSITIVITY: Final[float] = 0.40
ISP_SPECIFICITY: Final[float] = 0.98

#: What each tier means, for the card.
TIER_RULES: Final[dict[str, str]] = {
    "high": "P >= the high-risk threshold (and flagged)",
    "moderate": "flagged, below the high-risk threshold",
    "none": "not flagged",
}

#: Plot files written beside the card.
PLOTS: Final[dict[str, str]] = {
    "reliability": "iss15_reliability.png",
    "curves": "iss15_risk_curves.png",
    "regions": "iss15_regions.png",
}


def default_report_dir() -> Path:
    """``docs/field`` of the repository (else ``./docs/field``)."""
    return docs_dir("field")


def _f(x: Any, nd: int = 3) -> str:
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{float(x):.{nd}f}"


def _ci(ci: Any, nd: int = 3) -> str:
    if ci is None:
        return ""
    return f"[{_f(ci[0], nd)}, {_f(ci[1], nd)}]"


def _pct(x: Any) -> str:
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{100.0 * float(x):.1f} %"


def _pct_ci(ci: Any) -> str:
    return f"[{100.0 * ci[0]:.1f}, {100.0 * ci[1]:.1f}]"


def acceptance(doc: dict[str, Any]) -> list[tuple[str, bool, str]]:
    """Issue 38/39 acceptance items measured on the artifact's held-out figures (to the
    digit that decides them: AUC to 4 places, the flagged share to 0.01 %)."""
    iss = doc["outcomes"]["iss15"]
    h, t = iss["heldout"], iss["temporal"]
    op = doc["operating_points"][doc["default_operating_point"]]["figures"]["heldout"]
    out = [
        (
            "ISS 15+ AUC (held out by crash) at least the plain regression's",
            h["auc"] >= iss["plain"]["auc"],
            f"{_f(h['auc'], 4)} vs {_f(iss['plain']['auc'], 4)}",
        ),
        (
            "weighted mean predicted within 10 % of the weighted observed rate",
            abs(h["p_over_o_weighted"] - 1.0) <= 0.10,
            f"P/O {_f(h['p_over_o_weighted'])} {_ci(h.get('p_over_o_weighted_ci95'))}",
        ),
        (
            "weighted calibration slope 0.8-1.25",
            0.8 <= h["slope_weighted"] <= 1.25,
            f"{_f(h['slope_weighted'])} {_ci(h.get('slope_weighted_ci95'))}",
        ),
        (
            "2011-2014 fitted on 1997-2010: weighted P/O 0.8-1.25",
            0.8 <= t["p_over_o_weighted"] <= 1.25,
            f"{_f(t['p_over_o_weighted'])} {_ci(t.get('p_over_o_weighted_ci95'))}",
        ),
        (
            "default operating point held out: sensitivity >= 0.85",
            op["sensitivity"] >= 0.85,
            f"{_f(op['sensitivity'])} {_ci(op.get('sensitivity_ci95'))}",
        ),
        (
            "default operating point held out: <= 12.5 % of the weighted population flagged",
            op["flagged_weighted"] <= 0.125,
            f"{100.0 * op['flagged_weighted']:.2f} % {_pct_ci(op['flagged_weighted_ci95'])}",
        ),
    ]
    for r in REGION_NAMES:
        o = doc["outcomes"][f"region_{r}"]
        out.append(
            (
                f"{o['label']}: AUC at least the plain regression's; weighted P/O within 15 %",
                o["heldout"]["auc"] >= o["plain"]["auc"]
                and abs(o["heldout"]["p_over_o_weighted"] - 1.0) <= 0.15,
                f"AUC {_f(o['heldout']['auc'], 4)} vs {_f(o['plain']['auc'], 4)}; "
                f"P/O {_f(o['heldout']['p_over_o_weighted'])} "
                f"{_ci(o['heldout'].get('p_over_o_weighted_ci95'))}",
            )
        )
    return out


def _reliability_plot(path: Path, fit: RiskFit) -> None:
    d = fit.data
    y, p, w = d.outcomes[0].y, fit.oof["iss15"], d.w
    fig = Figure(figsize=(10.0, 4.5))
    axes = fig.subplots(1, 2)
    order = np.argsort(p)
    for ax, weights, title in ((axes[0], None, "unweighted"), (axes[1], w, "weighted (ratwgt)")):
        ww = np.ones_like(p) if weights is None else weights
        cum = np.cumsum(ww[order]) / ww.sum()
        bins = np.minimum((cum * 10).astype(int), 9)
        xs, ys = [], []
        for b in range(10):
            ix = order[bins == b]
            if ix.size:
                xs.append(np.average(p[ix], weights=ww[ix]))
                ys.append(np.average(y[ix], weights=ww[ix]))
        ax.plot([0, max(xs + ys)], [0, max(xs + ys)], color="grey", linestyle=":")
        ax.plot(xs, ys, "o-")
        ax.set_xlabel("predicted P(ISS 15+) (held out by crash)")
        ax.set_ylabel("observed share ISS 15+")
        ax.set_title(f"Deciles, {title}")
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def _curve_inputs(dv: float, mode: str, belted: bool) -> RiskInputs:
    pdof = {"frontal": 0.0, "near_side": 270.0, "far_side": 90.0, "rear": 180.0}.get(mode, 0.0)
    return RiskInputs(
        delta_v_kmh=dv,
        pdof_deg=pdof,
        seat_row=1,
        seat_side=SeatSide.LEFT,
        driver=True,
        belted=belted,
        frontal_airbag=AirbagCode.DEPLOYED
        if mode == "frontal" and dv > 15
        else AirbagCode.NOT_DEPLOYED,
        rollover=mode == "rollover",
        multiple_impacts=False,
    )


def _curves_plot(path: Path, model: RiskModel) -> None:
    dvs = np.linspace(5.0, 100.0, 96)
    fig = Figure(figsize=(10.0, 6.0))
    axes = fig.subplots(2, 3, sharex=True, sharey=True).ravel()
    t = model.threshold()
    for ax, mode in zip(
        axes, ("frontal", "near_side", "far_side", "rear", "rollover"), strict=False
    ):
        for belted, colour in ((True, "tab:blue"), (False, "tab:red")):
            preds = model.predict_many([_curve_inputs(float(v), mode, belted) for v in dvs])
            ax.plot(
                dvs,
                [q.probability for q in preds],
                color=colour,
                label="belted" if belted else "unbelted",
            )
            ax.fill_between(
                dvs, [q.ci95[0] for q in preds], [q.ci95[1] for q in preds], color=colour, alpha=0.2
            )
        nhtsa = [NHTSA_ALL.probability(kmh_to_mph(float(v))) for v in dvs]
        ax.plot(
            dvs,
            nhtsa,
            color="black",
            linestyle="--",
            linewidth=1,
            label="NHTSA MAIS 3+ (mph curve)",
        )
        ax.axhline(t, color="black", linestyle=":", linewidth=1, label="default threshold")
        ax.set_title(mode)
        ax.set_ylim(0.0, 1.0)
        ax.grid(alpha=0.3)
    axes[-1].axis("off")
    axes[0].legend(fontsize=7)
    for ax in axes[3:5]:
        ax.set_xlabel("delta-V, km/h")
    axes[0].set_ylabel("P(ISS 15+)")
    axes[3].set_ylabel("P(ISS 15+)")
    imp = model.imputation
    who = (
        "age, sex, stature and mass unknown (integrated over the data's drivers)"
        if model.donors is not None
        else f"age {imp.age_years:g}"
    )
    fig.suptitle(
        f"Driver, {who}, model year {imp.model_year:g}, single impact "
        "(95 % band: bootstrap refits by crash)"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def _regions_plot(path: Path, doc: dict[str, Any]) -> None:
    fig = Figure(figsize=(9.0, 4.0))
    ax = fig.subplots()
    names = list(REGION_NAMES)
    x = np.arange(len(names))
    for k, (key, label) in enumerate(
        (
            ("heldout", "field risk model"),
            ("plain", "plain regression"),
            ("delta_v_alone", "delta-V alone"),
        )
    ):
        vals = [doc["outcomes"][f"region_{r}"][key]["auc"] for r in names]
        ax.bar(x + (k - 1) * 0.27, vals, width=0.27, label=label)
    ax.set_xticks(
        x, [doc["outcomes"][f"region_{r}"]["label"] for r in names], rotation=30, fontsize=8
    )
    ax.set_ylim(0.5, 1.0)
    ax.set_ylabel("AUC, held out by crash")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def _score_row(name: str, s: dict[str, Any]) -> str:
    return (
        f"| {name} | {s['n']:,} | {s['positives']:,} | {_f(s['auc'])} {_ci(s.get('auc_ci95'))} | "
        f"{_f(s['auc_weighted'])} {_ci(s.get('auc_weighted_ci95'))} | "
        f"{_f(s.get('p_over_o_weighted'), 2)} {_ci(s.get('p_over_o_weighted_ci95'), 2)} | "
        f"{_f(s.get('slope_weighted'), 2)} {_ci(s.get('slope_weighted_ci95'), 2)} |"
    )


_SCORE_HEAD = (
    "| | occupants | ISS 15+ | AUC [95 % CI] | AUC weighted | P/O weighted | slope weighted |\n"
    "|---|---|---|---|---|---|---|"
)


def _population(doc: dict[str, Any]) -> list[str]:
    data = doc["data"]
    lines = [
        f"Data: `{data['file']}` (sha256 `{data['sha256'][:16]}...`), NASS-CDS accident years "
        f"{data['years'][0]}-{data['years'][1]}. Fitted population: {data['rows']:,} occupants of "
        f"{data['vehicles']:,} vehicles in {data['crashes']:,} crashes, after these filters:",
        "",
        "| rule | occupants removed |",
        "|---|---|",
    ]
    lines += [f"| {p['text']} | {p['removed']:,} |" for p in data["population"]]
    return lines


def _selection(doc: dict[str, Any]) -> list[str]:
    iss = doc["outcomes"]["iss15"]
    sel = iss["selection"]
    lines = [
        "Each input group is kept only if dropping it raises the held-out (5-fold by crash) "
        f"log loss; penalty chosen by the same log loss (ISS 15+: C = {iss['penalty_c']:g}; "
        f"tried {', '.join(f'{c}: {_f(v, 5)}' for c, v in sel['c_loss'].items())}).",
        "",
        "| input group | ISS 15+: log loss rise when dropped | kept for ISS 15+ "
        "| regions keeping it |",
        "|---|---|---|---|",
    ]
    for g, rise in sel["drop_loss"].items():
        regions = [r for r in REGION_NAMES if g in doc["outcomes"][f"region_{r}"]["groups"]]
        lines.append(
            f"| {g} | {_f(rise, 5)} | {'yes' if g in iss['groups'] else 'no'} "
            f"| {len(regions)} of 8 |"
        )
    lines.append("| delta_v | (always) | yes | 8 of 8 |")
    lines += [
        "",
        "Then the kind: the regression on the kept groups against a bag of "
        f"{cfg_members(doc)} boosted-tree models on the same inputs (trees of depth 3, the number "
        "of trees per member chosen by one member's cross-validated log loss; then, by the same "
        "member's log loss, whether the trees also get feature set 2's inputs, the PDOF seen from "
        "the occupant's side and the impact count where the regression dropped it), and blends "
        "of the two "
        "(calibrated logits weighted `1 - w` and `w`), by the same held-out log loss of the "
        "calibrated probability:",
        "",
        "| outcome | regression log loss | boosted log loss | best blend log loss (w) "
        "| trees per member "
        "| one member's log loss without / with PDOF seen from the seat and impact count "
        "| served kind |",
        "|---|---|---|---|---|---|---|",
    ]
    for o in doc["outcomes"].values():
        s = o["selection"]
        k = s["kind_loss"]
        trees = min(s["tree_loss"], key=lambda n: s["tree_loss"][n])
        g = s.get("tree_groups_loss")
        extra = (
            "-"
            if g is None
            else f"{_f(g['without'], 5)} / {_f(g['with'], 5)}"
            + (" (kept)" if o.get("tree_groups") else "")
        )
        blends = {n.removeprefix("blend_"): v for n, v in k.items() if n.startswith("blend_")}
        best = min(blends, key=lambda n: blends[n]) if blends else None
        blend = "-" if best is None else f"{_f(blends[best], 5)} ({best})"
        served = o["kind"] + (f" (w = {o['weight_boosted']:g})" if o["kind"] == "blend" else "")
        lines.append(
            f"| {o['label']} | {_f(k['logistic'], 5)} | {_f(k['boosted'], 5)} | {blend} "
            f"| {trees} | {extra} | **{served}** |"
        )
    return lines


def cfg_members(doc: dict[str, Any]) -> int:
    """Members of a boosted bag in the fit's settings."""
    return int(doc["config"]["boost_members"])


def _comparisons(doc: dict[str, Any]) -> list[str]:
    iss = doc["outcomes"]["iss15"]
    c = doc["comparisons"]
    version = doc["model"]["version"]
    lines = [_SCORE_HEAD, _score_row(f"field risk model {version} ({iss['kind']})", iss["heldout"])]
    lines.append(_score_row("plain logistic regression (every field, linear)", iss["plain"]))
    lines.append(_score_row("delta-V alone (logistic)", iss["delta_v_alone"]))
    lines.append(_score_row("2.0.0 (P(MAIS 3+), its own inputs)", c["legacy_2_0_0"]))
    lines.append(_score_row("NHTSA MAIS 3+ curve (mph, published)", c["nhtsa_mais3_curve"]))
    b = c["boosted"]
    lines.append(
        f"| one boosted model (HistGradientBoosting, 15 leaves, every column; ranking only) "
        f"| {b['n']:,} | {b['positives']:,} | {_f(b['auc'])} | {_f(b['auc_weighted'])} | | |"
    )
    d = iss["auc_minus_plain_ci95"]
    lines += [
        "",
        "AUC of the model minus the plain regression's: "
        f"{_f(iss['heldout']['auc'] - iss['plain']['auc'], 4)} "
        f"(95 % CI {_ci(d, 4)}); the one boosted model minus the served model: "
        f"{_f(b['auc'] - iss['heldout']['auc'], 4)} ({_ci(b['auc_minus_model_ci95'], 4)}).",
        "",
        "2.0.0 and the NHTSA curve are probabilities of MAIS 3+, not ISS 15+: their P/O against "
        "ISS 15+ shows the cost of the stand-in. On its own outcome (MAIS 3+, 2010-2014, weighted) "
        "the NHTSA curve's P/O is "
        f"{_f(c['nhtsa_mais3_curve_on_mais3_2010_2014']['p_over_o_weighted'], 2)}.",
    ]
    return lines


def _subgroups(doc: dict[str, Any]) -> list[str]:
    lines = [
        "| subgroup | occupants | ISS 15+ | AUC [95 % CI] | AUC weighted | P/O weighted "
        "| slope weighted | plain AUC |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, s in doc["subgroups"].items():
        lines.append(_score_row(name, s["model"]) + f" {_f(s['plain']['auc'])} |")
    return lines


def _operating_points(doc: dict[str, Any]) -> list[str]:
    lines = [
        "| operating point | threshold | sensitivity | sensitivity weighted | flagged (sample) | "
        "flagged weighted (national over-triage) | PPV "
        "| 2011-2014 (fit to 2010): sensitivity, flagged weighted |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, op in doc["operating_points"].items():
        h, t = op["figures"]["heldout"], op["figures"]["temporal"]
        lines.append(
            f"| `{name}`{' (default)' if name == doc['default_operating_point'] else ''} | "
            f"{_f(op['threshold'], 4)} | {_f(h['sensitivity'])} {_ci(h['sensitivity_ci95'])} | "
            f"{_f(h['sensitivity_weighted'])} {_ci(h['sensitivity_weighted_ci95'])} | "
            f"{_pct(h['flagged'])} {_pct_ci(h['flagged_ci95'])} | "
            f"{_pct(h['flagged_weighted'])} {_pct_ci(h['flagged_weighted_ci95'])} | "
            f"{_f(h['ppv'])} | {_f(t['sensitivity'])}, {_pct(t['flagged_weighted'])} |"
        )
    lines += [
        "",
        "Each threshold is set for the required sensitivity plus one binomial standard error "
        "over the positives the held-out check counts (every ISS 15+ occupant of the fit, each "
        "held out once). Until 2026-12-06 the margin was one fold's positives (2.2 times as "
        "wide); at that margin, with the threshold set on the held-out predictions themselves:",
        "",
        "| operating point | target sensitivity | sensitivity | flagged weighted |",
        "|---|---|---|---|",
    ]
    for name, op in doc["operating_points"].items():
        fm = op["figures"]["fold_margin"]
        h = fm["heldout_predictions"]
        lines.append(
            f"| `{name}` | {_f(fm['target_sensitivity'])} | {_f(h['sensitivity'])} | "
            f"{_pct(h['flagged_weighted'])} |"
        )
    return lines


def _fig(x: dict[str, Any], key: str, pct: bool = True) -> str:
    """A figure with its interval where the document has one."""
    ci = x.get(f"{key}_ci95")
    if pct:
        return _pct(x[key]) + (f" {_pct_ci(ci)}" if ci else "")
    return _f(x[key]) + (f" {_ci(ci)}" if ci else "")


def tier_lines(doc: dict[str, Any]) -> list[str]:
    """The card's section on the risk tiers (``models.tiers``); none for an artifact
    fitted before the tiers' figures."""
    tiers = doc.get("tiers")
    if not tiers:
        return []
    h, high = tiers["heldout"], tiers["high_threshold"]
    v = tiers["vehicle_at_high_threshold"]
    lines = [
        f"Each decision has a risk tier: `high` at or above the high-risk threshold ({high:.2f}, "
        "the CDC 2008 expert panel's 'high risk of severe injury', `AACN_HIGH_RISK_THRESHOLD`) "
        "and flagged; `moderate` flagged by the operating point "
        f"(`{tiers['operating_point']}`), below it (the 2021 field triage guideline's "
        "moderate-risk telemetry criterion); `none` not flagged. Held out by crash (the "
        "operating point's threshold chosen inside each training part, as its figures above); "
        "sensitivity: the share of the ISS 15+ occupants in the tier; PPV: the share of the "
        "tier's occupants with ISS 15+; flagged weighted: the tier's share of US towaway-crash "
        "occupants:",
        "",
        "| tier | rule | occupants (ISS 15+) | sensitivity | sensitivity weighted | "
        "at or above: sensitivity, weighted | PPV (sample) | PPV weighted | flagged weighted |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for tier in ("high", "moderate", "none"):
        t = h[tier]
        lines.append(
            f"| `{tier}` | {TIER_RULES[tier]} | {t['n']:,} ({t['positives']:,}) | "
            f"{_fig(t, 'sensitivity')} | {_fig(t, 'sensitivity_weighted')} | "
            f"{_pct(t['sensitivity_at_or_above'])}, "
            f"{_pct(t['sensitivity_at_or_above_weighted'])} | {_fig(t, 'ppv')} | "
            f"{_fig(t, 'ppv_weighted')} | {_fig(t, 'flagged_weighted')} |"
        )
    lines += [
        "",
        f"The vehicle's P(anyone ISS 15+) at {v['threshold']:.2f}, held out "
        f"({v['n']:,} vehicles, {v['positives']:,} with an ISS 15+ occupant), beside OnStar's "
        "published injury severity prediction at the same cut (Kononen, Flannagan & Wang "
        "2011; its own sample, NASS-CDS 1999-2008, MY 2000+, planar crashes: a published "
        "anchor, not a target):",
        "",
        "| vehicle at 0.20 | sensitivity | specificity | PPV | flagged weighted |",
        "|---|---|---|---|---|",
        f"| this model, sample | {_fig(v, 'sensitivity')} | {_fig(v, 'specificity')} | "
        f"{_fig(v, 'ppv')} | - |",
        f"| this model, weighted | {_fig(v, 'sensitivity_weighted')} | "
        f"{_fig(v, 'specificity_weighted')} | {_fig(v, 'ppv_weighted')} | "
        f"{_fig(v, 'flagged_weighted')} |",
        f"| OnStar ISP (published) | {_pct(ISP_SENSITIVITY)} | {_pct(ISP_SPECIFICITY)} | - | - |",
    ]
    return lines


def _temporal(doc: dict[str, Any]) -> list[str]:
    drift = doc["drift"]
    lines = [
        "Fleet drift treatments, each scored as the service answers (the accident year, where a "
        "treatment keeps it, at the latest fitted year: a notification gives no survey year) on "
        "two splits of the years up to 2010: an inner temporal split (fit to 2006, test "
        "2007-2010) and the folds by crash; chosen by the mean of the two weighted log losses: "
        f"**{drift['chosen']}**. (Until 2026-12-06 only the inner temporal split chose: it "
        "picked the accident-year term, whose served answers were 1.43 times the observed rate "
        "over 1997-2014.)",
        "",
        "| treatment | inner temporal: weighted log loss | P/O | folds by crash, as served: "
        "weighted log loss | P/O | criterion |",
        "|---|---|---|---|---|---|",
    ]
    for n, v in drift["inner_temporal"].items():
        lines.append(
            f"| {n} | {_f(v['weighted_log_loss'], 5)} | {_f(v['weighted_p_over_o'], 3)} | "
            f"{_f(v['served_folds_weighted_log_loss'], 5)} | "
            f"{_f(v['served_folds_weighted_p_over_o'], 3)} | {_f(v['criterion'], 5)} |"
        )
    lines += [
        "",
        "Outer temporal check: fitted on 1997-2010, served as on 2011-2014 (accident year at its "
        "latest fitted value), scored on 2011-2014:",
        "",
        "| outcome | occupants | positives | AUC [95 % CI] | AUC weighted | P/O weighted "
        "[95 % CI] | slope weighted | P/O unweighted |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for o in doc["outcomes"].values():
        t = o["temporal"]
        lines.append(
            f"| {o['label']} | {t['n']:,} | {t['positives']:,} | {_f(t['auc'])} "
            f"{_ci(t.get('auc_ci95'))} | {_f(t['auc_weighted'])} | "
            f"{_f(t['p_over_o_weighted'], 2)} {_ci(t.get('p_over_o_weighted_ci95'), 2)} | "
            f"{_f(t['slope_weighted'], 2)} | {_f(t['p_over_o'], 2)} |"
        )
    return lines


def _inputs_of(o: dict[str, Any]) -> list[str]:
    """The groups an outcome model uses (a bag's tree-only groups included)."""
    extra = o.get("tree_groups", []) if o["kind"] in ("boosted", "blend") else []
    return [*o["groups"], *extra]


def _regions(doc: dict[str, Any]) -> list[str]:
    lines = [
        "| region (outcome) | kind | positives | AUC [95 % CI] | AUC weighted | "
        "P/O weighted [95 % CI] | plain AUC | delta-V alone AUC | groups kept |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in REGION_NAMES:
        o = doc["outcomes"][f"region_{r}"]
        h = o["heldout"]
        lines.append(
            f"| {o['label']} | {o['kind']} | {h['positives']:,} | {_f(h['auc'])} "
            f"{_ci(h['auc_ci95'])} | "
            f"{_f(h['auc_weighted'])} | {_f(h['p_over_o_weighted'], 2)} "
            f"{_ci(h['p_over_o_weighted_ci95'], 2)} | {_f(o['plain']['auc'])} | "
            f"{_f(o['delta_v_alone']['auc'])} | {', '.join(_inputs_of(o))} |"
        )
    return lines


def _knowledge(doc: dict[str, Any], check: dict[str, Any] | None) -> list[str]:
    if "unknowns" not in doc:
        return []
    out = ["## Children, and what a car senses", *knowledge_lines(doc), ""]
    if "measurement_model" in doc:
        out += ["## Measured delta-V", *measured_lines(doc, check), ""]
    return out


def _card(doc: dict[str, Any], check: dict[str, Any] | None = None) -> str:
    iss = doc["outcomes"]["iss15"]
    v = doc["vehicle"]["heldout"]
    cfg = doc["config"]
    lines = [
        f"# Field risk model card: `{doc['model']['name']}` {doc['model']['version']}",
        "",
        "Written by `aacn-triage fit-field` from the fit; do not edit by hand. The MAIS 3+ model "
        "2.0.0 it replaces as the decision is described in `mais3/MODEL_CARD.md` and stays "
        "loadable for recall reports (`aacn-triage cases rescore`).",
        "",
        "## What it is",
        "P(ISS 15+) of an occupant (ISS >= 16: ISS 15 cannot occur), the trauma-center criterion, "
        "from what a notification carries; beside it, P(AIS 3+ injury) in each body region (AIS 2+ "
        "where AIS 3+ is too rare to fit: named in the outcome label) and P(anyone in the vehicle "
        "ISS 15+). Each is, as cross-validation by crash chose per outcome, either an "
        "L2-penalised logistic regression (splines of delta-V and age, delta-V slopes by crash "
        f"mode and belt), a bag of {cfg['boost_members']} boosted-tree models (depth 3) each "
        "fitted on a resample of whole crashes (on the regression's inputs and, where one "
        "member's cross-validated log loss falls with them, the PDOF seen from the occupant's "
        "side and the vehicle's impact count: feature set 2, `models/field/risk_impacts.py`), "
        "or a blend of the two (their calibrated logits weighted; the regression's refits on "
        "the bag's resamples), fitted unweighted for ranking, then recalibrated "
        "with the national weights `ratwgt` (a bag on its out-of-bag scores): the probability "
        "means *of such occupants in US towaway crashes*. ISS 15+ is "
        f"**{iss['kind']}**; the regions: "
        + ", ".join(
            f"{r.replace('_', ' ')} {doc['outcomes'][f'region_{r}']['kind']}" for r in REGION_NAMES
        )
        + ". The vehicle answer recalibrates the noisy-OR of its occupants' P(ISS 15+) on "
        "held-out vehicles. Intervals: bootstrap refits by crash "
        f"({cfg['n_bootstrap']} refits of a regression, a bag's {cfg['boost_members']} members; "
        f"the figures' intervals: {cfg['n_metric_bootstrap']} resamples of whole crashes). "
        "Served in numpy (`models/field/risk_model.py`, trees in `models/field/boosted.py`).",
        "",
        *_population(doc),
        "",
        (
            "Unknown occupant inputs (age, sex, stature, mass, belt use) are integrated over "
            "the fitted population's donors of the same seat (below); unknown vehicle inputs "
            "take the population's values (model year"
            if "unknowns" in doc
            else "Unknown inputs take the population's values (age, stature, mass: medians; sex: "
            "the share of women; model year"
        )
        + ": the latest year's median; quarter turns of a reported rollover: the "
        "median of rolled vehicles"
        + (
            "; the impact count of reported multiple impacts: the median of vehicles with two or "
            f"more harmful events, {doc['imputation']['impact_count']:g}; a single impact is one"
            if "impact_count" in doc["imputation"]
            else ""
        )
        + ") and are named in the answer's assumptions. The accident year, "
        f"where a model keeps it, is served at {doc['imputation']['accident_year']:g} "
        "(the latest fitted).",
        "",
        "## Inputs kept by cross-validation",
        *_selection(doc),
        "",
        f"## ISS 15+, held out by crash ({cfg['n_splits']}-fold, the occupants of a crash "
        "never on both sides)",
        *_comparisons(doc),
        "",
        f"![reliability]({PLOTS['reliability']})",
        "",
        "### By crash mode, seat and frontal airbag state",
        *_subgroups(doc),
        "",
        "## Fleet drift: the latest years held out",
        *_temporal(doc),
        "",
        (
            "## Operating points (held out: each fold's threshold set on the other folds' "
            "held-out predictions)"
            if doc["operating_points"]["sens85"]["figures"].get("threshold_method")
            == "other_folds_heldout"
            else "## Operating points (held out: thresholds chosen inside each training part)"
        ),
        *_operating_points(doc),
        "",
        f"![risk curves]({PLOTS['curves']})",
        "",
        *(["## Risk tiers (held out)", *tier_lines(doc), ""] if doc.get("tiers") else []),
        "## P(anyone in the vehicle ISS 15+)",
        f"Held out by crash: {v['n']:,} vehicles, {v['positives']:,} with an ISS 15+ occupant; AUC "
        f"{_f(v['auc'])} {_ci(v['auc_ci95'])}, weighted {_f(v['auc_weighted'])} "
        f"{_ci(v['auc_weighted_ci95'])}; weighted P/O {_f(v['p_over_o_weighted'], 2)} "
        f"{_ci(v['p_over_o_weighted_ci95'], 2)}. Published anchor (not a target): OnStar's "
        f"vehicle-level injury severity prediction, AUC {ONSTAR_VEHICLE_AUC:.2f}. Served, the "
        "vehicle's probability is never below its riskiest occupant's P(ISS 15+) (these "
        "figures are of the recalibrated value before that floor).",
        "",
        *_knowledge(doc, check),
        "## Region risk",
        *(
            [
                f"The region models are those of {doc['regions_from']['version']} as they are "
                "(a decision-only refit, `fit-field --regions-from`): fitted on "
                f"{doc['regions_from']['rows']:,} adult occupants; a child's region risks are "
                "the adults' models' (extrapolated). Their figures are that fit's.",
                "",
            ]
            if "regions_from" in doc
            else []
        ),
        *_regions(doc),
        "",
        f"![regions]({PLOTS['regions']})",
        "",
        "## Acceptance, measured",
        "| item | holds | figure |",
        "|---|---|---|",
        *[f"| {a} | {'yes' if ok else '**no**'} | {fig} |" for a, ok, fig in acceptance(doc)],
        *[
            f"| {a} | {'yes' if ok else '**no**'} | {fig} |"
            for a, ok, fig in (knowledge_acceptance(doc) if "unknowns" in doc else [])
        ],
        "",
        "## Limits",
        (
            "- Delta-V is NASS-CDS's reconstruction (from crush), which runs lower than a "
            "vehicle's measurement: a measured delta-V is read through the measurement model "
            "(above), whose coefficients rest on two published comparisons and no comparison by "
            "crash mode or vehicle class."
            if "measurement_model" in doc
            else "- Delta-V is NASS-CDS's reconstruction (from crush), which runs lower than EDR "
            "delta-V: a telematics delta-V reads somewhat higher than the data's, so the "
            "probability errs high."
        ),
        f"- Delta-V above {doc['data']['delta_v_max_kmh']:.0f} km/h (the data's largest) is "
        "extrapolated; the spline is clamped at 100 km/h.",
        "- Rows 4-5 are outside the fitted population. Children are in it (feature set 3), but "
        "the data know a child seat only as such (rear-facing, forward-facing and booster seats "
        "alike) and hold few severely injured children: their figures have wide intervals.",
        f"- ISS 15+ model ranking AUC {_f(iss['heldout']['auc'])}; weighted figures are dominated "
        "by few high-weight crashes and have wide intervals.",
    ]
    return "\n".join(lines) + "\n"


def write_risk_model_card(fit: RiskFit, out_dir: Path) -> Path:
    """Write ``MODEL_CARD.md`` and its plots into `out_dir`; returns the card's path."""
    out_dir.mkdir(parents=True, exist_ok=True)
    doc = fit.artifact
    model = RiskModel.from_document(doc)
    _reliability_plot(out_dir / PLOTS["reliability"], fit)
    _curves_plot(out_dir / PLOTS["curves"], model)
    _regions_plot(out_dir / PLOTS["regions"], doc)
    check = fit.figures.get("measured_check")
    return rewrite_card_text(doc, check, out_dir)


def rewrite_card_text(doc: dict[str, Any], check: dict[str, Any] | None, out_dir: Path) -> Path:
    """Write ``MODEL_CARD.md`` of `doc` (and its measured check) in `out_dir`; plots untouched."""
    path = out_dir / "MODEL_CARD.md"
    path.write_text(_card(doc, check), encoding="utf-8")
    return path
