"""The shipped artifacts match the current LPM code and parameter set.

The checksum test fails after any change of
the LPM code or parameters until ``aacn-triage build-surrogates`` is rerun.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pytest

from models.lpm.params import load_parameter_set
from models.surrogate.evaluate import SurrogateFamily, SurrogateLibrary, default_artifact_dir
from models.surrogate.spec import AGREEMENT_TARGET, MEDIAN_ERROR_TARGET
from models.surrogate.store import read_artifact
from tests.tolerance import LPM_CLOSE_SHARE, assert_lpm_close


def test_shipped_artifacts_match_the_current_lpm() -> None:
    """The manifest verifies every file's checksum, and its golden cases and parameter
    values hold (models.surrogate.golden; tests/surrogate/test_readiness.py)."""
    lib = SurrogateLibrary.load()  # verifies every checksum of the manifest
    assert lib.stale_reason() is None, "rerun aacn-triage build-surrogates"
    assert lib.manifest["golden"]["parameter_values_sha256"] == load_parameter_set().values_sha256


@dataclass(frozen=True)
class _HeldOut:
    """A shipped family with its stored held-out LPM runs (failed runs dropped)."""

    family: SurrogateFamily
    x: npt.NDArray[np.float64]
    y: npt.NDArray[np.float64]
    pred: npt.NDArray[np.float64]


@pytest.fixture(scope="module")
def heldout() -> dict[str, _HeldOut]:
    """Every shipped family's held-out runs and predictions, read once for the module."""
    out = {}
    for name, fam in SurrogateLibrary.load().families().items():
        arrays, _ = read_artifact(default_artifact_dir() / f"{name}.npz")
        x, y = arrays["heldout_x"], arrays["heldout_y"]
        ok = np.all(np.isfinite(y), axis=1)
        out[name] = _HeldOut(fam, x[ok], y[ok], fam.predict(x[ok]))
    return out


def _pooled_heldout(heldout: dict[str, _HeldOut]) -> tuple[dict[str, float], float]:
    """Pooled held-out errors of the shipped families against their own stored LPM runs."""
    rel: dict[str, list[float]] = {}
    agree: list[bool] = []
    for h in heldout.values():
        for k, o in enumerate(h.family.outputs):
            if o == "p_iss15":
                agree += list((h.pred[:, k] >= 0.5) == (h.y[:, k] >= 0.5))
            elif o != "iss":
                err = np.abs(h.pred[:, k] - h.y[:, k]) / np.maximum(np.abs(h.y[:, k]), 1e-12)
                rel.setdefault(o, []).extend(err)
    return {o: float(np.median(v)) for o, v in rel.items()}, float(np.mean(agree))


def test_shipped_heldout_pooled(heldout: dict[str, _HeldOut]) -> None:
    """Issue 5 held-out check on the shipped artifacts (their stored held-out LPM runs,
    150 uniform random points per family): pooled median relative error of every
    measure under 5 %; ISS15+ agreement held to a 95 % regression bound (the 97 %
    target: the next tests; REPORT.md for the per-family figures)."""
    errors, agreement = _pooled_heldout(heldout)
    assert all(e < MEDIAN_ERROR_TARGET for e in errors.values()), errors
    assert agreement >= 0.95, agreement


def test_shipped_heldout_agreement_target(heldout: dict[str, _HeldOut]) -> None:
    """Issue 5 target on the pooled held-out points of the 24 families (REPORT.md
    Table B)."""
    _, agreement = _pooled_heldout(heldout)
    assert agreement > AGREEMENT_TARGET, agreement


def test_shipped_heldout_agreement_at_the_service_decision(
    heldout: dict[str, _HeldOut],
) -> None:
    """Pooled over the 24 families, the surrogate and the LPM take the same decision as
    the service does (zero-load-corrected P(ISS >= 15) against the mode's threshold) on
    more than 97 % of the held-out points (REPORT.md)."""
    from models.offline.surrogate.report import service_raw_threshold

    agree: list[bool] = []
    for name, h in heldout.items():
        k = h.family.outputs.index("p_iss15")
        thr = service_raw_threshold(name, h.family.outputs)
        assert 0.10 < thr < 0.15, "the threshold on the uncorrected scale lies above t"
        agree += list((h.pred[:, k] >= thr) == (h.y[:, k] >= thr))
    assert float(np.mean(agree)) > AGREEMENT_TARGET


