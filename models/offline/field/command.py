"""``aacn-triage fit-field-mais3``: refit the MAIS 3+ field model 2.0.0 (kept for recalls).

The decision's model is the ISS 15+ field risk model (``aacn-triage fit-field``,
:mod:`.risk_command`); this refits the MAIS 3+ model it replaced, its artifact
(``--artifact``, default the shipped ``field_mais3.json``) and its model card
(``docs/field/mais3/``).

The orchestration of :mod:`.fit` (the fit and its cross-validation) and
:mod:`.report` (the model card); neither imports this module.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from models.offline.field.fit import FitConfig, fit_field, write_artifact
from models.offline.field.report import default_report_dir, write_model_card

__all__ = ["main"]


def main(argv: Sequence[str] | None = None) -> int:
    """``aacn-triage fit-field-mais3``: refit 2.0.0, write the artifact and the model card."""
    parser = argparse.ArgumentParser(
        prog="aacn-triage fit-field-mais3", description=__doc__.split("\n")[0]
    )
    parser.add_argument(
        "--out", type=Path, default=None, help="report directory (default docs/field/mais3)"
    )
    parser.add_argument(
        "--artifact", type=Path, default=None, help="artifact path (default: shipped)"
    )
    parser.add_argument("--cache", type=Path, default=None, help="engine-run cache directory")
    parser.add_argument("--workers", type=int, default=None, help="processes (default CPU count)")
    parser.add_argument("--quick", action="store_true", help="few repeats and refits (a smoke run)")
    args = parser.parse_args(argv)
    cfg = FitConfig(n_repeats=2, n_bootstrap=20, n_metric_bootstrap=200) if args.quick else None
    fit = fit_field(cfg, cache_dir=args.cache, workers=args.workers)
    path = write_artifact(fit.artifact, args.artifact)
    card = write_model_card(fit, args.out or default_report_dir())
    sys.stderr.write(f"artifact: {path}\nmodel card: {card}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
