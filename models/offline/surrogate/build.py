"""Offline build of the PCE surrogate families (``aacn-triage build-surrogates``).

Per family (:data:`models.surrogate.spec.FAMILIES`):

1. Per delta-V piece (:data:`models.surrogate.spec.DELTA_V_PIECES_KMH`), a
   Latin hypercube design of :meth:`BuildConfig.n_train_for` points (per mode; seeded,
   uniform in log delta-V and log duration, see ``spec.LOG_INPUTS``) over the
   piece's input box; plus :attr:`BuildConfig.n_holdout` independent uniform
   points over the whole family domain for the held-out check. Every point is
   one direct LPM run (``models.lpm.simulate.simulate`` on a haversine pulse
   along the PDOF, sampled at 10 kHz, 200 ms simulated).
2. aPCE basis: per input, the orthonormal recurrence of the design's own
   empirical distribution (discretised Stieltjes, :mod:`models.surrogate.basis`),
   on a hyperbolic multi-index set (q = :data:`Q_NORM`) of degree up to 15.
3. Per output (each measure on a log scale, P(ISS >= 15) on a logit scale, ISS):
   hybrid LAR with the degree chosen by the corrected analytic LOO
   (:mod:`models.offline.surrogate.fit`); then :attr:`BuildConfig.n_boot` bootstrap
   replicates, each *rerunning the LAR selection* on resampled rows at the
   chosen degree (``pce-notes.md``: a fixed basis gives bands far too narrow).
4. One artifact ``<family>.npz`` (no pickles) and ``manifest.json`` with the
   SHA-256 of each file.

Seeded and reproducible bit for bit (single-threaded BLAS per worker, fixed
member order and timestamps in the files), parallel over processes, resumable
(a family whose artifact records the same configuration is skipped),
``--family NAME`` rebuilds one family (``aacn-triage build-surrogates``,
:mod:`.command`). chaospy is not needed (the Stieltjes
recurrence and LAR are a few lines of numpy); it is used only by the tests to
cross-check the basis (where chaospy would fit, measured: ``benchmarks/bench_chaospy.py``,
``benchmarks/RESULTS.md``: the empirical-measure recurrence has no chaospy routine, its
Latin hypercube uses the global random state).
"""

from __future__ import annotations

import hashlib
import json
import platform
import time
import zlib
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from models import ENGINE_VERSION
from models.arrays import FloatArray
from models.offline.surrogate.fit import MAX_DEGREE, SparseFit, fit_adaptive, fit_degree
from models.offline.surrogate.kriging_fit import fit_residual_kriging
from models.offline.surrogate.runs import (
    ISS15_DECISION_PROBABILITY,
    LpmRuns,
    heldout_scores,
    lpm_outputs,
    lpm_runs,
)
from models.surrogate.basis import (
    design_matrix,
    graded_counts,
    hyperbolic_multi_indices,
    stieltjes,
)
from models.surrogate.spec import (
    DELTA_V_PIECES_KMH,
    HEAD_CLEARANCE,
    INPUT_NAMES,
    LOG_INPUTS,
    LOGIT_CLIP,
    MEASURE_FLOORS,
    FamilySpec,
    _bounds,
    piece_ranges,
    to_output_scale,
    to_unit,
)
from models.surrogate.store import (
    FORMAT_VERSION,
    MANIFEST_NAME,
    read_artifact,
    sha256_file,
    write_artifact,
    write_json,
)

__all__ = [
    "DEFAULT_SEED",
    "ISS15_DECISION_PROBABILITY",
    "Q_NORM",
    "BuildConfig",
    "FamilyFit",
    "build_family",
    "default_config",
    "fit_family",
    "heldout_scores",
    "is_current",
    "latin_hypercube",
    "LpmRuns",
    "lpm_outputs",
    "lpm_runs",
    "standardise",
    "write_manifest",
]


