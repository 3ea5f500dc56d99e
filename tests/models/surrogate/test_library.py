"""Artifacts: round trip, checksum verification, determinism, propagation."""

from __future__ import annotations

import json
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from models.impact_mode import ImpactMode
from models.notification import Body
from models.offline.surrogate.build import (
    BuildConfig,
    build_family,
    is_current,
    write_manifest,
)
from models.offline.surrogate.command import main
from models.surrogate.evaluate import SurrogateFamily, SurrogateLibrary
from models.surrogate.store import read_artifact
from tests.models.surrogate.tiny import TINY_DELTA_V, TINY_NAME, tiny_spec

NOMINAL = {
    "delta_v_kmh": 50.0,
    "angle_deg": 10.0,
    "posture_deg": 8.0,
    "seat_track_mm": 20.0,
    "duration_ms": 90.0,
}


def _family(d: Path) -> SurrogateFamily:
    lib = SurrogateLibrary.load(d, require_all=False)
    return lib.family(ImpactMode.FRONTAL, Body.MALE_50TH, True, True)


def test_round_trip(tiny_library_dir: Path) -> None:
    lib = SurrogateLibrary.load(tiny_library_dir, require_all=False)
    assert lib.family_names == (TINY_NAME,)
    manifest = json.loads((tiny_library_dir / "manifest.json").read_text())
    assert lib.lpm_code_sha256 == manifest["lpm_code_sha256"]
    assert lib.parameter_set_sha256 == manifest["parameter_set_sha256"]
    assert lib.stale_reason() is None
    fam = lib.family(ImpactMode.FRONTAL, Body.MALE_50TH, True, True)
    arrays, meta = read_artifact(tiny_library_dir / f"{TINY_NAME}.npz")
    again = SurrogateFamily.from_arrays(arrays, meta)
    x = arrays["heldout_x"]
    np.testing.assert_array_equal(fam.predict(x), again.predict(x))
    assert fam.n_bootstrap == 150
    assert meta["config"]["seed"] == 7
    for key in ("lpm_code_sha256", "parameter_set_sha256", "engine_version"):
        assert meta[key] == manifest[key]
    with pytest.raises(AttributeError):
        fam.name = "x"  # type: ignore[misc]


def test_missing_family_and_complete_library(tiny_library_dir: Path) -> None:
    lib = SurrogateLibrary.load(tiny_library_dir, require_all=False)
    with pytest.raises(KeyError):
        lib.family(ImpactMode.REAR, Body.MALE_50TH, True, False)
    with pytest.raises(ValueError, match="families missing"):
        SurrogateLibrary.load(tiny_library_dir)


def test_tampered_file_is_rejected(tiny_library_dir: Path, tmp_path: Path) -> None:
    d = tmp_path / "lib"
    shutil.copytree(tiny_library_dir, d)
    path = d / f"{TINY_NAME}.npz"
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x01
    path.write_bytes(bytes(data))
    with pytest.raises(ValueError, match="checksum mismatch"):
        SurrogateLibrary.load(d, require_all=False)
    path.unlink()
    with pytest.raises(ValueError, match="missing"):
        SurrogateLibrary.load(d, require_all=False)
    (d / "manifest.json").unlink()
    with pytest.raises(ValueError, match="manifest missing"):
        SurrogateLibrary.load(d, require_all=False)


def test_manifest_of_other_code_is_rejected(tiny_library_dir: Path, tmp_path: Path) -> None:
    d = tmp_path / "lib"
    shutil.copytree(tiny_library_dir, d)
    m = json.loads((d / "manifest.json").read_text())
    m["lpm_code_sha256"] = "0" * 64
    (d / "manifest.json").write_text(json.dumps(m))
    with pytest.raises(ValueError, match="lpm_code_sha256 differs"):
        SurrogateLibrary.load(d, require_all=False)


def test_propagate_is_deterministic_and_sane(tiny_library_dir: Path) -> None:
    fam = _family(tiny_library_dir)
    a = fam.propagate(**NOMINAL)
    b = _family(tiny_library_dir).propagate(**NOMINAL)
    assert a == b
    assert a.n_bootstrap == 150
    assert a.n_samples >= 64
    assert a.clamped_inputs == ()
    lo, hi = a.p_iss15_ci95
    assert 0.0 <= lo < hi <= 1.0  # non-degenerate
    assert lo <= a.p_iss15 <= hi
    assert set(a.measures) == {
        "hic15",
        "nij",
        "chest_deflection_mm",
        "chest_vc_m_s",
        "chest_a3ms_g",
    }
    for name, v in a.measures.items():
        lo, hi = a.measures_ci95[name]
        assert lo < hi
        assert lo <= v <= hi, name
    assert a.iss_ci95[0] <= a.iss_ci95[1]
    # the angle's sign does not matter (planar models see its cosine)
    assert fam.propagate(**{**NOMINAL, "angle_deg": -10.0}) == a
    # larger sensor errors widen the measure intervals
    wide = fam.propagate(**NOMINAL, posture_sd_deg=6.0, seat_track_sd_mm=60.0)
    narrow = fam.propagate(**NOMINAL, posture_sd_deg=0.5, seat_track_sd_mm=5.0)
    w = wide.measures_ci95["hic15"]
    n = narrow.measures_ci95["hic15"]
    assert w[1] - w[0] > n[1] - n[0]


def test_out_of_range_inputs_are_clamped_and_flagged(tiny_library_dir: Path) -> None:
    fam = _family(tiny_library_dir)
    r = fam.propagate(**{**NOMINAL, "delta_v_kmh": 150.0, "posture_deg": 40.0})
    assert r.clamped_inputs == ("delta_v_kmh", "posture_deg")
    edge = fam.propagate(**{**NOMINAL, "delta_v_kmh": TINY_DELTA_V[1], "posture_deg": 25.0})
    assert r.p_iss15 == edge.p_iss15
    with pytest.raises(ValueError, match="finite"):
        fam.propagate(**{**NOMINAL, "delta_v_kmh": float("nan")})
    with pytest.raises(ValueError, match=">= 0"):
        fam.propagate(**NOMINAL, posture_sd_deg=-1.0)


def test_build_is_bit_reproducible_and_resumable(tmp_path: Path) -> None:
    config = BuildConfig(
        n_train=40,
        n_train_by_mode=(),
        n_holdout=10,
        n_boot=5,
        seed=3,
        delta_v_pieces_kmh=(40.0, 50.0, 60.0),
    )
    spec = tiny_spec()
    for sub in ("a", "b"):
        build_family(spec, tmp_path / sub, config)
        write_manifest(tmp_path / sub, config)
    for name in (f"{TINY_NAME}.npz", "manifest.json"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    path = tmp_path / "a" / f"{TINY_NAME}.npz"
    assert is_current(path, spec, config)
    assert not is_current(path, spec, replace(config, seed=4))
    assert not is_current(path, replace(spec, ranges=((40.0, 61.0), *spec.ranges[1:])), config)


def test_cli_rejects_unknown_family(tmp_path: Path) -> None:
    assert main(["--out", str(tmp_path), "--family", "nope", "--no-report"]) == 2
