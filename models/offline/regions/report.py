"""The body map against real injuries: the report of issue 39 (items 3, 4 and 5).

Runs the occupant models on the shared NASS-CDS 1997-2014 file (the cached
physics table, :mod:`models.offline.regions.table`), then writes

- ``docs/regions/regions.md`` and ``regions.png``: region by region, the
  measures, the published curves, the body map's region AIS and delta-V
  alone against the real region outcomes (:mod:`models.offline.regions.skill`),
  the AIS 6 check by mode, and whether field-calibrated measures add
  (:mod:`models.offline.regions.calibrate`);
- the same tables into ``docs/occupant-models.md`` between the markers
  ``<!-- regions:begin -->`` and ``<!-- regions:end -->``.

Run::

    python -m models.offline.regions.report [--region-risk CSV] [--out DIR] [--workers 1]

``--region-risk``: cross-validated field region risks keyed by occupant (see
:mod:`models.offline.regions.skill`); without it that column says "not given".
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Final

import numpy as np
import pandas as pd

from models.notification import AirbagState
from models.offline.paths import docs_dir
from models.offline.regions.calibrate import AddedValue, CalibratedCurve, item_five
from models.offline.regions.rows import KEY_COLUMNS, outcome_frame
from models.offline.regions.sidecheck import SideRun, side_runs, side_table
from models.offline.regions.skill import (
    MODES,
    REGION_SPECS,
    AisSixRow,
    RegionSkill,
    ais_six_check,
    analysis_frame,
    region_skill,
)
from models.offline.regions.stats import BOOTSTRAP_REPLICATES, BOOTSTRAP_SEED
from models.offline.regions.table import physics_table

__all__ = ["BEGIN", "END", "RegionReport", "main", "run_report"]

BEGIN: Final[str] = "<!-- regions:begin -->"
END: Final[str] = "<!-- regions:end -->"


class RegionReport:
    """Everything the report shows."""

    def __init__(
        self,
        frame: pd.DataFrame,
        skills: list[RegionSkill],
        ais_six: list[AisSixRow],
        curves: list[CalibratedCurve],
        added: list[AddedValue],
        region_risk_given: bool,
        side: list[SideRun],
        near_side_bags: AisSixRow,
    ) -> None:
        self.frame = frame
        self.skills = skills
        self.ais_six = ais_six
        self.curves = curves
        self.added = added
        self.region_risk_given = region_risk_given
        self.side = side
        self.near_side_bags = near_side_bags


def _region_risk(frame: pd.DataFrame, path: Path | None) -> dict[str, pd.Series]:
    if path is None:
        return {}
    risk = pd.read_csv(path)
    merged = frame[list(KEY_COLUMNS)].merge(risk, on=list(KEY_COLUMNS), how="left")
    return {
        c.removeprefix("region_risk_"): merged[c]
        for c in risk.columns
        if c.startswith("region_risk_")
    }


def run_report(
    region_risk: Path | None = None, workers: int | None = None, progress: bool = True
) -> RegionReport:
    """Compute the report (about 2 minutes on one core with the runs cached)."""
    table = physics_table(workers=workers, progress=progress)
    frame = analysis_frame(table, outcome_frame())
    risks = _region_risk(frame, region_risk)
    skills = [
        region_skill(frame, spec, None if spec.risk_region is None else risks.get(spec.risk_region))
        for spec in REGION_SPECS
    ]
    curves, added = item_five(frame)
    bags = analysis_frame(
        physics_table(side_airbag=AirbagState.DEPLOYED, workers=workers, progress=progress),
        outcome_frame(),
    )
    near_bags = next(
        r for r in ais_six_check(bags, "reported_ais_head_neck") if r.mode == "near_side"
    )
    return RegionReport(
        frame=frame,
        skills=skills,
        ais_six=ais_six_check(frame, "reported_ais_head_neck"),
        curves=curves,
        added=added,
        region_risk_given=bool(risks),
        side=side_runs(),
        near_side_bags=near_bags,
    )


def _pct(x: float) -> str:
    return "-" if not np.isfinite(x) else f"{100 * x:.1f} %"


def _skill_table(rep: RegionReport) -> list[str]:
    lines = [
        "| region (outcome) | score | occupants (with the outcome) | AUC, weighted [95 %] |"
        " AUC, unweighted |",
        "|---|---|---:|---:|---:|",
    ]
    for rs in rep.skills:
        labels = [s.label for s in rs.scores]
        for s in rs.scores:
            first = s is rs.scores[0]
            name = f"{rs.spec.name} (AIS {rs.spec.level}+)" if first else ""
            lines.append(
                f"| {name} | {s.label} | {s.n:,} ({s.positives:,}) | {s.auc.text()} | "
                f"{s.auc_unweighted:.3f} |"
            )
        if "region risk" not in labels:
            note = "not given" if rs.spec.risk_region is not None else "no region risk"
            lines.append(f"| | region risk (field model) | | {note} | |")
    return lines


def _calibration_table(rep: RegionReport) -> list[str]:
    lines = [
        "| region (outcome) | observed, weighted [95 %] | body map AIS >= 3, weighted share |"
        " share / observed [95 %] | published curves' mean P(AIS 3+) | mean P / observed [95 %] |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for rs in rep.skills:
        c = rs.calibration
        curve = "-" if c.curve_mean is None else _pct(c.curve_mean)
        obs = f"{_pct(c.observed.value)} [{_pct(c.observed.low)}, {_pct(c.observed.high)}]"
        curve_ratio = "-" if c.curve_ratio is None else c.curve_ratio.text("{:.1f}")
        lines.append(
            f"| {rs.spec.name} (AIS {rs.spec.level}+) | {obs} | {_pct(c.map_share)} | "
            f"{c.map_ratio.text('{:.1f}')} | {curve} | {curve_ratio} |"
        )
    return lines


def _mode_table(rep: RegionReport) -> list[str]:
    lines = [
        "| region | score | " + " | ".join(MODES) + " |",
        "|---|---|" + "---:|" * len(MODES),
    ]
    for rs in rep.skills:
        labels = [s.label for s in rs.scores if s.label != "region risk"]
        for label in labels:
            cells = []
            for m in MODES:
                row = rs.by_mode[m]
                cells.append(
                    f"{row[label]:.2f} ({int(row['positives'])})"
                    if np.isfinite(row[label])
                    else f"- ({int(row['positives'])})"
                )
            lines.append(f"| {rs.spec.name} | {label} | " + " | ".join(cells) + " |")
    return lines


def _ais_six_row(r: AisSixRow, label: str) -> str:
    agree = (
        f"{_pct(r.agree_mais5)} / {_pct(r.died)} / {r.median_iss:.0f}"
        if np.isfinite(r.agree_mais5)
        else "-"
    )
    return (
        f"| {label} | {r.n:,} | {_pct(r.model_ais6)} | {_pct(r.reported_ais6)} | "
        f"{_pct(r.reported_ais5)} | {_pct(r.real_mais5)} | {_pct(r.real_head5)} | {agree} |"
    )


def _ais_six_table(rep: RegionReport) -> list[str]:
    lines = [
        "| mode | occupants | models' head/neck AIS 6 (assessment) | reported AIS 6 |"
        " reported AIS 5+ | real MAIS 5+ | real head/neck AIS 5+ |"
        " of the models' AIS 6: real MAIS 5+ / died / median ISS |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    lines += [_ais_six_row(r, r.mode) for r in rep.ais_six]
    lines.append(
        _ais_six_row(rep.near_side_bags, "near_side, side airbags taken as deployed (what-if)")
    )
    return lines


def _item_five_tables(rep: RegionReport) -> list[str]:
    lines = [
        "Field-fitted risk functions, P(AIS 3+) = expit(a_mode + b ln(1 + measure)):",
        "",
        "| region | measure | b | a (frontal / near / far / rear) | cross-validated AUC |"
        " mean P / observed |",
        "|---|---|---:|---|---:|---:|",
    ]
    for c in rep.curves:
        a = " / ".join(f"{c.intercepts[m]:.2f}" if m in c.intercepts else "-" for m in MODES)
        lines.append(
            f"| {c.region} | {c.measure} | {c.slope:.3f} | {a} | {c.auc_cv:.3f} | "
            f"{c.expected / c.observed:.2f} |"
        )
    lines += [
        "",
        "Do the measures add to the notification's fields (delta-V by mode, belt, age, sex,"
        " frontal airbag, rollover, multiple impacts)? Out-of-fold weighted AUC:",
        "",
        "| outcome | positives | without physics | with the measures | difference [95 %] |"
        " difference, 2010-2014 held out | verdict |",
        "|---|---:|---:|---:|---:|---:|---|",
    ]
    for av in rep.added:
        verdict = "adds" if av.adds else "does not add"
        late = "-" if not np.isfinite(av.held_out_years) else f"{av.held_out_years:+.3f}"
        lines.append(
            f"| {av.outcome} | {av.positives:,} | {av.auc_base:.3f} | {av.auc_physics:.3f} | "
            f"{av.difference.text('{:+.3f}')} | {late} | {verdict} |"
        )
    return lines


def block(rep: RegionReport) -> str:
    """The generated block of docs/occupant-models.md."""
    n = len(rep.frame)
    crashes = rep.frame["crash"].nunique()
    lines = [
        BEGIN,
        "",
        "## The body map against real injuries (NASS-CDS 1997-2014)",
        "",
        "Generated by `python -m models.offline.regions.report` (method and caveats in its",
        "modules' docstrings; full report `docs/regions/regions.md`). The occupant models were",
        f"run, as the service runs them, on the {n:,} occupants of {crashes:,} crashes of the",
        "shared file an occupant model answers for (adults in the front outboard seats, PDOF",
        "inside a mode's coverage, delta-V, belt and injuries known; side airbags not reported,",
        "as in the file). Survey-weighted unless marked; 95 % intervals from "
        f"{BOOTSTRAP_REPLICATES} resamples of crashes (seed {BOOTSTRAP_SEED}).",
        "",
        "### Region by region: AUC",
        "",
        *_skill_table(rep),
        "",
        "### Calibration of the map",
        "",
        *_calibration_table(rep),
        "",
        "### AIS 6 by mode (unweighted shares of occupants)",
        "",
        *_ais_six_table(rep),
        "",
        "### Why the side models reach HIC15 in the thousands (item 4)",
        "",
        "The near-side model on a summary pulse (belted driver), at the IIHS side test's",
        "struck-car delta-V (18-31 km/h, mean 24 km/h over 49 tests: wbldb.lievers.net/01377)",
        "and beyond it, against the one published dummy result at hand (IIHS, 2007 Aveo with",
        "side airbags, SID-IIs 5F: `models/lpm/data/PUBLISHED_NCAP.md`, S4):",
        "",
        *side_table(rep.side),
        "",
        "### Item 5: calibrated physics",
        "",
        *_item_five_tables(rep),
        "",
        END,
    ]
    return "\n".join(lines)


def _full(rep: RegionReport) -> str:
    return "\n".join(
        [
            "# The occupant models region by region against real injuries",
            "",
            block(rep).replace(BEGIN, "").replace(END, ""),
            "",
            "## AUC by mode (weighted; positives in brackets)",
            "",
            *_mode_table(rep),
            "",
            "![regions](regions.png)",
            "",
        ]
    )


#: The occupant models' measured skill the case page states (shipped with the engine).
SKILL_PATH: Final[Path] = (
    Path(__file__).resolve().parents[2] / "injury" / "data" / ("occupant_model_field_skill.json")
)


def skill_document(rep: RegionReport) -> dict[str, object]:
    """What the case page says of the occupant models' body map, from this report."""
    regions: dict[str, dict[str, float | str]] = {}
    for rs in rep.skills:
        key = rs.spec.risk_region
        if key not in ("head", "thorax", "abdomen"):
            continue
        by = {s.label: s for s in rs.scores}
        regions[key] = {
            "ais_level": rs.spec.level,
            "auc_body_map": round(by["body map: region AIS"].auc.value, 3),
            "auc_delta_v": round(by["delta-V alone"].auc.value, 3),
        }
    six = next(r for r in rep.ais_six if r.mode == "all")
    return {
        "generated_by": "python -m models.offline.regions.report",
        "data": "NASS-CDS 1997-2014 (models/offline/data), occupants an occupant model answers",
        "occupants": int(len(rep.frame)),
        "auc_weighted": regions,
        "curves_ais6": {
            "share_of_occupants": round(six.model_ais6, 4),
            "real_mais5": round(six.agree_mais5, 3),
            "died": round(six.died, 3),
            "median_iss": six.median_iss,
        },
    }