#: Base seed of every design and bootstrap (families derive theirs from it and their name).
DEFAULT_SEED = 20261123
#: q-norm of the hyperbolic truncation (Blatman & Sudret 2011 recommend 0.4-0.75);
#: 446 candidate terms at degree 15 in 5 inputs.
Q_NORM = 0.5
#: Number of bootstrap replicates (reference paper section 2.5, after its ref. [15]).
N_BOOTSTRAP = 150


@dataclass(frozen=True)
class BuildConfig:
    """Settings of a build (recorded in every artifact; a change rebuilds).

    Attributes
    ----------
    n_train : int
        Latin hypercube design size per delta-V piece (LPM runs each PCE is fitted on).
    n_train_by_mode : tuple of (str, int)
        Design sizes of the modes that differ from `n_train` (:meth:`n_train_for`).
    n_holdout : int
        Independent uniform points per family for the held-out check.
    n_boot : int
        Bootstrap replicates per output.
    max_degree : int
    q_norm : float
    seed : int
    delta_v_pieces_kmh : tuple of float
        Edges of the delta-V pieces (one PCE per piece), km/h.
    split_min_side_runs : int
    split_band_mm : float
        Head-strike split of a piece (see the fields).
    kriging_max_runs : int
        Design runs a piece's residual Kriging is fitted on, at most.
    """

    #: 600 runs per piece: measured on three frontal families (held-out median
    #: relative error of HIC15 9-10 % with 300 runs, 7-8 % with 600; the LPM runs
    #: cost ~3 ms each, the bootstrap LAR fits take most of the build time)
    n_train: int = 600
    #: (mode, design size per delta-V piece) where a mode's design differs
    #: from :attr:`n_train`. [R] Frontal 1200: measured 2026-12-02 on the
    #: family then furthest from the targets (belted 5F without airbag, 150
    #: held-out points, with the residual Kriging): HIC15 / Nij median relative
    #: error 6.0 / 5.9 %, ISS15+ agreement 96.7 % with 600 runs; 3.8 / 3.9 %,
    #: 97.3 % with 1200 (146 s instead of ~70 s for the family). The frontal
    #: head and chest measures have the head-strike and airbag-contact kinks
    #: that the side and rear modes do not. Near side 2000: on its one family
    #: above 5 % with 600 runs (belted 5F without side airbag, HIC15 5.7 %; her
    #: head strikes the side interior in every run above 20 km/h) 1200 runs
    #: gave 5.2 % and 2000 runs 4.2 % (:attr:`kriging_max_runs` for the
    #: Kriging's share).
    n_train_by_mode: tuple[tuple[str, int], ...] = (("frontal", 1200), ("near_side", 2000))
    #: Design runs the residual Kriging of a piece is fitted on (the first of
    #: its Latin hypercube rows, a random subset; all when fewer). The request
    #: path evaluates a (96 sensor samples x runs) kernel per piece: 1.1 ms at
    #: 1200 runs, 3.5 ms at 2000 (5.1 ms per near-side propagation).
    #: [R] Measured 2026-12-02 on 150 held-out points, HIC15 / Nij median
    #: relative error and ISS15+ agreement: near-side belted 5F without side
    #: airbag, 2000-run design: PCE alone 4.65 / 4.10 %, Kriging on all 2000
    #: runs 4.19 / 1.77 %, on 1200 5.07 / 2.36 %, on 1000 4.15 / 2.38 % (100 %
    #: agreement in all); frontal belted 5F without airbag, 1200-run design:
    #: Kriging on all 1200 3.81 / 3.93 %, 97.3 %, on 1000 3.99 / 4.73 %, 98.0 %.
    #: The spread between the subsets is the held-out median's own sampling
    #: error (150 points): about half a per cent.
    kriging_max_runs: int = 1000
    n_holdout: int = 150
    n_boot: int = N_BOOTSTRAP
    max_degree: int = MAX_DEGREE
    q_norm: float = Q_NORM
    seed: int = DEFAULT_SEED
    delta_v_pieces_kmh: tuple[float, ...] = DELTA_V_PIECES_KMH
    #: a piece is split at the head-strike onset when both sides of its design
    #: (head clearance below / above zero) hold at least this many runs.
    #: [R] spec.DELTA_V_PIECES_KMH: measured with 30 (sides of 30 runs fit up
    #: to 15 terms, fit.MIN_SAMPLES_PER_TERM)
    split_min_side_runs: int = 30
    #: half-width of the head-clearance band over which the two sides of a
    #: split piece are blended (smoothstep), mm; each side is fitted on its
    #: runs and those inside the band, so it is inside its design where it is
    #: used. [R] Measured 2026-12-02 on the two frontal families then below 97 %
    #: ISS15+ agreement (150 held-out points; HIC15 / Nij median relative
    #: error, agreement): belted 5F without airbag, unsplit 15.0 / 10.8 %,
    #: 96.7 %; band 3 mm 9.4 / 6.3 %, 96.0 %; 10 mm 10.3 / 6.4 %, 96.0 %; 25 mm
    #: 13.9 / 9.7 %, 96.0 %; unbelted 50M with airbag, unsplit 6.2 / 2.2 %,
    #: 96.7 %; 3 mm 6.4 / 2.4 %, 99.3 %; 10 mm 6.9 / 2.1 %, 98.0 %; 25 mm 5.8 /
    #: 2.7 %, 97.3 %. The 5F's misses are all at 66-115 km/h, where her head
    #: strikes the wheel in (almost) every run and the piece is not split.
    split_band_mm: float = 3.0

    def n_train_for(self, mode: str) -> int:
        """Design size per delta-V piece of the families of impact mode `mode`."""
        return dict(self.n_train_by_mode).get(mode, self.n_train)