def test_shipped_heldout_agreement_target_per_family(heldout: dict[str, _HeldOut]) -> None:
    """Issue 5 target per family: ISS15+ agreement above 97 % on its 150 held-out points."""
    low = {}
    for name, h in heldout.items():
        k = h.family.outputs.index("p_iss15")
        agreement = float(np.mean((h.pred[:, k] >= 0.5) == (h.y[:, k] >= 0.5)))
        if agreement <= AGREEMENT_TARGET:
            low[name] = agreement
    assert low == {}


def test_shipped_heldout_median_per_family_under_target(heldout: dict[str, _HeldOut]) -> None:
    """Issue 5: per family and measure, the held-out median relative error is under
    5 % (REPORT.md Table B; VALIDATION.md repeats the check on 600 fresh points)."""
    high: dict[str, dict[str, float]] = {}
    for name, h in heldout.items():
        for k, o in enumerate(h.family.outputs):
            if o in ("p_iss15", "iss"):
                continue
            err = np.abs(h.pred[:, k] - h.y[:, k]) / np.maximum(np.abs(h.y[:, k]), 1e-12)
            med = float(np.median(err))
            if med >= MEDIAN_ERROR_TARGET:
                high.setdefault(name, {})[o] = med
    assert high == {}


def test_shipped_p_interval_covers_the_monte_carlo_value() -> None:
    """Issue 5 coverage check on the shipped families (40 seeded random cases; the
    report runs 120): the served 95% interval of P(ISS >= 15) contains the mean of
    direct LPM runs over the sensor distribution in at least 90% of them."""
    import numpy as np

    from models.offline.surrogate.report import coverage_check

    rows = coverage_check(SurrogateLibrary.load(), 40, seed=7)
    assert float(np.mean([r["hit"] for r in rows])) >= 0.90


def test_held_out_calibration_widens_and_never_narrows() -> None:
    """The factor is >= 1, 1 when the held-out truth is the surrogate itself, and
    grows when the truth moves away from it."""
    import numpy as np

    from models.surrogate.evaluate import default_artifact_dir
    from models.surrogate.store import read_artifact

    lib = SurrogateLibrary.load()
    name = "frontal__male_50th__belted__airbag"
    fam = lib.families()[name]
    assert all(f.p_interval_inflation >= 1.0 for f in lib.families().values())
    assert fam.p_interval_inflation > 1.0, "the frontal fits err beyond their bootstrap spread"
    arrays, _ = read_artifact(default_artifact_dir() / f"{name}.npz")
    x = arrays["heldout_x"]
    own = fam.predict(x)[:, fam.outputs.index("p_iss15")]
    assert fam._p_inflation(x, own) == 1.0
    shifted = np.clip(own * 1.5, 0.0, 1.0)
    assert fam._p_inflation(x, shifted) > fam.p_interval_inflation
    r = fam.propagate(
        delta_v_kmh=60.0, angle_deg=5.0, posture_deg=10.0, seat_track_mm=0.0, duration_ms=90.0
    )
    assert r.p_interval_inflation == fam.p_interval_inflation
    assert r.p_iss15_ci95[0] <= r.p_iss15 <= r.p_iss15_ci95[1]


def test_shipped_measure_intervals_hold_the_direct_lpm_outcomes() -> None:
    """Issue 5, the measures' and ISS intervals: over 24 seeded random cases, the
    served 95% interval holds on average at least 92 % of the direct LPM outcomes
    at independently drawn true sensor values (REPORT.md Table D runs 120 cases).
    Without the held-out margin the shares were 73-94 % on these cases (chest CTI
    73 %, VC 84 %, 3 ms acceleration 85 %, Nij 89 %), which this test rejects."""
    import numpy as np

    from models.offline.surrogate.report import measure_coverage_check

    shares = measure_coverage_check(SurrogateLibrary.load().families(), 24, seed=13)
    assert set(shares) >= {"hic15", "nij", "chest_deflection_mm", "iss"}
    low = {k: round(float(np.mean(v)), 3) for k, v in shares.items() if np.mean(v) < 0.92}
    assert low == {}


