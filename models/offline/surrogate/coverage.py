"""Coverage checks of the served intervals against direct LPM runs (REPORT.md Tables C, D).

Used by the build report (:mod:`.report`) and the fresh validation (:mod:`.validate`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from models.arrays import FloatArray
from models.offline.surrogate.runs import lpm_outputs
from models.surrogate.evaluate import SurrogateFamily, SurrogateLibrary, UncertaintyResult
from models.surrogate.spec import FAMILIES, P_RESOLUTION

__all__ = ["COVERAGE_SEED", "MEASURE_DRAWS", "coverage_check", "measure_coverage_check"]


#: Seed of the coverage cases drawn by :func:`coverage_check`.
COVERAGE_SEED = 5


def _random_case(
    families: Mapping[str, SurrogateFamily], names: Sequence[str], rng: np.random.Generator
) -> tuple[str, FloatArray, FloatArray, FloatArray, UncertaintyResult]:
    """A random family of `names` and uniform in-domain readings, with the served answer.

    Returns the family name, the domain's lower and upper bounds, the readings
    (shape (5,)) and the :class:`UncertaintyResult` at them.
    """
    name = names[int(rng.integers(len(names)))]
    fam = families[name]
    lo = np.array([r[0] for r in fam.ranges])
    hi = np.array([r[1] for r in fam.ranges])
    x0 = lo + (hi - lo) * rng.random(lo.size)
    r = fam.propagate(
        delta_v_kmh=float(x0[0]),
        angle_deg=float(x0[1]),
        posture_deg=float(x0[2]),
        seat_track_mm=float(x0[3]),
        duration_ms=float(x0[4]),
    )
    return name, lo, hi, x0, r


def coverage_check(
    lib: SurrogateLibrary,
    n_cases: int,
    seed: int = COVERAGE_SEED,
    families: Sequence[str] | None = None,
) -> list[dict[str, Any]]:
    """Does the 95% interval of P(ISS >= 15) contain the Monte Carlo value?

    Cases: random families and random in-domain readings (seeded); the known
    input distribution is the default Gaussian sensor error around the
    readings (clipped to the domain). The Monte Carlo value is the mean
    P(ISS >= 15) of direct LPM runs at the fixed sensor sample points; it counts
    as inside when within :data:`P_RESOLUTION` of the interval.

    Parameters
    ----------
    lib : SurrogateLibrary
    n_cases, seed : int
    families : sequence of str, optional
        Draw the cases from these families only (default: every family of `lib`).

    Returns
    -------
    list of dict
        One row per case: family, inputs, interval, Monte Carlo value, hit.
    """
    from models.surrogate.evaluate import (
        _NORMALS,
        DEFAULT_POSTURE_SD_DEG,
        DEFAULT_SEAT_TRACK_SD_MM,
    )

    specs = {s.name: s for s in FAMILIES}
    names = [n for n in lib.family_names if n in specs and (families is None or n in families)]
    rng = np.random.default_rng(seed)
    rows: list[dict[str, Any]] = []
    for _ in range(n_cases):
        name, lo, hi, x0, r = _random_case(lib.families(), names, rng)
        x = np.tile(x0, (_NORMALS.shape[0], 1))
        x[:, 2] = np.clip(x0[2] + DEFAULT_POSTURE_SD_DEG * _NORMALS[:, 0], lo[2], hi[2])
        x[:, 3] = np.clip(x0[3] + DEFAULT_SEAT_TRACK_SD_MM * _NORMALS[:, 1], lo[3], hi[3])
        y, _ = lpm_outputs(specs[name], x)
        mc = float(np.nanmean(y[:, specs[name].outputs.index("p_iss15")]))
        rows.append(
            {
                "family": name,
                "x": [round(float(v), 1) for v in x0],
                "p": r.p_iss15,
                "ci95": r.p_iss15_ci95,
                "mc": mc,
                "hit": bool(
                    r.p_iss15_ci95[0] - P_RESOLUTION <= mc <= r.p_iss15_ci95[1] + P_RESOLUTION
                ),
            }
        )
    return rows


#: Direct LPM draws of the true sensor values per case in :func:`measure_coverage_check`.
MEASURE_DRAWS = 48


#: A measure outcome counts as inside when within this relative tolerance of
#: the interval (the surrogate and the check are both double precision; the
#: tolerance only absorbs rounding at an interval that is a single value).
_REL_TOL = 1e-3


def measure_coverage_check(
    families: Mapping[str, SurrogateFamily],
    n_cases: int,
    seed: int = COVERAGE_SEED,
    n_draws: int = MEASURE_DRAWS,
) -> dict[str, list[float]]:
    """Share of direct LPM outcomes inside the served 95% interval of each measure and ISS.

    Cases: random families and random in-domain readings (seeded). For each,
    `n_draws` true sensor values are drawn independently (seeded Gaussian
    draws, not the service's fixed sample set) from the default sensor error
    around the readings, clipped to the domain; the LPM is run at each, and
    the share of its outcomes inside the interval the service would give for
    those readings is recorded. For honest 95% intervals the shares average
    about 0.95 or more.

    Parameters
    ----------
    families : Mapping[str, SurrogateFamily]
        The families to draw from (``SurrogateLibrary.families()``, or the
        same families without their held-out margin, :func:`bare_families`).
    n_cases, seed, n_draws : int

    Returns
    -------
    dict
        Output name (measures and ``iss``) -> one share per case that computes it.
    """
    from models.surrogate.evaluate import DEFAULT_POSTURE_SD_DEG, DEFAULT_SEAT_TRACK_SD_MM

    specs = {s.name: s for s in FAMILIES}
    names = sorted(n for n in families if n in specs)
    rng = np.random.default_rng(seed)
    shares: dict[str, list[float]] = {}
    for _ in range(n_cases):
        name, lo, hi, x0, r = _random_case(families, names, rng)
        x = np.tile(x0, (n_draws, 1))
        x[:, 2] = np.clip(
            x0[2] + DEFAULT_POSTURE_SD_DEG * rng.standard_normal(n_draws), lo[2], hi[2]
        )
        x[:, 3] = np.clip(
            x0[3] + DEFAULT_SEAT_TRACK_SD_MM * rng.standard_normal(n_draws), lo[3], hi[3]
        )
        y, _ = lpm_outputs(specs[name], x)
        for k, out in enumerate(specs[name].outputs):
            if out == "p_iss15":
                continue
            a, b = r.iss_ci95 if out == "iss" else r.measures_ci95[out]
            v = y[:, k][np.isfinite(y[:, k])]
            if v.size == 0:
                continue
            tol = _REL_TOL * max(abs(a), abs(b), 1e-12)
            shares.setdefault(out, []).append(float(np.mean((v >= a - tol) & (v <= b + tol))))
    return shares