def default_config() -> BuildConfig:
    """The configuration of the shipped artifacts."""
    return BuildConfig()


def latin_hypercube(n: int, dim: int, rng: np.random.Generator) -> FloatArray:
    """Latin hypercube sample in [0, 1)^dim (one point per stratum and input).

    Returns
    -------
    ndarray, shape (n, dim)
    """
    u = rng.random((n, dim))
    perms = np.stack([rng.permutation(n) for _ in range(dim)], axis=1)
    return np.asarray((perms + u) / n, dtype=np.float64)


def standardise(x: npt.ArrayLike, ranges: Sequence[tuple[float, float]]) -> FloatArray:
    """Map raw inputs (n, dim) from their design ranges to [-1, 1] (see spec.LOG_INPUTS)."""
    return to_unit(x, ranges)


def from_unit(z: npt.ArrayLike, ranges: Sequence[tuple[float, float]]) -> FloatArray:
    """Inverse of :func:`standardise`."""
    zv = np.atleast_2d(np.asarray(z, dtype=np.float64))
    lo, hi, lg = _bounds(ranges)
    u = (zv + 1.0) / 2.0
    lin = lo + (hi - lo) * u
    llo = np.log(np.where(lg, lo, 1.0))
    lhi = np.log(np.where(lg, hi, 2.0))
    logv = np.exp(llo + (lhi - llo) * u)
    return np.asarray(np.where(lg, logv, lin), dtype=np.float64)


def _seed(config: BuildConfig, *keys: str) -> np.random.Generator:
    words = [config.seed] + [zlib.crc32(k.encode()) for k in keys]
    return np.random.default_rng(np.random.SeedSequence(words))


@dataclass(frozen=True)
class FamilyFit:
    """Fitted PCEs of one family (arrays ready for the artifact).

    Attributes
    ----------
    arrays : dict
        Artifact members.
    outputs : dict
        Per output: degree, terms, LOO, ... of the piece's fit (of the
        head-struck side when the piece is split).
    split : dict or None
        For a piece split at the head-strike onset: the band, the run counts
        and the fits of the gate and of each side.
    """

    arrays: dict[str, npt.NDArray[Any]]
    outputs: dict[str, dict[str, Any]]
    split: dict[str, Any] | None = None


