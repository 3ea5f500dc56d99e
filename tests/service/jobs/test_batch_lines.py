"""A batch line is typed (its text, whether it was refused) and a job process loads its
engine models once per settings: the pool's summary counts the refused lines from that."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from service.cli import main as cli
from service.jobs.worker import models_for
from service.settings import get_settings
from tests.support import summary


def test_the_summary_counts_the_refused_lines(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = summary()
    bad["occupants"] = []
    lines = [json.dumps(summary(30)), "", "{not json", json.dumps(bad), '{"a": 1, "a": 2}']
    src, out = tmp_path / "in.jsonl", tmp_path / "out.jsonl"
    src.write_text("\n".join(lines) + "\n")
    assert cli.main(["triage", "--batch", str(src), "--out", str(out), "--workers", "1"]) == 0
    records = [json.loads(x) for x in out.read_text().splitlines()]
    assert [r["line"] for r in records] == [1, 2, 3, 4, 5]
    assert ["result" in r for r in records] == [True, False, False, False, False]
    assert [r["error"].get("status") for r in records[1:]] == [None, 400, 422, 400]
    assert records[1]["error"] == {"title": "Empty line"}
    assert "5 evaluated by 1 process, 4 refused" in capsys.readouterr().err


def test_a_process_loads_the_models_once_per_settings() -> None:
    settings = get_settings()
    first = models_for(settings)
    assert models_for(settings.model_copy()) is first, "the same settings: the same models"
    assert first.surrogates is not None


def test_a_decision_only_process_loads_no_surrogates() -> None:
    settings = get_settings()
    decision_only = models_for(settings, occupant_models=False)
    assert decision_only.surrogates is None, "a decision-only batch never runs them"
    assert models_for(settings, occupant_models=False) is decision_only
    assert models_for(settings) is not decision_only
