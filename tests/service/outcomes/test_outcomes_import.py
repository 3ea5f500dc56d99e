"""`aacn-triage outcomes import FILE.csv [--dry-run]`: every refused line named, the file
taken whole or not at all; keyed by case id or by client, event id and seat."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from service.cli import main as cli
from service.settings import get_settings
from tests.support import ApiClient, post_case, summary


@pytest.fixture
def env_api(api: ApiClient, monkeypatch: pytest.MonkeyPatch) -> Iterator[ApiClient]:
    """The app, and the command line on the same database."""
    monkeypatch.setenv("AACN_DATABASE_URL", api.settings.database_url)
    get_settings.cache_clear()
    yield api
    get_settings.cache_clear()


def _history(api: ApiClient, case_id: str, seat: str = "driver") -> list[dict[str, Any]]:
    r = api.client.get(
        f"/v1/cases/{case_id}/occupants/{seat}/outcome", headers=api.headers("auditor")
    )
    if r.status_code == 404:
        return []
    assert r.status_code == 200, r.text
    history: list[dict[str, Any]] = r.json()["history"]
    return history


HEADER = "case_id,client,event_id,seat,iss,mais,died,disposition,source,recorded_at,weight\n"


def _cases(api: ApiClient, n: int) -> list[dict[str, Any]]:
    return [post_case(api, summary(event_id=f"import-{i}")) for i in range(n)]


def test_a_good_file_is_imported_by_case_id_and_by_event(
    env_api: ApiClient, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    a, b = _cases(env_api, 2)
    src = tmp_path / "extract.csv"
    src.write_text(
        HEADER
        + f"{a['case_id']},,,driver,17,3,false,admitted_icu,trauma_registry,2026-12-01T10:00Z,\n"
        + ",submitter-client,import-1,driver,4,2,no,discharged_from_ed,hospital,"
        "2026-12-02T10:00Z,12.5\n"
    )
    assert cli.main(["outcomes", "import", str(src), "--dry-run"]) == 0
    assert "dry run: 2 lines good (2 new" in capsys.readouterr().out
    assert _history(env_api, a["case_id"]) == []  # the dry run wrote nothing
    assert cli.main(["outcomes", "import", str(src), "--by", "registry of county X"]) == 0
    assert "imported 2 lines (2 new" in capsys.readouterr().out
    (first,) = _history(env_api, a["case_id"])
    assert (first["iss"], first["channel"], first["written_by"]) == (
        17,
        "import",
        "registry of county X",
    )
    (second,) = _history(env_api, b["case_id"])
    assert (second["iss"], second["weight"], second["died"]) == (4, 12.5, False)
    # the same file again changes nothing; a corrected line is a new revision
    assert cli.main(["outcomes", "import", str(src)]) == 0
    assert "2 unchanged" in capsys.readouterr().out
    assert len(_history(env_api, a["case_id"])) == 1
    src.write_text(
        HEADER + f"{a['case_id']},,,driver,22,3,false,admitted_icu,trauma_registry,"
        "2026-12-01T10:00Z,\n"
    )
    assert cli.main(["outcomes", "import", str(src)]) == 0
    assert "1 correction" in capsys.readouterr().out
    assert [h["iss"] for h in _history(env_api, a["case_id"])] == [17, 22]


def test_one_bad_line_refuses_the_whole_file_naming_each_bad_line(
    env_api: ApiClient, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (a,) = _cases(env_api, 1)
    good = f"{a['case_id']},,,driver,17,3,,,trauma_registry,2026-12-01T10:00Z,\n"
    bad_lines = {
        3: ("no-such-case,,,driver,17,3,,,trauma_registry,2026-12-01T10:00Z,\n", "case_id"),
        4: (",submitter-client,nope,driver,17,3,,,ems,2026-12-01T10:00Z,\n", "event_id"),
        5: (f"{a['case_id']},,,rear_left,9,3,,,ems,2026-12-01T10:00Z,\n", "no occupant"),
        6: (f"{a['case_id']},,,sunroof,9,3,,,ems,2026-12-01T10:00Z,\n", "seat"),
        7: (f"{a['case_id']},,,driver,15,,,,ems,2026-12-01T10:00Z,\n", "ISS 15 cannot occur"),
        8: (f"{a['case_id']},,,driver,80,,,,ems,2026-12-01T10:00Z,\n", "iss"),
        9: (f"{a['case_id']},,,driver,9,,maybe,,ems,2026-12-01T10:00Z,\n", "died"),
        10: (f"{a['case_id']},,,driver,9,,,,ems,2026-12-01T10:00Z,-1\n", "weight"),
        11: (good, "same occupant as line 2"),
    }
    src = tmp_path / "extract.csv"
    src.write_text(HEADER + good + "".join(text for text, _ in bad_lines.values()))
    assert cli.main(["outcomes", "import", str(src)]) == 1
    err = capsys.readouterr().err
    for line, (_, reason) in bad_lines.items():
        refusal = next(x for x in err.splitlines() if x.startswith(f"extract.csv:{line}:"))
        assert reason in refusal, (line, refusal)
    assert "extract.csv:2:" not in err  # the good line is not refused...
    assert "9 of 10 lines refused: nothing imported" in err
    assert _history(env_api, a["case_id"]) == []  # ...but not written either


def test_a_file_that_is_not_an_extract(
    env_api: ApiClient, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = tmp_path / "x.csv"
    src.write_text("case_id,seat,colour\n1,driver,red\n")
    assert cli.main(["outcomes", "import", str(src)]) == 2
    assert "unknown column(s) colour" in capsys.readouterr().err
    src.write_text("seat,iss\ndriver,9\n")
    assert cli.main(["outcomes", "import", str(src)]) == 2
    assert "missing column(s): source, recorded_at, case_id" in capsys.readouterr().err
