"""``aacn-triage evaluate``: the decision scored against labelled notifications."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from models.offline.field.metrics import auc, triage_rates
from models.offline.field.rows import (
    CALIBRATION_CSV,
    CalibrationRow,
    load_calibration_rows,
    row_notification,
)
from models.triage import load_engine_models, triage
from service.cli.main import main


def _rows() -> list[CalibrationRow]:
    """60 rows with 12 positives, every crash mode (seeded)."""
    rows = load_calibration_rows()
    rng = np.random.default_rng(7)
    pos = [r for r in rows if r.mais3]
    neg = [r for r in rows if not r.mais3]
    pick = [pos[i] for i in rng.choice(len(pos), 12, replace=False)]
    pick += [neg[i] for i in rng.choice(len(neg), 48, replace=False)]
    return sorted(pick, key=lambda r: r.row)


def _wire(row: CalibrationRow) -> dict[str, Any]:
    """The row as a call center would POST it (the wire contract)."""
    n = row_notification(row)
    o = n.occupants[0]
    return {
        "event_id": n.event_id,
        "occurred_at": "2026-12-01T10:00:00Z",
        "vehicle": {"model": n.vehicle_model, "drive_side": n.drive_side.value},
        "crash": {
            "pulse": {
                "kind": "summary",
                "delta_v_kmh": row.delta_v_kmh,
                "pdof_deg": row.pdof_deg,
            },
            "multiple_impacts": n.multiple_impacts,
            "rollover": n.rollover,
        },
        "occupants": [
            {
                "seat": o.seat.value,
                "stature_cm": row.stature_cm,
                "mass_kg": row.mass_kg,
                "age_years": row.age_years,
                "belted": row.belted,
                "frontal_airbag": o.frontal_airbag.value,
            }
        ],
    }


@pytest.fixture(scope="module")
def expected() -> dict[str, Any]:
    models = load_engine_models()
    rows = _rows()
    y = np.array([r.mais3 for r in rows], dtype=float)
    results = [triage(row_notification(r), models) for r in rows]
    p = np.array([res.triage.probability for res in results])
    flags = np.array([res.triage.iss15_plus for res in results])
    return {"rows": rows, "y": y, "p": p, "flags": flags}


def _overall(report: str) -> tuple[float, float, float]:
    """AUC, and the decided operating point's sensitivity and flagged share, of the 'all' rows."""
    auc_row = re.search(r"^\| all \| \d+ \| \d+ \| ([0-9.]+) ", report, re.M)
    assert auc_row is not None, report
    decided = report.split("Operating point `decided`")[1]
    rates = re.search(r"^\| all \| ([0-9.]+) % .*?\| ([0-9.]+) % ", decided, re.M)
    assert rates is not None, decided
    return float(auc_row.group(1)), float(rates.group(1)), float(rates.group(2))


def test_evaluate_scores_a_labelled_jsonl_as_the_service_answers(
    tmp_path: Path, expected: dict[str, Any]
) -> None:
    src = tmp_path / "cases.jsonl"
    with src.open("w", encoding="utf-8") as fh:
        for r in expected["rows"]:
            fh.write(json.dumps({**_wire(r), "outcome": int(r.mais3)}) + "\n")
        fh.write(json.dumps({"event_id": "broken", "outcome": 1}) + "\n")  # refused, counted
    out = tmp_path / "report"
    assert main(["evaluate", str(src), "--out", str(out), "--workers", "1"]) == 0
    report = (out / "evaluation.md").read_text(encoding="utf-8")
    assert (out / "evaluation_reliability.png").stat().st_size > 10_000
    got_auc, sens, flagged = _overall(report)
    y, p, flags = expected["y"], expected["p"], expected["flags"]
    assert got_auc == pytest.approx(auc(y, p), abs=5e-4)
    rates = triage_rates(y, flags)
    assert sens == pytest.approx(100 * rates.sensitivity, abs=0.05)
    assert flagged == pytest.approx(100 * rates.flagged, abs=0.05)
    for name in ("sens85", "acs_cot"):  # the shipped ISS 15+ model's operating points
        assert f"Operating point `{name}`" in report
    assert "calibration intercept" in report


def test_evaluate_takes_labels_from_a_separate_file(
    tmp_path: Path, expected: dict[str, Any]
) -> None:
    src = tmp_path / "cases.jsonl"
    labels = tmp_path / "labels.csv"
    src.write_text("".join(json.dumps(_wire(r)) + "\n" for r in expected["rows"]))
    with labels.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["event_id", "mais3"])
        for r in expected["rows"]:
            w.writerow([f"calibration-{r.row}", int(r.mais3)])
    out = tmp_path / "report"
    code = main(
        [
            "evaluate",
            str(src),
            "--labels",
            str(labels),
            "--label-field",
            "mais3",
            "--out",
            str(out),
            "--workers",
            "1",
        ]
    )
    assert code == 0
    got_auc, _, _ = _overall((out / "evaluation.md").read_text(encoding="utf-8"))
    assert got_auc == pytest.approx(auc(expected["y"], expected["p"]), abs=5e-4)


def test_evaluate_reads_the_nass_calibration_format(
    tmp_path: Path, expected: dict[str, Any]
) -> None:
    lines = CALIBRATION_CSV.read_text(encoding="utf-8").splitlines()
    wanted = {str(r.row) for r in expected["rows"]}
    src = tmp_path / "subset.csv"
    src.write_text(
        "\n".join([lines[0], *(ln for ln in lines[1:] if ln.split(",")[0] in wanted)]) + "\n"
    )
    out = tmp_path / "report"
    assert main(["evaluate", str(src), "--out", str(out), "--workers", "1"]) == 0
    got_auc, _, _ = _overall((out / "evaluation.md").read_text(encoding="utf-8"))
    assert got_auc == pytest.approx(auc(expected["y"], expected["p"]), abs=5e-4)


def test_evaluate_refuses_an_unknown_csv(tmp_path: Path) -> None:
    src = tmp_path / "x.csv"
    src.write_text("a,b\n1,2\n")
    assert main(["evaluate", str(src), "--out", str(tmp_path / "r")]) == 2