def _fit_output(
    psi: FloatArray,
    y: FloatArray,
    counts: npt.NDArray[np.int64],
    max_degree: int,
    n_boot: int,
    rng: np.random.Generator,
) -> tuple[SparseFit, list[SparseFit]]:
    point = fit_adaptive(psi, y, counts, max_degree)
    sub = psi[:, : counts[point.degree]]
    n = y.size
    boots: list[SparseFit] = []
    draws = 0
    while len(boots) < n_boot:
        draws += 1
        if draws > 4 * n_boot:
            raise RuntimeError("too many rank-deficient bootstrap replicates")
        rows = rng.integers(0, n, n)
        f = fit_degree(sub[rows], y[rows], point.degree)
        if np.isfinite(f.loo):  # rank-deficient replicates: LOO = inf, skipped
            boots.append(f)
    return point, boots


def _fit_outputs(
    spec: FamilySpec,
    psi: FloatArray,
    y: FloatArray,
    names: Sequence[str],
    counts: npt.NDArray[np.int64],
    config: BuildConfig,
    prefix: str,
    n_boot: int | None = None,
) -> tuple[dict[str, npt.NDArray[Any]], dict[str, dict[str, Any]]]:
    """Point and bootstrap PCEs of each column of `y` (physical values) on basis `psi`.

    `n_boot` replicates per output (default ``config.n_boot``; 0 for a point
    PCE only, as the gate of a split piece).
    """
    n_boot = config.n_boot if n_boot is None else n_boot
    arrays: dict[str, npt.NDArray[Any]] = {}
    info: dict[str, dict[str, Any]] = {}
    for j, name in enumerate(names):
        yt = to_output_scale(name, y[:, j])
        point, boots = _fit_output(
            psi,
            yt,
            counts,
            config.max_degree,
            n_boot,
            _seed(config, spec.name, prefix, name),
        )
        sizes = np.array([b.terms.size for b in boots], dtype=np.int64)
        key = prefix + name
        # compact storage: term indices < 2^15; bootstrap coefficients as float32
        # (relative rounding 6e-8, far below the replicate spread; the stored
        # values are the model, evaluated exactly as stored)
        arrays[f"{key}/point_terms"] = point.terms.astype(np.int16)
        arrays[f"{key}/point_coef"] = point.coef
        arrays[f"{key}/boot_offsets"] = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int32)
        arrays[f"{key}/boot_terms"] = np.concatenate(
            [np.zeros(0, dtype=np.int16)] + [b.terms.astype(np.int16) for b in boots]
        )
        arrays[f"{key}/boot_coef"] = np.concatenate(
            [np.zeros(0, dtype=np.float32)] + [b.coef.astype(np.float32) for b in boots]
        )
        arrays[f"{key}/boot_loo"] = np.array([b.loo for b in boots], dtype=np.float64)
        var_y = float(np.var(yt))
        info[name] = {
            "degree": point.degree,
            "n_terms": int(point.terms.size),
            "loo": point.loo,
            "loo_corrected": point.loo_corrected,
            "boot_n_terms_median": float(np.median(sizes)) if sizes.size else None,
            "sd_fitted_scale": float(np.sqrt(np.sum(point.coef[point.terms != 0] ** 2))),
            "sd_design": var_y**0.5,
            "n_runs": int(y.shape[0]),
        }
    return arrays, info