def test_measure_interval_margin_is_calibrated_on_the_held_out_runs() -> None:
    """The factor is 0 when the held-out truth is the surrogate itself and grows
    when the truth moves away; the served interval then contains the bare
    sensor x bootstrap interval (a family assembled without its held-out runs)."""
    import numpy as np

    from models.surrogate.evaluate import SurrogateFamily, default_artifact_dir
    from models.surrogate.store import read_artifact

    name = "near_side__male_50th__belted__no_side_airbag"
    fam = SurrogateLibrary.load().families()[name]
    arrays, meta = read_artifact(default_artifact_dir() / f"{name}.npz")
    x = np.asarray(arrays["heldout_x"])
    own = fam.predict(x)
    assert all(v == pytest.approx(0.0, abs=1e-6) for v in fam._interval_factors(x, own).values())
    worse = fam._interval_factors(x, own * 1.3)
    assert all(worse[k] > fam.interval_factors[k] for k in ("hic15", "nij", "chest_cti"))
    assert set(fam.interval_factors) == set(fam.outputs) - {"p_iss15"}
    bare = SurrogateFamily.from_arrays(
        {k: v for k, v in arrays.items() if not k.startswith("heldout_")}, meta
    )
    assert dict(bare.interval_factors) == {}
    kw = {
        "delta_v_kmh": 30.0,
        "angle_deg": 5.0,
        "posture_deg": 10.0,
        "seat_track_mm": 20.0,
        "duration_ms": 70.0,
    }
    served, plain = fam.propagate(**kw), bare.propagate(**kw)
    assert served.p_iss15_ci95 == plain.p_iss15_ci95  # P has its own calibration
    for k, (lo, hi) in served.measures_ci95.items():
        p_lo, p_hi = plain.measures_ci95[k]
        assert lo <= p_lo <= p_hi <= hi, k
        assert lo <= served.measures[k] <= hi, k
    assert served.iss_ci95[0] <= plain.iss_ci95[0] <= plain.iss_ci95[1] <= served.iss_ci95[1]


def test_served_p_is_the_assessment_of_the_served_measures_at_the_occupant_age() -> None:
    """Evaluation 3: P(ISS >= 15) comes from the surrogate's measures through the
    risk curves, with the occupant's age (the direct LPM run uses it for the chest
    deflection curve). Without sensor error every sample is the reading, so the
    served P is the scalar assessment of the served measures; an older occupant's
    chest gives a higher P at the same crash."""
    from models.injury.assessment import InjuryMeasures, assess
    from models.notification import Body

    fam = SurrogateLibrary.load().families()["frontal__male_50th__belted__no_airbag"]
    kw = {
        "delta_v_kmh": 62.0,
        "angle_deg": 0.0,
        "posture_deg": 5.8,
        "seat_track_mm": 0.0,
        "duration_ms": 90.0,
        "posture_sd_deg": 0.0,
        "seat_track_sd_mm": 0.0,
    }
    by_age = {}
    for age in (None, 25.0, 80.0):
        r = fam.propagate(**kw, age_years=age)
        ref = assess(InjuryMeasures(**r.measures), Body.MALE_50TH, age, "frontal")
        assert r.p_iss15 == pytest.approx(ref.p_iss15, rel=1e-9, abs=1e-12)
        assert r.p_iss15_ci95[0] <= r.p_iss15 <= r.p_iss15_ci95[1]
        by_age[age] = r.p_iss15
    assert by_age[80.0] > by_age[25.0]
    assert 0.01 < by_age[None] < 0.99, "the check is made where P is not saturated"


