"""Calibration command: seeded, resumable, writes a valid parameter set."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from models.lpm.params import ParameterSet, load_parameter_set
from models.offline.lpm.calibrate import DEFAULT_TARGETS, calibrate, load_cases

PARAMS = ["frontal.airbag.head_force=1500:3000"]


def test_calibration_is_seeded_and_resumable(params: ParameterSet, tmp_path: Path) -> None:
    cases = load_cases(DEFAULT_TARGETS[:1])
    a, cost_a = calibrate(
        tmp_path / "a",
        cases=cases,
        params=PARAMS,
        base=params,
        seed=3,
        maxiter=2,
        popsize=3,
        progress=False,
    )
    b, cost_b = calibrate(
        tmp_path / "b",
        cases=cases,
        params=PARAMS,
        base=params,
        seed=3,
        maxiter=2,
        popsize=3,
        progress=False,
    )
    assert cost_a == cost_b
    assert a["frontal.airbag.head_force"] == b["frontal.airbag.head_force"]
    assert np.isfinite(cost_a)
    # resume: one more generation from the saved population
    st = np.load(tmp_path / "a" / "state.npz")
    assert int(st["nit"]) == 2
    c, cost_c = calibrate(
        tmp_path / "a",
        cases=cases,
        params=PARAMS,
        base=params,
        seed=3,
        maxiter=3,
        popsize=3,
        resume=True,
        progress=False,
    )
    assert int(np.load(tmp_path / "a" / "state.npz")["nit"]) == 3
    assert cost_c <= cost_a + 1e-12
    fitted = load_parameter_set(path=tmp_path / "a" / f"{c.name}.json")
    assert fitted["frontal.airbag.head_force"] == c["frontal.airbag.head_force"]
    assert "calibrated" in fitted.entries["frontal.airbag.head_force"].source
    assert (tmp_path / "a" / "report.md").read_text().count("|") > 10
    json.loads((tmp_path / "a" / f"{c.name}.json").read_text())