def fit_family(
    spec: FamilySpec,
    x: FloatArray,
    y: FloatArray,
    config: BuildConfig,
    ranges: tuple[tuple[float, float], ...] | None = None,
    prefix: str = "",
    clearance_mm: FloatArray | None = None,
) -> FamilyFit:
    """aPCE + bootstrapped PCE of every output on one design (one delta-V piece).

    Parameters
    ----------
    spec : FamilySpec
    x : ndarray, shape (n, 5)
        Raw design inputs.
    y : ndarray, shape (n, n_outputs)
        Physical LPM outputs (rows with NaN are dropped).
    config : BuildConfig
    ranges : tuple of (low, high), optional
        Design ranges (default ``spec.ranges``).
    prefix : str, optional
        Prepended to every array name (``"piece0/"``).
    clearance_mm : ndarray, shape (n,), optional
        Head clearance of each run (:class:`LpmRuns`). When both signs hold at
        least ``config.split_min_side_runs`` runs the piece is split: a gate
        PCE of the clearance on every run (``<prefix>gate/``) and the outputs
        fitted separately on the struck side (clearance below
        ``+split_band_mm``, ``<prefix>contact/``) and the free side (above
        ``-split_band_mm``, ``<prefix>free/``), on the piece's basis.

    Returns
    -------
    FamilyFit
    """
    rng_ = spec.ranges if ranges is None else ranges
    ok = np.all(np.isfinite(y), axis=1)
    if clearance_mm is not None:
        ok &= np.isfinite(clearance_mm)
    x, y = x[ok], y[ok]
    z = standardise(x, rng_)
    recs = [stieltjes(z[:, j], None, config.max_degree) for j in range(z.shape[1])]
    cand = hyperbolic_multi_indices(z.shape[1], config.max_degree, config.q_norm)
    counts = graded_counts(cand, config.q_norm, config.max_degree)
    psi = design_matrix(z, recs, cand)
    basis: dict[str, npt.NDArray[Any]] = {
        "candidates": cand.astype(np.int16),
        "recurrence_alpha": np.stack([r[0] for r in recs]),
        "recurrence_beta": np.stack([r[1] for r in recs]),
        "ranges": np.asarray(rng_, dtype=np.float64),
    }
    c = None if clearance_mm is None else np.asarray(clearance_mm, dtype=np.float64)[ok]
    n_struck = 0 if c is None else int(np.sum(c < 0.0))
    n_free = 0 if c is None else int(np.sum(c >= 0.0))
    if c is None or min(n_struck, n_free) < config.split_min_side_runs:
        arrays = {prefix + k: v for k, v in basis.items()}
        fitted, info = _fit_outputs(spec, psi, y, spec.outputs, counts, config, prefix)
        arrays.update(fitted)
        return FamilyFit(arrays, info)
    band = config.split_band_mm
    arrays = {}
    sides: dict[str, Any] = {}
    # the gate is a point PCE only: the point gate picks the side for every
    # replicate (evaluate._SplitPiece), so its bootstrap would not be used
    parts = (
        ("gate", np.ones(c.size, dtype=bool), c[:, None], (HEAD_CLEARANCE,), 0),
        ("contact", c < band, y, spec.outputs, config.n_boot),
        ("free", c > -band, y, spec.outputs, config.n_boot),
    )
    for side, rows, ys, names, nb in parts:
        sub = f"{prefix}{side}/"
        arrays.update({sub + k: v for k, v in basis.items()})
        fitted, info = _fit_outputs(spec, psi[rows], ys[rows], names, counts, config, sub, nb)
        arrays.update(fitted)
        sides[side] = info
    split = {
        "gate": HEAD_CLEARANCE,
        "band_mm": band,
        "n_struck": n_struck,
        "n_free": n_free,
        "fits": sides,
    }
    return FamilyFit(arrays, sides["contact"], split)


def _config_digest(spec: FamilySpec, config: BuildConfig, checks: Mapping[str, str]) -> str:
    blob = json.dumps(
        {
            "config": asdict(config),
            "family": {
                "name": spec.name,
                "ranges": spec.ranges,
                "outputs": spec.outputs,
                "belted": spec.belted,
                "airbag": spec.airbag_deployed,
            },
            "checks": dict(checks),
            "format": FORMAT_VERSION,
            "transforms": {
                "logit_clip": LOGIT_CLIP,
                "floors": MEASURE_FLOORS,
                "log_inputs": LOG_INPUTS,
            },
        },
        sort_keys=True,
    )
    return hashlib.sha256(blob.encode()).hexdigest()


def _checks() -> dict[str, str]:
    from models.lpm.fingerprint import lpm_code_sha256
    from models.lpm.params import load_parameter_set

    ps = load_parameter_set()
    lpm_code_sha256.cache_clear()  # the code may have changed since the last call
    return {
        "lpm_code_sha256": lpm_code_sha256(),
        "parameter_set": ps.name,
        "parameter_set_sha256": ps.sha256,
        "engine_version": ENGINE_VERSION,
    }


