"""Readiness follows what the surrogates depend on, not the bytes of the code.

On a copy of the engine, run by the real service in a fresh interpreter:
reformatting every file and editing a docstring of the kernel leave /readyz
200 with the shipped artifacts; changing a physical parameter value, or a
number of the injury risk curves, makes it 503 with the reason.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from models.lpm.params import load_parameter_set
from models.surrogate.evaluate import SurrogateLibrary
from models.surrogate.golden import golden_mismatch
from models.surrogate.spec import FAMILIES
from tests.paths import ROOT

#: Runs the service on the engine copy in the working directory; prints /readyz.
_READYZ = """
import json, sys
from fastapi.testclient import TestClient
import models
from service.app import create_app
from service.settings import Settings
assert models.__file__.startswith(sys.argv[2]), models.__file__
app = create_app(Settings(database_url="sqlite:///" + sys.argv[1]))
with TestClient(app) as client:
    r = client.get("/readyz")
print(json.dumps({"status": r.status_code, "body": r.json()}))
"""


@pytest.fixture(scope="module")
def engine_copy(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("engine")
    shutil.copytree(ROOT / "models", root / "models", ignore=shutil.ignore_patterns("__pycache__"))
    return root


def _readyz(root: Path, tmp: Path) -> dict[str, object]:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(root / ".numba")}
    out = subprocess.run(
        [sys.executable, "-c", _READYZ, str(tmp / "ready.db"), str(root)],
        cwd=root,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert out.returncode == 0, out.stderr[-3000:]
    result: dict[str, object] = json.loads(out.stdout.strip().splitlines()[-1])
    (tmp / "ready.db").unlink(missing_ok=True)
    return result


def test_the_shipped_library_is_current() -> None:
    lib = SurrogateLibrary.load()
    assert lib.stale_reason() is None
    golden = lib.manifest["golden"]
    assert set(golden["cases"]) == {s.name for s in FAMILIES}
    assert golden_mismatch(golden, {s.name: s for s in FAMILIES}, load_parameter_set()) is None


def test_a_changed_parameter_value_is_a_change_of_physics() -> None:
    """In process: any parameter value (here one mass by 1 %) makes the library stale."""
    ps = load_parameter_set()
    key = "body.male_50th.mass.pelvis"
    moved = ps.with_values({key: ps[key] * 1.01})
    golden = SurrogateLibrary.load().manifest["golden"]
    reason = golden_mismatch(golden, {s.name: s for s in FAMILIES}, moved)
    assert reason is not None
    assert "parameter values" in reason
    # a source text or the file's layout is not a value
    assert ps.with_values({}, note="reworded").values_sha256 == ps.values_sha256


def test_reformatting_and_a_kernel_docstring_keep_the_service_ready(
    engine_copy: Path, tmp_path: Path
) -> None:
    kernel = engine_copy / "models" / "lpm" / "kernel.py"
    text = kernel.read_text(encoding="utf-8")
    kernel.write_text(text.replace('"""', '"""Edited docstring. ', 1), encoding="utf-8")
    before = {p: p.read_text() for p in (engine_copy / "models").rglob("*.py")}
    subprocess.run(
        [sys.executable, "-m", "ruff", "format", "--quiet", "--line-length", "79", "models"],
        cwd=engine_copy,
        check=True,
    )
    changed = [p for p, t in before.items() if p.read_text() != t]
    assert len(changed) > 20, "the reformat changed the layout of many files"
    result = _readyz(engine_copy, tmp_path)
    assert result["status"] == 200, result


def test_a_changed_parameter_value_makes_the_service_not_ready(
    engine_copy: Path, tmp_path: Path
) -> None:
    path = engine_copy / "models" / "lpm" / "data" / "compact_sedan.json"
    original = path.read_text(encoding="utf-8")
    doc = json.loads(original)
    doc["parameters"]["body.male_50th.mass.pelvis"]["value"] *= 1.01
    path.write_text(json.dumps(doc, indent=1), encoding="utf-8")
    try:
        result = _readyz(engine_copy, tmp_path)
    finally:
        path.write_text(original, encoding="utf-8")
    assert result["status"] == 503, result
    assert "parameter values" in json.dumps(result["body"])


def test_a_changed_risk_curve_makes_the_service_not_ready(
    engine_copy: Path, tmp_path: Path
) -> None:
    """A change of physics in code (a number of a published risk curve) is seen by the
    golden cases, with the case and the output named."""
    path = engine_copy / "models" / "injury" / "risk.py"
    original = path.read_text(encoding="utf-8")
    edited = original.replace(
        "VC_RISK_SLOPE_RATIO: Final[float] = 1.3", "VC_RISK_SLOPE_RATIO: Final[float] = 1.6"
    )
    assert edited != original
    path.write_text(edited, encoding="utf-8")
    try:
        result = _readyz(engine_copy, tmp_path)
    finally:
        path.write_text(original, encoding="utf-8")
    assert result["status"] == 503, result
    assert "golden case" in json.dumps(result["body"])
