"""The model card's and README's figures of the measured-delta-V consistency check.

From the check's document (:mod:`models.offline.field.risk_measured`,
``docs/field/measured_check.json``), bound to the artifact by its checksum.
Sensitivity is unweighted (the sample's ISS 15+ occupants), the weighted figure
beside it; the flagged share is weighted (the nation's occupants), the
sample's beside it; intervals by resampling crashes.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

__all__ = ["measured_check_lines", "readme_measured_check_lines"]

#: Each reading's words.
_READING_WORDS = {
    "no_scatter": "measured = reconstructed / f (the sources' direction: the measurement "
    "is the precise reading)",
    "measurement_noisier": "measured = (reconstructed - N(0, 8.6 km/h)) / f (the bound: "
    "were the measurement the noisier)",
}

#: Rows of the calibration table, with the scores' kind.
_ROWS = (
    ("adults, age sent", "age_sent", "adults"),
    ("adults 65+, age sent", "age_sent", "adults 65+"),
    ("children, age sent", "age_sent", "children"),
    ("adults, only what the car senses", "sensed_only", "adults"),
)


def _f(x: Any, nd: int = 3) -> str:
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{float(x):.{nd}f}"


def _ci(ci: Any, nd: int = 2) -> str:
    return f"[{_f(ci[0], nd)}, {_f(ci[1], nd)}]" if ci else ""


def _pct(x: Any) -> str:
    return "n/a" if x is None or not math.isfinite(float(x)) else f"{100.0 * float(x):.1f} %"


def _pct_ci(ci: Any) -> str:
    return f"[{100.0 * ci[0]:.1f}, {100.0 * ci[1]:.1f}]" if ci else ""


def _at(f: Mapping[str, Any]) -> str:
    return (
        f"{_f(f['sensitivity'], 2)} {_ci(f.get('sensitivity_ci95'))} | "
        f"{_f(f['sensitivity_weighted'], 2)} | {_pct(f['flagged_weighted'])} "
        f"{_pct_ci(f.get('flagged_weighted_ci95'))} | {_pct(f['flagged'])}"
    )


def measured_check_lines(check: Mapping[str, Any], reconstructed: Mapping[str, Any]) -> list[str]:
    """The card's lines of the check.

    Parameters
    ----------
    check : mapping
        The check's document.
    reconstructed : mapping
        The artifact's ``unknowns.figures`` (the same figures for the reconstructed
        delta-V, beside).
    """
    fig = check["figures"]
    mm = check["measurement_model"]
    lines = [
        "**Held-out consistency check of the served reading** (a check, not a validation: "
        "the measurements pass through the model they check). Each held-out occupant's "
        "delta-V is replaced by one a vehicle could have measured in that crash, drawn "
        f"{check['draws']} times from `{mm['name']}@{mm['version']}` (the ratio f of the "
        "crash's direction), and decided through its fold's model as served (the tolerance "
        "integrated, the served thresholds). Two readings of the 8.6 km/h "
        "scatter, by which reading is the noisier:",
        "",
    ]
    for reading, words in _READING_WORDS.items():
        if reading in fig:
            ratio = fig[reading]["measured_over_reconstructed_weighted"]
            lines.append(
                f"- `{reading}`: {words}; measured / reconstructed {_f(ratio, 2)} (weighted)."
            )
    lines += [
        "",
        "| delta-V | who | AUC [95 % CI] | weighted predicted/observed [95 % CI] |",
        "|---|---|---|---|",
    ]
    for label, kind, group in _ROWS:
        r = reconstructed[kind].get(group)
        if r is not None:
            lines.append(
                f"| reconstructed (the data) | {label} | {_f(r['auc'])} "
                f"{_ci(r.get('auc_ci95'), 3)} | {_f(r['p_over_o_weighted'], 2)} "
                f"{_ci(r.get('p_over_o_weighted_ci95'))} |"
            )
        for reading in _READING_WORDS:
            s = fig.get(reading, {}).get(kind, {}).get(group)
            if s is not None:
                lines.append(
                    f"| measured, `{reading}` | {label} | {_f(s['auc'])} "
                    f"{_ci(s.get('auc_ci95'), 3)} | {_f(s['p_over_o_weighted'], 2)} "
                    f"{_ci(s.get('p_over_o_weighted_ci95'))} |"
                )
    lines += [
        "",
        "The operating points for a measured delta-V, at the served thresholds (the same as "
        "for a reconstructed one) and at a threshold set on the reading's own held-out "
        "predictions:",
        "",
        "| point | knowledge | delta-V | threshold | sensitivity [95 % CI] | weighted | "
        "flagged weighted [95 % CI] | flagged (sample) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for op in ("sens85", "acs_cot"):
        for know in ("adult", "child", "age_unknown"):
            rec = reconstructed["thresholds_by_knowledge"][op].get(know)
            group = {"adult": "adults", "child": "children", "age_unknown": "everyone"}[know]
            if rec is not None and group in rec["figures"]:
                lines.append(
                    f"| `{op}` | {know} | reconstructed | {rec['threshold']:.4f} | "
                    f"{_at(rec['figures'][group])} |"
                )
            for reading in _READING_WORDS:
                o = fig.get(reading, {}).get("operating_points", {}).get(op, {}).get(know)
                if o is None:
                    continue
                lines.append(
                    f"| `{op}` | {know} | `{reading}`, served | {o['served_threshold']:.4f} | "
                    f"{_at(o['at_served'])} |"
                )
                lines.append(
                    f"| `{op}` | {know} | `{reading}`, own | {o['own_threshold']:.4f} | "
                    f"{_at(o['at_own'])} |"
                )
    lines += ["", *_verdict(check, reconstructed)]
    return lines


def _verdict(check: Mapping[str, Any], reconstructed: Mapping[str, Any]) -> list[str]:
    fig = check["figures"]
    ns = fig["no_scatter"]
    mn = fig["measurement_noisier"]
    a = ns["operating_points"]["sens85"]["adult"]["at_served"]
    b = mn["operating_points"]["sens85"]["adult"]
    rec = reconstructed["thresholds_by_knowledge"]["sens85"]["adult"]["figures"]["adults"]
    po = ns["age_sent"]["adults"]["p_over_o_weighted"]
    return [
        "**What the scatter costs.** The sources make the reconstruction the noisier reading "
        "(Part 563 holds the EDR within +/-10 %; the reconstruction scatters by 8.6 km/h "
        "around it), so the check that stands for the field is `no_scatter`: a measured "
        f"delta-V decided as served keeps the promise of `sens85` for adults with the age sent "
        f"(sensitivity {_f(a['sensitivity'], 3)}) at {_pct(a['flagged_weighted'])} of the "
        f"weighted adults flagged ({_pct(rec['flagged_weighted'])} for the reconstructed "
        f"delta-V), weighted predicted/observed {_f(po, 2)}. The served thresholds are "
        "therefore the reconstructed ones. Were the measurement the noisier reading instead "
        f"(`measurement_noisier`), the scatter would cost sensitivity "
        f"({_f(b['at_served']['sensitivity'], 3)} at the served threshold, "
        f"{_pct(b['at_served']['flagged_weighted'])} flagged) and holding 85 % would flag "
        f"{_pct(b['at_own']['flagged_weighted'])}: the direction is the sources', and the "
        "bound is stated so that a reader who doubts them can see its price.",
    ]


def readme_measured_check_lines(check: Mapping[str, Any]) -> list[str]:
    """The README's line on the check."""
    fig = check["figures"]
    ns, mn = fig["no_scatter"], fig["measurement_noisier"]
    a = ns["operating_points"]["sens85"]["adult"]["at_served"]
    u = ns["operating_points"]["sens85"].get("age_unknown", {}).get("at_served")
    b = mn["operating_points"]["sens85"]["adult"]
    po = ns["age_sent"]["adults"]
    unknown = (
        f"; adults and children sent with only what the car senses: sensitivity "
        f"{_f(u['sensitivity'], 2)} with {_pct(u['flagged_weighted'])} flagged"
        if u
        else ""
    )
    return [
        "Held out with each delta-V as a vehicle would have measured it (a consistency check "
        "through the measurement model, not a validation; model card): adults with the age "
        f"sent, weighted predicted/observed {_f(po['p_over_o_weighted'], 2)} "
        f"{_ci(po.get('p_over_o_weighted_ci95'))}, `sens85` sensitivity "
        f"{_f(a['sensitivity'], 2)} {_ci(a.get('sensitivity_ci95'))} with "
        f"{_pct(a['flagged_weighted'])} flagged{unknown}. Were the measurement the noisier "
        f"reading (the sources say it is not), the served threshold would find "
        f"{_f(b['at_served']['sensitivity'], 2)} and holding 85 % would flag "
        f"{_pct(b['at_own']['flagged_weighted'])}.",
    ]