def update_doc(text: str, path: Path) -> None:
    """Replace the block between the markers of `path` (appended when absent)."""
    doc = path.read_text(encoding="utf-8")
    if BEGIN in doc and END in doc:
        head, rest = doc.split(BEGIN, 1)
        _, tail = rest.split(END, 1)
        doc = head + text + tail
    else:
        doc = doc.rstrip("\n") + "\n\n" + text + "\n"
    path.write_text(doc, encoding="utf-8")


def main(argv: Sequence[str] | None = None) -> int:
    """Command line entry point."""
    from models.offline.regions.plot import plot_report

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--region-risk", type=Path, default=None)
    ap.add_argument("--out", type=Path, default=docs_dir("regions"))
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--no-doc", action="store_true", help="leave docs/occupant-models.md")
    args = ap.parse_args(list(argv) if argv is not None else None)
    rep = run_report(args.region_risk, args.workers)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "regions.md").write_text(_full(rep), encoding="utf-8")
    plot_report(rep.frame, rep.skills, rep.ais_six, rep.curves, args.out / "regions.png")
    SKILL_PATH.parent.mkdir(parents=True, exist_ok=True)
    SKILL_PATH.write_text(json.dumps(skill_document(rep), indent=2) + "\n", encoding="utf-8")
    if not args.no_doc:
        update_doc(block(rep), docs_dir("occupant-models.md"))
    sys.stdout.write(block(rep) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
