"""Research hand-overs: evaluate, simulate, baseline fit and the offline tools' own
commands (with ``research_dask``, the only modules that import ``models.offline``)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from service.cli.common import echo, load_settings

__all__ = ["HANDED_OVER", "cmd_evaluate", "cmd_simulate", "cmd_handed_over", "cmd_baseline"]


def _labelled_jsonl(
    path: Path, labels: Path | None, label_field: str, weight_field: str | None
) -> tuple[list[tuple[Any, bool, float]], int]:
    """Notifications of a JSON Lines file with their outcomes (engine form).

    The outcome (0/1) is the `label_field` of each line (removed before the
    notification is validated) or, with `labels`, the row of a CSV or JSON Lines
    file with the same ``event_id``. Returns the labelled notifications and the
    number of lines refused (invalid, or without a label).
    """
    import csv

    from service.cases.notification import CrashNotificationIn

    table: dict[str, dict[str, Any]] = {}
    if labels is not None:
        if labels.suffix.lower() == ".csv":
            with labels.open(newline="", encoding="utf-8") as fh:
                table = {r["event_id"]: dict(r) for r in csv.DictReader(fh)}
        else:
            for raw in labels.read_text(encoding="utf-8").splitlines():
                if raw.strip():
                    rec = json.loads(raw)
                    table[str(rec["event_id"])] = rec
    out: list[tuple[Any, bool, float]] = []
    refused = 0
    for raw in path.read_text(encoding="utf-8").splitlines():
        if not raw.strip():
            continue
        doc = json.loads(raw)
        label_doc = table.get(str(doc.get("event_id"))) if labels is not None else doc
        outcome = None if label_doc is None else label_doc.get(label_field)
        weight = 1.0
        if weight_field and label_doc is not None and label_doc.get(weight_field) is not None:
            weight = float(label_doc[weight_field])
        for key in (label_field, weight_field):
            if key:
                doc.pop(key, None)
        try:
            notification = CrashNotificationIn.model_validate(doc)
        except ValidationError:
            refused += 1
            continue
        if outcome is None or str(outcome) not in ("0", "1", "True", "False", "true", "false"):
            refused += 1
            continue
        engine_input, _ = notification.to_engine()
        out.append((engine_input, str(outcome) in ("1", "True", "true"), weight))
    return out, refused


def cmd_evaluate(args: argparse.Namespace) -> int:
    """Score labelled notifications: AUC, calibration, triage rates; Markdown + PNG."""
    from models.offline.field.evaluate import evaluate_notifications, write_evaluation
    from models.offline.field.rows import (
        load_calibration_rows,
        police_notification,
        row_notification,
    )
    from models.offline.field_check import field_cases

    load_settings()
    src = Path(args.file)
    weighted = False
    if src.suffix.lower() == ".csv":
        with src.open(encoding="utf-8") as fh:
            header = fh.readline()
        if "mais3pl" in header:
            labelled = [(row_notification(r), r.mais3, 1.0) for r in load_calibration_rows(src)]
        elif "injSeverity" in header:
            labelled = [
                (police_notification(c, i), c.serious, c.weight)
                for i, c in enumerate(field_cases(src))
            ]
            weighted = True
        else:
            echo(
                "error: a CSV must be the NASS-CDS MAIS calibration format (mais3pl) or the "
                "NASS-CDS 1997-2000 format (injSeverity); other data: JSON Lines",
                err=True,
            )
            return 2
        refused = 0
    else:
        labels = Path(args.labels) if args.labels else None
        labelled, refused = _labelled_jsonl(src, labels, args.label_field, args.weight_field)
        weighted = args.weight_field is not None
    if not labelled:
        echo("error: no labelled notification to score", err=True)
        return 1
    if args.scheduler:  # on a Dask cluster (service.cli.research_dask)
        from service.cli.research_dask import evaluate_on_dask

        cases = evaluate_on_dask(
            labelled, scheduler=args.scheduler, operating_point=args.operating_point
        )
    else:
        cases = evaluate_notifications(
            labelled, operating_point=args.operating_point, workers=args.workers
        )
    out = write_evaluation(
        cases, Path(args.out), title=f"Evaluation of {src.name}", weighted=weighted
    )
    echo(f"{len(cases)} scored, {refused} refused; report in {out}", err=True)
    return 0


def cmd_simulate(args: argparse.Namespace) -> int:
    """Run the occupant models of one notification; print the measures, draw the plot."""
    import dataclasses

    from models.offline.lpm.plot import plot_simulation
    from models.triage import UnknownVehicleModel, load_engine_models, simulate_notification
    from service.cases.notification import CrashNotificationIn
    from service.problems import problem_from_validation

    load_settings()
    try:
        notification = CrashNotificationIn.model_validate_json(
            Path(args.file).read_text(encoding="utf-8")
        )
    except ValidationError as exc:
        echo(json.dumps(problem_from_validation(exc), indent=2), err=True)
        return 1
    engine_input, notes = notification.to_engine()
    models = load_engine_models(use_surrogates=False)
    try:
        pulse, simulations, assumptions = simulate_notification(engine_input, models)
    except (UnknownVehicleModel, ValueError) as exc:
        echo(f"error: {exc}", err=True)
        return 1
    report: dict[str, Any] = {
        "event_id": engine_input.event_id,
        "delta_v_kmh": pulse.delta_v_kmh,
        "pdof_deg": pulse.pdof_deg,
        "assumptions": [
            {"code": a.code.value, "message": a.message, "occupant": a.occupant}
            for a in (*notes, *assumptions)
        ],
        "occupants": [],
    }
    plots = []
    for sim in simulations:
        entry: dict[str, Any] = {
            "seat": sim.occupant.seat.value,
            "impact_mode": sim.impact.mode.value,
            "in_lpm_coverage": sim.impact.in_lpm_coverage,
        }
        if sim.result is not None:
            r = sim.result
            entry["status"] = r.status
            entry["message"] = r.message
            entry["measures"] = {
                k: v for k, v in dataclasses.asdict(r.measures).items() if v is not None
            }
            if r.assessment is not None:
                entry["region_ais"] = dict(r.assessment.region_ais)
                entry["iss"] = r.assessment.iss
                entry["p_iss15"] = r.assessment.p_iss15
            if args.plot:
                out = Path(args.plot)
                if len(simulations) > 1:
                    out = out.with_name(f"{out.stem}-{sim.occupant.seat.value}{out.suffix}")
                plot_simulation(
                    r,
                    out,
                    body=sim.occupant.body,
                    title=f"{engine_input.event_id}: {sim.occupant.seat.value}, "
                    f"{sim.impact.mode.value}, {pulse.delta_v_kmh:.0f} km/h",
                )
                plots.append(str(out))
        report["occupants"].append(entry)
    report["plots"] = plots
    echo(json.dumps(report, indent=2))
    return 0


#: Commands handed over whole to an engine module's ``main(argv)``: argparse's
#: REMAINDER does not pass on arguments that start with "--" (``--family NAME``,
#: ``--help``), so ``main`` below hands them their arguments itself.
HANDED_OVER: dict[str, tuple[str, str]] = {
    "build-surrogates": (
        "models.offline.surrogate.command",
        "build the PCE surrogate artifacts (offline, resumable; numpy only, no chaospy)",
    ),
    "validate-surrogates": (
        "models.offline.surrogate.validate",
        "score the surrogates on fresh direct LPM runs (resumable)",
    ),
    "fit-field": (
        "models.offline.field.risk_command",
        "fit the field risk models (ISS 15+, body regions, vehicle) on NASS-CDS 1997-2014, "
        "validate them held out by crash and by year, write the artifact, model card and "
        "README figures (resumable)",
    ),
    "fit-field-mais3": (
        "models.offline.field.command",
        "refit the MAIS 3+ field model 2.0.0 (kept for recalls) and its model card",
    ),
}


def cmd_handed_over(command: str, argv: list[str]) -> int:
    import importlib

    module = importlib.import_module(HANDED_OVER[command][0])
    return int(module.main(argv) or 0)


def cmd_baseline(args: argparse.Namespace) -> int:
    from models.offline.baseline.fit import main as fit_main

    argv: list[str] = ["--seed", str(args.seed)]
    if args.data:
        argv += ["--data", args.data]
    if args.out:
        argv += ["--out", args.out]
    if args.fit_date:
        argv += ["--fit-date", args.fit_date]
    return int(fit_main(argv) or 0)