def test_shipped_head_strike_gates_sort_the_held_out_runs() -> None:
    """Pieces where the head strikes the interior in part of the design are split,
    and the gate PCEs put the held-out LPM runs on the side the LPM itself reached
    (the sign of the head clearance): 95 % of 879 runs in 22 pieces as built
    2026-12-02, at least 86 % in each piece (10-70 runs per piece; the misses
    lie near zero clearance, where the two sides meet)."""
    import numpy as np

    from models.surrogate.evaluate import default_artifact_dir
    from models.surrogate.store import read_artifact

    lib = SurrogateLibrary.load()
    n_split = 0
    pooled: list[bool] = []
    for name, fam in lib.families().items():
        splits = [p for p in fam.meta["pieces"] if "split" in p]
        if not splits:
            continue
        n_split += len(splits)
        arrays, _ = read_artifact(default_artifact_dir() / f"{name}.npz")
        x, c = arrays["heldout_x"], arrays["heldout_head_clearance_mm"]
        gate = fam.head_clearance(x)
        for p in splits:
            lo, hi = p["delta_v_kmh"]
            inside = (x[:, 0] >= lo) & (x[:, 0] < hi) & np.isfinite(c)
            if inside.sum() < 10:
                continue
            hits = (gate[inside] < 0.0) == (c[inside] < 0.0)
            pooled += list(hits)
            assert np.mean(hits) >= 0.8, (name, lo, hi, np.mean(hits))
        # and pieces that are not split hold the same gate value: none
        unsplit = [p for p in fam.meta["pieces"] if "split" not in p]
        for p in unsplit:
            lo, hi = p["delta_v_kmh"]
            inside = (x[:, 0] >= lo) & (x[:, 0] < hi)
            assert np.all(np.isnan(gate[inside]))
    assert n_split >= 4  # the frontal head strikes of both bodies, at least
    assert np.mean(pooled) >= 0.93, np.mean(pooled)


def test_shipped_heldout_targets_are_todays_direct_lpm_runs() -> None:
    """The held-out figures above compare the surrogates with stored LPM runs; this
    reruns the direct LPM at three stored held-out points of every family and gets
    the stored outputs back, so the figures are against the LPM as shipped.

    Not bit for bit: the runs were stored on the build machine, and elsewhere the
    libm the numba kernels call (glibc's FMA or non-FMA exp/pow) and numba's code
    for the CPU can change the last bits (issue 22). Every output is held to
    :data:`~tests.tolerance.LPM_RTOL` (a contact hinge can amplify a last-bit
    difference: up to 5.7e-4 relative measured over all the stored held-out runs)
    and 95 % of them to
    :data:`~tests.tolerance.RERUN_RTOL` (at these points all agree to 7.1e-13 on
    the other code paths), so a change of the LPM that moves every output a little
    still fails; the ISS, an integer, moves only if an AIS crosses its threshold."""
    from models.offline.surrogate.build import lpm_runs
    from models.surrogate.evaluate import default_artifact_dir
    from models.surrogate.spec import FAMILIES
    from models.surrogate.store import read_artifact

    params = load_parameter_set()
    close = total = 0
    for spec in FAMILIES:
        arrays, _ = read_artifact(default_artifact_dir() / f"{spec.name}.npz")
        x, y = arrays["heldout_x"][:3], arrays["heldout_y"][:3]
        c, n = assert_lpm_close(lpm_runs(spec, x, params).y, y, context=spec.name)
        close, total = close + c, total + n
    assert close >= LPM_CLOSE_SHARE * total, (close, total)


def test_one_point_blend_weights_are_the_array_weights() -> None:
    """The request path's scalar blend weights equal the array method's, bit for bit,
    across every family's delta-V domain (blend zones and piece interiors)."""
    for spec_name, fam in SurrogateLibrary.load().families().items():
        dv = np.concatenate(
            [np.geomspace(fam._lo[0], fam._hi[0], 801), [fam._lo[0], fam._hi[0]], fam._edges]
        )
        dv = dv[(dv >= fam._lo[0]) & (dv <= fam._hi[0])]
        arr = fam._weights(dv)
        one = np.array([fam._weights_at(float(v)) for v in dv])
        assert np.array_equal(arr, one), spec_name
        assert np.any((arr > 0.0) & (arr < 1.0)), f"{spec_name}: no blend zone exercised"