def _fit_kriging(
    spec: FamilySpec,
    piece_arrays: Mapping[str, npt.NDArray[Any]],
    piece_meta: Mapping[str, Any],
    prefix: str,
    x: FloatArray,
    y: FloatArray,
    max_runs: int,
) -> tuple[dict[str, FloatArray], dict[str, Any]]:
    """Kriging of one piece's point-PCE residuals on its design (models.surrogate.kriging).

    Parameters
    ----------
    piece_arrays : mapping
        The piece's fitted arrays (:func:`fit_family`).
    piece_meta : mapping
        The piece's metadata (``design_ranges``, ``split``), without ``kriging``.
    x : ndarray, shape (n, 5)
    y : ndarray, shape (n, n_outputs)
        The piece's design and LPM outputs (rows with a NaN are left out).
    max_runs : int
        The first `max_runs` finite rows are used (:attr:`BuildConfig.kriging_max_runs`).
    """
    from models.surrogate.pieces import _piece

    fitted = tuple(o for o in spec.outputs if o != "p_iss15")
    base = _piece(piece_arrays, fitted, prefix, piece_meta)
    ok = np.all(np.isfinite(y), axis=1)
    xs, ys = x[ok][:max_runs], y[ok][:max_runs]
    truth = np.stack([to_output_scale(o, ys[:, spec.outputs.index(o)]) for o in fitted], axis=1)
    residuals = truth - base.predict_raw(xs, 0)
    ranges = tuple((float(a), float(b)) for a, b in piece_meta["design_ranges"])
    return fit_residual_kriging(to_unit(xs, ranges), residuals, prefix)


