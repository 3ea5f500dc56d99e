"""Pieces split at the head-strike onset: a hinge the polynomial cannot round off.

Synthetic outputs over a frontal family's inputs, with a known "clearance"
(a smooth function of the inputs) and measures that are flat while it is
positive and rise linearly with the penetration once it is negative, the
shape of HIC15 through a head strike in the LPM (spec.DELTA_V_PIECES_KMH).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from models.offline.surrogate.build import BuildConfig, fit_family, from_unit, latin_hypercube
from models.surrogate.evaluate import SurrogateFamily
from models.surrogate.spec import FAMILIES, INPUT_NAMES, FamilySpec

SPEC = next(s for s in FAMILIES if s.name == "frontal__female_5th__belted__no_airbag")
RANGES = ((30.0, 70.0), *SPEC.ranges[1:])
CONFIG = BuildConfig(
    n_train=500, n_train_by_mode=(), n_boot=8, seed=3, delta_v_pieces_kmh=(30.0, 70.0)
)


def _clearance(x: np.ndarray) -> np.ndarray:
    """mm: less margin at higher delta-V, more forward lean and a seat further forward."""
    dv, _, post, seat, dur = x.T
    return 150.0 - 4.0 * (dv - 30.0) - 2.0 * post - 0.3 * seat + 0.5 * (dur - 90.0)


def _outputs(spec: FamilySpec, x: np.ndarray) -> np.ndarray:
    c = _clearance(x)
    depth = np.maximum(-c, 0.0)
    base = 1.0 + 0.01 * x[:, 0]
    cols = []
    for name in spec.outputs:
        if name == "p_iss15":
            cols.append(1.0 / (1.0 + np.exp(3.0 - 0.05 * depth)))
        elif name == "iss":
            cols.append(np.minimum(1.0 + 0.2 * depth, 75.0))
        else:
            cols.append(30.0 * base + 20.0 * depth)  # flat, then linear in the penetration
    return np.stack(cols, axis=1)


def _family(fit: Any, spec: FamilySpec) -> SurrogateFamily:
    piece: dict[str, Any] = {"fits": fit.outputs}
    if fit.split is not None:
        piece["split"] = fit.split
    meta = {
        "family": spec.name,
        "mode": spec.mode.value,
        "body": spec.body.value,
        "outputs": list(spec.outputs),
        "inputs": [
            {"name": n, "low": r[0], "high": r[1]} for n, r in zip(INPUT_NAMES, RANGES, strict=True)
        ],
        "delta_v_pieces_kmh": [30.0, 70.0],
        "pieces": [piece],
    }
    return SurrogateFamily.from_arrays(fit.arrays, meta)


@pytest.fixture(scope="module")
def fits() -> tuple[Any, Any]:
    """The split and the unsplit fit of the same synthetic piece."""
    spec = replace(SPEC, ranges=RANGES)
    x = from_unit(2.0 * latin_hypercube(500, 5, np.random.default_rng(1)) - 1.0, RANGES)
    y = _outputs(spec, x)
    split = fit_family(spec, x, y, CONFIG, RANGES, "piece0/", clearance_mm=_clearance(x))
    whole = fit_family(spec, x, y, CONFIG, RANGES, "piece0/")
    return split, whole


def test_the_gate_is_a_point_pce_and_the_sides_are_bootstrapped(fits: tuple[Any, Any]) -> None:
    split, _ = fits
    gate = split.arrays["piece0/gate/head_clearance_mm/boot_offsets"]
    assert gate.tolist() == [0]
    assert split.arrays["piece0/gate/head_clearance_mm/point_terms"].size > 0
    for side in ("contact", "free"):
        off = split.arrays[f"piece0/{side}/hic15/boot_offsets"]
        assert off.size == CONFIG.n_boot + 1
        assert np.all(np.diff(off) > 0)


@pytest.fixture(scope="module")
def families(fits: tuple[Any, Any]) -> tuple[SurrogateFamily, SurrogateFamily]:
    spec = replace(SPEC, ranges=RANGES)
    split, whole = fits
    assert split.split is not None
    assert whole.split is None
    assert split.split["n_struck"] >= 30
    assert split.split["n_free"] >= 30
    return _family(split, spec), _family(whole, spec)


def _test_points(n: int = 400) -> np.ndarray:
    lo = np.array([r[0] for r in RANGES])
    hi = np.array([r[1] for r in RANGES])
    return lo + (hi - lo) * np.random.default_rng(2).random((n, 5))


def test_split_piece_fits_the_hinge_better(
    families: tuple[SurrogateFamily, SurrogateFamily],
) -> None:
    split, whole = families
    x = _test_points()
    truth = _outputs(SPEC, x)[:, 0]
    err_split = np.median(np.abs(split.predict(x)[:, 0] / truth - 1.0))
    err_whole = np.median(np.abs(whole.predict(x)[:, 0] / truth - 1.0))
    assert err_split < 0.02
    assert err_split < 0.5 * err_whole


def test_split_is_continuous_across_the_onset(
    families: tuple[SurrogateFamily, SurrogateFamily],
) -> None:
    split, _ = families
    # a fine delta-V line through the onset (clearance 0 near 65 km/h here)
    dv = np.linspace(55.0, 70.0, 3001)
    x = np.column_stack(
        [
            dv,
            np.full_like(dv, 10.0),
            np.full_like(dv, 10.0),
            np.zeros_like(dv),
            np.full_like(dv, 100.0),
        ]
    )
    hic = split.predict(x)[:, 0]
    assert np.all(np.isfinite(hic))
    # steps of 0.005 km/h: the true slope is at most 80 per km/h beyond the onset
    assert np.max(np.abs(np.diff(hic))) < 5.0


def test_propagation_through_a_split_piece_matches_predict(
    families: tuple[SurrogateFamily, SurrogateFamily],
) -> None:
    split, _ = families
    point = {
        "delta_v_kmh": 62.0,
        "angle_deg": 5.0,
        "posture_deg": 10.0,
        "seat_track_mm": 0.0,
        "duration_ms": 100.0,
    }
    r = split.propagate(**point, posture_sd_deg=0.0, seat_track_sd_mm=0.0)
    x = np.array([[point[n] for n in INPUT_NAMES]])
    np.testing.assert_allclose(r.measures["hic15"], split.predict(x)[0, 0], rtol=1e-9)
    wide = split.propagate(**point)
    lo, hi = wide.measures_ci95["hic15"]
    assert lo < wide.measures["hic15"] < hi


def test_inconsistent_split_pieces_are_rejected() -> None:
    spec = replace(SPEC, ranges=RANGES)
    x = from_unit(2.0 * latin_hypercube(300, 5, np.random.default_rng(4)) - 1.0, RANGES)
    config = replace(CONFIG, n_boot=2)
    fit = fit_family(spec, x, _outputs(spec, x), config, RANGES, "piece0/", _clearance(x))
    assert fit.split is not None
    _family(fit, spec)  # consistent: loads
    missing = dict(fit.arrays)
    del missing["piece0/free/candidates"]
    with pytest.raises(ValueError, match="missing"):
        _family(replace(fit, arrays=missing), spec)
    other_basis = dict(fit.arrays)
    other_basis["piece0/contact/recurrence_alpha"] = (
        other_basis["piece0/gate/recurrence_alpha"] + 0.1
    )
    with pytest.raises(ValueError, match="basis"):
        _family(replace(fit, arrays=other_basis), spec)
    bad_band = replace(fit, split={**fit.split, "band_mm": 0.0})
    with pytest.raises(ValueError, match="band"):
        _family(bad_band, spec)
