"""The batch commands on a Dask cluster give the local pool's results.

A real ``dask.distributed`` cluster on loopback (a scheduler and two worker
processes, `LocalCluster`) runs ``aacn-triage triage --batch --scheduler`` and
``aacn-triage evaluate --scheduler``; the same inputs go through the local process
pool. The batch answers are the same bytes line for line, once the two fields that
differ between any two runs are set aside (``received_at``, the wall-clock time of
the answer, and ``timings_ms``); Parquet input gives what JSON Lines gives;
``--resume`` continues an interrupted Dask run; the evaluation report is the same
file, byte for byte.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from datetime import datetime
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from distributed import LocalCluster

from models.offline.field.rows import CALIBRATION_CSV
from service.cli import main as cli
from tests.support import example, summary

#: Fields of a batch answer that differ between any two runs, local or not.
PER_RUN = ("received_at", "timings_ms")
#: Calibration rows scored by the evaluation test (every k-th of the shipped file).
EVALUATE_EVERY = 60


@pytest.fixture(scope="module")
def scheduler() -> Iterator[str]:
    """The address of a local Dask cluster: two single-threaded worker processes."""
    with LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=":0",
    ) as cluster:
        yield cluster.scheduler_address


def _bodies() -> list[str]:
    texts = [json.dumps(summary(dv, pdof)) for dv in (12, 33, 51, 70) for pdof in (0, 90, 270)]
    texts += [json.dumps(example("delta_v")), json.dumps(example("acceleration"))]
    bad = summary()
    bad["occupants"] = []
    return [*texts[:5], json.dumps(bad), "", *texts[5:], '{"event_id": 1, "event_id": 2}']


def _instant(text: str) -> datetime:
    return datetime.fromisoformat(text.replace("Z", "+00:00"))


def _comparable(out: Path) -> list[str]:
    """The output's lines as bytes, without the per-run fields."""
    lines = []
    for raw in out.read_text(encoding="utf-8").splitlines():
        record = json.loads(raw)
        for key in PER_RUN:
            record.get("result", {}).pop(key, None)
        lines.append(json.dumps(record, separators=(",", ":")))
    return lines


def test_triage_batch_on_dask_matches_the_local_pool(scheduler: str, tmp_path: Path) -> None:
    texts = _bodies()
    src = tmp_path / "in.jsonl"
    src.write_text("".join(t + "\n" for t in texts), encoding="utf-8")
    local, dask, parquet_out = (tmp_path / f"{n}.jsonl" for n in ("local", "dask", "parquet"))
    assert cli.main(["triage", "--batch", str(src), "--out", str(local), "--workers", "2"]) == 0
    argv = ["triage", "--batch", str(src), "--out", str(dask), "--scheduler", scheduler]
    assert cli.main(argv) == 0
    expected = _comparable(local)
    assert len(expected) == len(texts)
    assert _comparable(dask) == expected
    records = [json.loads(x) for x in expected]
    assert [r["line"] for r in records] == list(range(1, len(texts) + 1))
    assert sum("error" in r for r in records) == 3, "invalid, empty, repeated keys"

    # --reproducible: nothing of the run in the answers, so the two are byte-identical
    local_r, dask_r = tmp_path / "local-r.jsonl", tmp_path / "dask-r.jsonl"
    argv_r = ["triage", "--batch", str(src), "--reproducible"]
    assert cli.main([*argv_r, "--out", str(local_r), "--workers", "2"]) == 0
    assert cli.main([*argv_r, "--out", str(dask_r), "--scheduler", scheduler]) == 0
    assert dask_r.read_bytes() == local_r.read_bytes()
    assert [json.loads(x) for x in local_r.read_text().splitlines()] != [], "answers written"
    first = json.loads(local_r.read_text().splitlines()[0])["result"]
    assert first["timings_ms"] == {}
    crash_time = json.loads(texts[0])["occurred_at"]
    assert _instant(first["received_at"]) == _instant(crash_time)

    # the same notifications as Parquet (a `notification` column of JSON text)
    src_pq = tmp_path / "in.parquet"
    pq.write_table(pa.table({"notification": texts}), src_pq, row_group_size=4)
    argv = ["triage", "--batch", str(src_pq), "--out", str(parquet_out), "--scheduler", scheduler]
    assert cli.main(argv) == 0
    assert _comparable(parquet_out) == expected

    # interrupted after three lines and a torn fourth: --resume redoes only the rest
    kept = dask.read_text(encoding="utf-8").splitlines()[:3]
    dask.write_text("".join(k + "\n" for k in kept) + '{"line": 4, "resu', encoding="utf-8")
    assert cli.main([*argv[:3], str(src), "--out", str(dask), "--resume", *argv[5:]]) == 0
    assert dask.read_text(encoding="utf-8").splitlines()[:3] == kept, "kept lines untouched"
    assert _comparable(dask) == expected


def test_evaluate_on_dask_writes_the_local_report(scheduler: str, tmp_path: Path) -> None:
    lines = CALIBRATION_CSV.read_text(encoding="utf-8").splitlines()
    src = tmp_path / "sample.csv"
    src.write_text("\n".join([lines[0], *lines[1::EVALUATE_EVERY]]) + "\n", encoding="utf-8")
    local, dask = tmp_path / "local", tmp_path / "dask"
    assert cli.main(["evaluate", str(src), "--out", str(local), "--workers", "2"]) == 0
    assert cli.main(["evaluate", str(src), "--out", str(dask), "--scheduler", scheduler]) == 0
    report = (local / "evaluation.md").read_bytes()
    assert b"AUC" in report
    assert (dask / "evaluation.md").read_bytes() == report
