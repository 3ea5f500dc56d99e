"""``aacn-triage fit-field``: fit the field risk models, write the artifact and the model card.

Shows progress (tqdm) and caches each stage (``--cache``, default
``.cache/fit-field``): an interrupted fit re-run with the same settings resumes
at the stage it stopped in.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from models.field.risk_model import default_artifact_path
from models.offline.field.risk_fit import RiskConfig
from models.offline.field.risk_run import fit_risk

__all__ = ["main", "write_risk_artifact"]


def write_risk_artifact(doc: dict[str, object], path: Path | None = None) -> Path:
    """Write the artifact document (indented JSON, LF) and return its path."""
    out = default_artifact_path() if path is None else path
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n", encoding="utf-8")
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """``aacn-triage fit-field``: fit, write the artifact and the model card."""
    from models.offline.field.risk_report import default_report_dir, write_risk_model_card

    parser = argparse.ArgumentParser(
        prog="aacn-triage fit-field", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--out", type=Path, default=None, help="report directory (docs/field)")
    parser.add_argument("--artifact", type=Path, default=None, help="artifact path (shipped)")
    parser.add_argument(
        "--cache", type=Path, default=Path(".cache/fit-field"), help="stage cache directory"
    )
    parser.add_argument("--no-cache", action="store_true", help="recompute every stage")
    parser.add_argument(
        "--heldout-csv",
        type=Path,
        default=None,
        help="also write every occupant's held-out (out-of-fold) probabilities, keyed by "
        "year, psu, caseno, vehno, occno (columns iss15, region_risk_<region>): the region "
        "report's --region-risk input",
    )
    parser.add_argument(
        "--quick", action="store_true", help="a fifth of the crashes, few refits (a smoke run)"
    )
    parser.add_argument(
        "--regions-from",
        default=None,
        metavar="VERSION",
        help="refit the decision (ISS 15+) only and carry the region models of the shipped "
        "artifact of VERSION (models/offline/field/risk_decision.py); reuses the stage cache",
    )
    parser.add_argument(
        "--selection-from",
        default=None,
        metavar="VERSION",
        help="with --regions-from: take the drift choice and the ISS 15+ selection (groups, "
        "penalty, kind, trees) of the shipped artifact of VERSION instead of re-running the "
        "selection; every fold's model, the children's calibration and the figures are refitted",
    )
    parser.add_argument(
        "--check-measured",
        action="store_true",
        help="run only the held-out measured-delta-V check of the shipped artifact (no refit): "
        "writes docs/field/measured_check.json and the model card's and README's text from it",
    )
    args = parser.parse_args(argv)
    if args.check_measured:
        return _check_measured(
            args.out or default_report_dir(), None if args.no_cache else args.cache
        )
    cfg = (
        RiskConfig(subsample=0.2, n_bootstrap=5, n_metric_bootstrap=30, n_splits=3)
        if args.quick
        else RiskConfig()
    )
    cache = None if args.no_cache else args.cache
    if args.selection_from is not None and args.regions_from is None:
        parser.error("--selection-from needs --regions-from (a decision-only refit)")
    if args.regions_from is not None:
        from models.offline.field.risk_decision import fit_decision

        fit = fit_decision(cfg, cache, args.regions_from, args.selection_from)
    else:
        fit = fit_risk(cfg, cache_dir=cache)
    path = write_risk_artifact(fit.artifact, args.artifact)
    card = write_risk_model_card(fit, args.out or default_report_dir())
    sys.stderr.write(f"artifact: {path}\nmodel card: {card}\n")
    check = fit.figures.get("measured_check")
    if check is not None:
        from models.offline.field.risk_measured import CHECK_FILE, write_check

        written = write_check(check, (args.out or default_report_dir()) / CHECK_FILE)
        sys.stderr.write(f"measured-delta-V check: {written}\n")
    if args.heldout_csv is not None:
        keys = fit.data.rows[["year", "psu", "caseno", "vehno", "occno"]].copy()
        for name, p in fit.oof.items():
            keys[name if name == "iss15" else name.replace("region_", "region_risk_")] = p
        args.heldout_csv.parent.mkdir(parents=True, exist_ok=True)
        keys.to_csv(args.heldout_csv, index=False)
        sys.stderr.write(f"held-out probabilities: {args.heldout_csv}\n")
    if args.artifact is None and not args.quick:
        # the shipped artifact: the README's figures and example answer follow it
        from models.offline.field.readme import example_answer, readme_block, update_readme

        readme = update_readme(readme_block(fit.artifact, example_answer(fit.artifact), check))
        sys.stderr.write(f"README figures: {readme or 'no README with the markers'}\n")
    return 0


def _check_measured(out_dir: Path, cache: Path | None) -> int:
    """``fit-field --check-measured``: the check of the shipped artifact, its card and README."""
    from models.offline.field.readme import example_answer, readme_block, update_readme
    from models.offline.field.risk_decision import check_served
    from models.offline.field.risk_measured import CHECK_FILE, write_check
    from models.offline.field.risk_report import rewrite_card_text

    doc = json.loads(default_artifact_path().read_text(encoding="utf-8"))
    check = check_served(doc, cache)
    written = write_check(check, out_dir / CHECK_FILE)
    card = rewrite_card_text(doc, check, out_dir)
    readme = update_readme(readme_block(doc, example_answer(doc), check))
    sys.stderr.write(
        f"measured-delta-V check: {written}\nmodel card: {card}\n"
        f"README figures: {readme or 'no README with the markers'}\n"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
