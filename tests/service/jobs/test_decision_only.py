"""A decision-only batch (``triage --batch --decision-only``): the full run's decision
fields, byte for byte, without running the occupant models."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from service.cli import main as cli
from tests.decision_pins import notifications


def _decision_fields(record: dict[str, Any]) -> bytes:
    """The answer's decision (the case's, the vehicle's, each occupant's) as JSON bytes."""
    result = record["result"]
    picked = {
        "triage": result["triage"],
        "vehicle": result.get("vehicle"),
        "occupants": [o["triage"] for o in result["occupants"]],
    }
    return json.dumps(picked, sort_keys=True).encode()


def _run(src: Path, out: Path, *extra: str) -> list[dict[str, Any]]:
    argv = ["triage", "--batch", str(src), "--out", str(out), "--workers", "1"]
    assert cli.main([*argv, "--reproducible", *extra]) == 0
    return [json.loads(line) for line in out.read_text().splitlines()]


def test_decision_only_gives_the_full_runs_decisions_without_the_occupant_models(
    tmp_path: Path,
) -> None:
    docs = list(notifications().values())  # side, rear, rollover, children, measured delta-V
    src = tmp_path / "in.jsonl"
    src.write_text("".join(json.dumps(d) + "\n" for d in docs))
    full = _run(src, tmp_path / "full.jsonl")
    fast = _run(src, tmp_path / "fast.jsonl", "--decision-only")
    assert len(full) == len(fast) == len(docs)
    assert all("result" in r for r in full + fast)
    assert [_decision_fields(r) for r in fast] == [_decision_fields(r) for r in full]

    explained = 0
    for a, b in zip(full, fast, strict=True):
        for occ_full, occ_fast in zip(
            a["result"]["occupants"], b["result"]["occupants"], strict=True
        ):
            assert occ_fast["method"] == "field"
            assert occ_fast["occupant_model"] is None
            assert occ_fast["measures"] is None
            if occ_full["method"] == "lpm":
                assert occ_full["occupant_model"] is not None
                explained += 1
        codes = [x["code"] for x in b["result"]["assumptions"]]
        lpm_seats = sum(o["method"] == "lpm" for o in a["result"]["occupants"])
        assert codes.count("occupant_models_not_run") == lpm_seats
        assert "occupant_models_not_run" not in [x["code"] for x in a["result"]["assumptions"]]
    assert explained > 5, "the full run explains many of these occupants"