def build_family(spec: FamilySpec, directory: Path, config: BuildConfig) -> dict[str, Any]:
    """Run the LPM on the design, fit, and write ``<directory>/<family>.npz``.

    Returns
    -------
    dict
        Timings (s) and the artifact's metadata.
    """
    from threadpoolctl import threadpool_limits  # type: ignore[import-untyped]

    from models.lpm.simulate import warm_up
    from models.surrogate.evaluate import SurrogateFamily

    with threadpool_limits(limits=1):
        t0 = time.perf_counter()
        warm_up()
        checks = _checks()
        lo = np.array([r[0] for r in spec.ranges])
        hi = np.array([r[1] for r in spec.ranges])
        arrays: dict[str, npt.NDArray[Any]] = {}
        pieces: list[dict[str, Any]] = []
        n_failed = 0
        t_lpm = t_fit = 0.0
        edges = config.delta_v_pieces_kmh
        for k, pr in enumerate(piece_ranges(spec.ranges, edges)):
            ta = time.perf_counter()
            u = latin_hypercube(
                config.n_train_for(spec.mode.value), lo.size, _seed(config, spec.name, f"design{k}")
            )
            x = from_unit(2.0 * u - 1.0, pr)
            runs = lpm_runs(spec, x)
            y, status = runs.y, runs.status
            tb = time.perf_counter()
            fam = fit_family(
                spec, x, y, config, pr, prefix=f"piece{k}/", clearance_mm=runs.head_clearance_mm
            )
            t_lpm += tb - ta
            t_fit += time.perf_counter() - tb
            n_failed += int(np.sum(status < 0))
            arrays.update(fam.arrays)
            arrays[f"piece{k}/design_x"] = x
            arrays[f"piece{k}/design_y"] = y
            arrays[f"piece{k}/design_head_clearance_mm"] = runs.head_clearance_mm
            piece: dict[str, Any] = {
                "delta_v_kmh": [edges[k], edges[k + 1]],
                "design_ranges": [list(r) for r in pr],
                "fits": fam.outputs,
            }
            if fam.split is not None:
                piece["split"] = fam.split
            tk = time.perf_counter()
            kriging, piece["kriging"] = _fit_kriging(
                spec, fam.arrays, piece, f"piece{k}/", x, y, config.kriging_max_runs
            )
            arrays.update(kriging)
            t_fit += time.perf_counter() - tk
            pieces.append(piece)
        ta = time.perf_counter()
        xh = lo + (hi - lo) * _seed(config, spec.name, "holdout").random(
            (config.n_holdout, lo.size)
        )
        runs_h = lpm_runs(spec, xh)
        yh, status_h = runs_h.y, runs_h.status
        t_lpm += time.perf_counter() - ta
        n_failed += int(np.sum(status_h < 0))
        meta: dict[str, Any] = {
            "format_version": FORMAT_VERSION,
            "family": spec.name,
            "mode": spec.mode.value,
            "body": spec.body.value,
            "belted": spec.belted,
            "airbag_deployed": spec.airbag_deployed,
            "inputs": [
                {"name": n, "low": r[0], "high": r[1]}
                for n, r in zip(INPUT_NAMES, spec.ranges, strict=True)
            ],
            "standardisation": "z = 2 (x - low) / (high - low) - 1",
            "basis": "aPCE: per-input orthonormal three-term recurrence of the design's "
            "empirical distribution (discretised Stieltjes) on z; hyperbolic multi-indices",
            "outputs": list(spec.outputs),
            "output_scale": {
                n: ("logit" if n == "p_iss15" else "identity" if n == "iss" else "log(x + floor)")
                for n in spec.outputs
            },
            "delta_v_pieces_kmh": list(edges),
            "pieces": pieces,
            "config": asdict(config),
            "config_sha256": _config_digest(spec, config, checks),
            "n_failed_runs": n_failed,
            "library_versions": {
                "numpy": np.__version__,
                "python": platform.python_version(),
            },
            **checks,
        }
        arrays["heldout_x"] = xh
        arrays["heldout_y"] = yh
        arrays["heldout_head_clearance_mm"] = runs_h.head_clearance_mm
        # timings vary run to run: kept out of the artifact bytes
        timing = {"lpm_seconds": t_lpm, "fit_seconds": t_fit}
        surrogate = SurrogateFamily.from_arrays(arrays, meta)
        meta["heldout"] = heldout_scores(spec, yh, surrogate.predict(xh))
        directory.mkdir(parents=True, exist_ok=True)
        write_artifact(directory / f"{spec.name}.npz", arrays, meta)
    return {"family": spec.name, **timing, "total_seconds": time.perf_counter() - t0}


def is_current(
    path: Path, spec: FamilySpec, config: BuildConfig, checks: Mapping[str, str] | None = None
) -> bool:
    """Whether the artifact at `path` was built with this configuration and LPM code.

    Compares the recorded digest of (configuration, family, LPM code and
    parameter-set checksums, engine version, format version).
    """
    if checks is None:
        checks = _checks()
    if not path.exists():
        return False
    try:
        _, meta = read_artifact(path)
    except ValueError:
        return False
    return bool(meta.get("config_sha256") == _config_digest(spec, config, checks))


def write_manifest(directory: Path, config: BuildConfig) -> dict[str, Any]:
    """Write ``manifest.json``: library identity, checks and each file's SHA-256."""
    from models.lpm.params import load_parameter_set
    from models.surrogate.golden import golden_record
    from models.surrogate.spec import FAMILIES

    checks = _checks()
    files = {p.name: sha256_file(p) for p in sorted(directory.glob("*.npz"))}
    built = {f[:-4] for f in files}
    golden = golden_record([s for s in FAMILIES if s.name in built], load_parameter_set())
    manifest = {
        "name": "lpm-pce-surrogates",
        "version": f"{FORMAT_VERSION}.{ENGINE_VERSION}",
        "format_version": FORMAT_VERSION,
        "seed": config.seed,
        "config": asdict(config),
        "families": sorted(f[:-4] for f in files),
        "files": files,
        # what the families depend on, rerun by the service at start
        "golden": golden,
        **checks,
    }
    write_json(directory / MANIFEST_NAME, manifest)
    return manifest
