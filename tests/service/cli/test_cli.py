"""The `aacn-triage` command line, in process and as the installed console script."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import httpx2 as httpx
import pytest

from service.cli import main as cli
from service.db import migrate
from service.settings import get_settings
from tests.support import console_server, example, summary


@pytest.fixture
def env_db(monkeypatch: pytest.MonkeyPatch, sqlite_url: str) -> Iterator[str]:
    monkeypatch.setenv("AACN_DATABASE_URL", sqlite_url)
    get_settings.cache_clear()
    yield sqlite_url
    get_settings.cache_clear()


def test_keys_create_prints_the_key_once_and_stores_only_a_hash(
    env_db: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert cli.main(["keys", "create", "--role", "submitter", "--name", "center-a"]) == 0
    key = capsys.readouterr().out.strip()
    assert key.startswith("aacn_")
    assert len(key) > 40
    assert cli.main(["keys", "list"]) == 0
    listing = capsys.readouterr().out
    assert "center-a\tsubmitter" in listing
    assert key not in listing
    db_bytes = Path(env_db.removeprefix("sqlite:///")).read_bytes()
    assert key.encode() not in db_bytes
    assert cli.main(["keys", "create", "--role", "auditor", "--name", "center-a"]) == 1


def test_db_upgrade_downgrade_current(env_db: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["db", "upgrade"]) == 0
    assert f"revision {migrate.head_revision()}" in capsys.readouterr().out
    assert cli.main(["db", "downgrade", "base"]) == 0
    assert "revision base" in capsys.readouterr().out


def test_triage_one_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = tmp_path / "n.json"
    src.write_text(json.dumps(example("delta_v")))
    assert cli.main(["triage", str(src)]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["case_id"] is None
    assert len(result["occupants"]) == 2
    assert {o["impact_mode"] for o in result["occupants"]} == {"near_side", "far_side"}


def test_triage_refuses_a_bad_file_with_the_field(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    body = summary()
    body["crash"]["pulse"]["delta_v_kmh"] = 999
    src = tmp_path / "bad.json"
    src.write_text(json.dumps(body))
    assert cli.main(["triage", str(src)]) == 1
    assert "crash.pulse.delta_v_kmh" in capsys.readouterr().err


def test_batch_writes_one_line_per_input_and_resumes(tmp_path: Path) -> None:
    bodies = [summary(dv) for dv in (15, 30, 45, 60)]
    bad = summary()
    bad["occupants"] = []
    lines = (
        [json.dumps(b) for b in bodies[:2]]
        + [json.dumps(bad)]
        + [json.dumps(b) for b in bodies[2:]]
    )
    src, out = tmp_path / "in.jsonl", tmp_path / "out.jsonl"
    src.write_text("\n".join(lines) + "\n")
    assert cli.main(["triage", "--batch", str(src), "--out", str(out)]) == 0
    full = [json.loads(x) for x in out.read_text().splitlines()]
    assert [r["line"] for r in full] == [1, 2, 3, 4, 5]
    assert "error" in full[2]
    assert full[2]["error"]["errors"][0]["field"] == "occupants"
    assert all("result" in r for i, r in enumerate(full) if i != 2)

    # interrupted after two lines and a torn third: --resume redoes only the rest
    kept = out.read_text().splitlines()[:2]
    out.write_text("\n".join(kept) + '\n{"line": 3, "resu')
    assert cli.main(["triage", "--batch", str(src), "--out", str(out), "--resume"]) == 0
    resumed = [json.loads(x) for x in out.read_text().splitlines()]
    assert [r["line"] for r in resumed] == [1, 2, 3, 4, 5]
    assert resumed[:2] == full[:2], "kept lines are untouched"
    strip = ("received_at", "timings_ms")
    for a, b in zip(resumed, full, strict=True):
        if "result" in a:
            for k in strip:
                a["result"].pop(k)
                b["result"].pop(k)
        assert a == b


def test_batch_lines_end_at_newline_only_not_at_a_bare_cr(tmp_path: Path) -> None:
    """A bare CR is JSON whitespace: it splits no record and shifts no line number."""
    bodies = [summary(dv) for dv in (20, 35, 50)]
    with_cr = json.dumps(bodies[1]).replace(", ", ",\r", 3)
    assert "\r" in with_cr
    assert json.loads(with_cr) == bodies[1]
    src, out = tmp_path / "in.jsonl", tmp_path / "out.jsonl"
    src.write_bytes(
        (json.dumps(bodies[0]) + "\r\n" + with_cr + "\n" + json.dumps(bodies[2]) + "\n").encode()
    )
    assert cli.main(["triage", "--batch", str(src), "--out", str(out)]) == 0
    records = [json.loads(x) for x in out.read_text().splitlines()]
    assert [r["line"] for r in records] == [1, 2, 3]
    assert all("result" in r for r in records), [r.get("error") for r in records]
    assert [r["result"]["event_id"] for r in records] == [b["event_id"] for b in bodies]


def test_batch_pool_matches_one_process(tmp_path: Path) -> None:
    """`--workers 2` (a process pool) writes what one process writes, in input order."""
    bodies = [summary(dv, pdof) for dv in (12, 33, 51, 70) for pdof in (0, 90, 180)]
    src = tmp_path / "in.jsonl"
    src.write_text(
        "".join(json.dumps(b) + "\n" for b in bodies) + '{"event_id": 1, "event_id": 2}\n'
    )
    outs = []
    for workers in ("1", "2"):
        out = tmp_path / f"out{workers}.jsonl"
        argv = ["triage", "--batch", str(src), "--out", str(out), "--workers", workers]
        assert cli.main(argv) == 0
        records = [json.loads(x) for x in out.read_text().splitlines()]
        for r in records:
            if "result" in r:
                r["result"].pop("received_at")
                r["result"].pop("timings_ms")
        outs.append(records)
    assert [r["line"] for r in outs[1]] == list(range(1, len(bodies) + 2))
    assert outs[1][-1]["error"]["status"] == 400, "duplicate keys refused in batches too"
    assert outs[0] == outs[1]


def test_console_script_serves_real_http(tmp_path: Path) -> None:
    with console_server(tmp_path) as (_server, base, key, _log):
        h = {"Authorization": f"Bearer {key}"}
        for kind in ("summary", "delta_v", "acceleration"):
            body = example(kind)
            created = httpx.post(base + "/v1/cases", json=body, headers=h, timeout=30)
            assert created.status_code == 201, created.text
            got = httpx.get(base + created.headers["location"], headers=h, timeout=30)
            assert got.json()["result"] == created.json()
            assert got.json()["notification"] == body
            replay = httpx.post(base + "/v1/cases", json=body, headers=h, timeout=30)
            assert replay.status_code == 200
            assert replay.headers["idempotent-replayed"] == "true"
        assert httpx.post(base + "/v1/cases", json=body, timeout=30).status_code == 401


def test_simulate_prints_measures_and_draws_a_plot(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = tmp_path / "n.json"
    src.write_text(json.dumps(example("delta_v")))
    plot = tmp_path / "sim.png"
    assert cli.main(["simulate", str(src), "--plot", str(plot)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert [o["impact_mode"] for o in report["occupants"]] == ["near_side", "far_side"]
    for occupant, path in zip(report["occupants"], report["plots"], strict=True):
        assert occupant["measures"]["hic15"] > 0
        assert 0 <= occupant["iss"] <= 75
        assert Path(path).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_build_surrogates_receives_its_own_options(capsys: pytest.CaptureFixture[str]) -> None:
    """Options after ``build-surrogates`` reach the builder (argparse's REMAINDER
    alone dropped those starting with ``--``): an unknown family is refused by
    the builder itself, with exit code 2 and the known names, before any work."""
    assert cli.main(["build-surrogates", "--family", "no_such_family"]) == 2
    err = capsys.readouterr().err
    assert "unknown family ['no_such_family']" in err
    assert "frontal__male_50th__belted__airbag" in err
    with pytest.raises(SystemExit) as exc:
        cli.main(["build-surrogates", "--help"])
    assert exc.value.code == 0
    assert "--family" in capsys.readouterr().out


def test_validate_surrogates_receives_its_own_options(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``validate-surrogates`` hands its options to the validator: one family, a few
    points, another output directory; an unknown family is exit code 2."""
    rc = cli.main(
        [
            "validate-surrogates",
            "--family",
            "rear__female_5th__unbelted__airbag_any",
            "--n",
            "12",
            "--out",
            str(tmp_path),
            "--coverage-cases",
            "0",
        ]
    )
    assert rc in (0, 1)
    assert "[1/1] rear__female_5th__unbelted__airbag_any: 12 runs" in capsys.readouterr().err
    assert (tmp_path / "VALIDATION.md").is_file()
    assert cli.main(["validate-surrogates", "--family", "no_such_family"]) == 2
    assert "unknown family ['no_such_family']" in capsys.readouterr().err
    # a partial validation does not overwrite the shipped VALIDATION.md
    rear = "rear__male_50th__belted__airbag_any"
    assert cli.main(["validate-surrogates", "--family", rear]) == 2
    assert "--family needs --out DIR" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        cli.main(["validate-surrogates", "--help"])
    assert exc.value.code == 0
    assert "--seed" in capsys.readouterr().out
