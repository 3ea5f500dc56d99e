"""Build report: ``REPORT.md`` and PNG plots (matplotlib, Agg), like the paper's Table 2 / Figure 8.

Per family: degrees and LOO of every output and delta-V piece, the standard
deviation of each output under the default sensor errors at a nominal crash,
held-out errors against direct LPM runs (median relative error per measure,
ISS15+ decision agreement), a surrogate-vs-LPM scatter per mode and a
Figure-8-like plot of P(ISS >= 15) against delta-V with its bootstrap band.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from types import ModuleType
from typing import Any, Final

import numpy as np
import numpy.typing as npt

from models.impact_mode import ImpactMode
from models.offline.surrogate.coverage import (
    COVERAGE_SEED,
    MEASURE_DRAWS,
    coverage_check,
    measure_coverage_check,
)
from models.offline.surrogate.runs import (
    heldout_scores,
    lpm_outputs,
    relative_error,
    service_raw_threshold,
)
from models.offline.surrogate.validate import FRESH_N
from models.surrogate.evaluate import (
    EVALUATION_VERSION,
    N_SENSOR_SAMPLES,
    SurrogateFamily,
    SurrogateLibrary,
)
from models.surrogate.spec import (
    AGREEMENT_TARGET,
    FAMILIES,
    HEAD_CLEARANCE,
    LOGIT_CLIP,
    MEDIAN_ERROR_TARGET,
)

__all__ = [
    "COVERAGE_SEED",
    "NOMINAL",
    "coverage_check",
    "bare_families",
    "measure_coverage_check",
    "write_report",
]


#: Nominal crash of the table's standard deviations: delta-V (km/h), |angle|
#: (deg), posture (deg, neutral 5.8), seat track (mm), duration (ms).
NOMINAL = {
    "delta_v_kmh": 50.0,
    "angle_deg": 0.0,
    "posture_deg": 5.8,
    "seat_track_mm": 0.0,
    "duration_ms": 90.0,
}


def _sd_under_sensor_error(fam: SurrogateFamily) -> dict[str, float]:
    """Standard deviation of each output over the sensor samples (point PCE)."""
    from models.surrogate.evaluate import (
        _NORMALS,
        DEFAULT_POSTURE_SD_DEG,
        DEFAULT_SEAT_TRACK_SD_MM,
    )

    n = _NORMALS.shape[0]
    x = np.tile([NOMINAL[k] for k in NOMINAL], (n, 1))
    x[:, 2] = np.clip(x[:, 2] + DEFAULT_POSTURE_SD_DEG * _NORMALS[:, 0], 0.0, 25.0)
    x[:, 3] = np.clip(x[:, 3] + DEFAULT_SEAT_TRACK_SD_MM * _NORMALS[:, 1], -120.0, 120.0)
    y = fam.predict(x)
    return {o: float(np.std(y[:, k])) for k, o in enumerate(fam.outputs)}


def bare_families(artifact_dir: Path) -> dict[str, SurrogateFamily]:
    """The artifacts' families assembled without their held-out runs.

    Their measure and ISS intervals are the bare sensor x bootstrap percentiles
    and their P(ISS >= 15) interval is not widened: the comparison of the
    report's Table D.
    """
    from models.surrogate.store import read_artifact

    out = {}
    for path in sorted(Path(artifact_dir).glob("*.npz")):
        arrays, meta = read_artifact(path)
        kept = {k: v for k, v in arrays.items() if not k.startswith("heldout_")}
        fam = SurrogateFamily.from_arrays(kept, meta)
        out[fam.name] = fam
    return out


def _measure_coverage_table(lib: SurrogateLibrary, artifact_dir: Path, n_cases: int) -> list[str]:
    served = measure_coverage_check(lib.families(), n_cases)
    bare = measure_coverage_check(bare_families(artifact_dir), n_cases)
    lines = [
        "",
        "## Table D: coverage of the measure and ISS intervals",
        "",
        f"{n_cases} random in-domain readings (seeded, as in Table C); at each, "
        f"{MEASURE_DRAWS} true sensor values drawn independently from the default sensor error "
        "and run through the LPM. The share of those outcomes inside the served 95% interval, "
        "averaged over the cases (an honest 95% interval: about 0.95 or more), with the "
        "served interval and with the bare sensor x bootstrap percentiles. The served interval "
        "adds, in quadrature to each side about the point value, the surrogate's own error at the "
        "reading: a held-out calibrated factor (split conformal, the ceil((n + 1) 0.95) / n "
        "quantile of |y_LPM - y_PCE| over the bootstrap standard deviation on the fitted scale) "
        "times the bootstrap standard deviation there. Where the sensors hardly move a measure "
        "(most side cases) an error of a few per cent put every LPM outcome outside the bare "
        "interval.",
        "",
        "| output | cases | served interval | bare percentiles | cases under 80 % (served / bare)"
        " |",
        "|---|---|---|---|---|",
    ]
    for out, v in served.items():
        b = np.asarray(bare.get(out, [np.nan]))
        a = np.asarray(v)
        lines.append(
            f"| {out} | {a.size} | {a.mean():.3f} | {np.mean(b):.3f} | "
            f"{int(np.sum(a < 0.8))} / {int(np.sum(b < 0.8))} |"
        )
    lines += [
        "",
        "Factors (bootstrap standard deviations) per family: "
        + "; ".join(
            f"{f.name} " + ", ".join(f"{k} {v:.1f}" for k, v in f.interval_factors.items())
            for f in (lib.families()[n] for n in lib.family_names)
        )
        + ".",
    ]
    return lines


def _fmt(v: float) -> str:
    return f"{v:.3g}"


#: Cases of the coverage check in the report: about 35 s of direct LPM runs; with
#: 24 the share moved by +-8 points between draws of the same library.
COVERAGE_CASES = 120


def _header(lib: SurrogateLibrary) -> list[str]:
    """Which library, from which code and parameters, on which design."""
    cfg = lib.manifest.get("config", {})
    return [
        "# PCE surrogate build report (issue 5)",
        "",
        f"Library `{lib.name}` version {lib.version}, manifest sha256 `{lib.sha256[:16]}...`; "
        f"LPM code `{lib.lpm_code_sha256[:16]}...`, parameter set "
        f"`{lib.manifest.get('parameter_set')}` `{lib.parameter_set_sha256[:16]}...`, "
        f"engine {lib.engine_version}, seed {lib.manifest.get('seed')}.",
        "",
        f"Design: Latin hypercube of {cfg.get('n_train')} LPM runs per delta-V piece"
        + "".join(f" ({m}: {n})" for m, n in cfg.get("n_train_by_mode", []))
        + ", pieces "
        f"{cfg.get('delta_v_pieces_kmh')} km/h (log-scale delta-V and duration), "
        f"{cfg.get('n_holdout')} held-out uniform points per family over the whole domain; "
        f"hyperbolic truncation q = {cfg.get('q_norm')}, degree adaptive up to "
        f"{cfg.get('max_degree')}; {cfg.get('n_boot')} bootstrap replicates with the LAR "
        "selection rerun in each.",
        "",
    ]


def _design_choices(
    fams: list[SurrogateFamily], held: Mapping[str, Mapping[str, Any]], cfg: Mapping[str, Any]
) -> list[str]:
    """The choices behind the surrogates and the open items of the held-out check."""
    return [
        "## Design choices",
        "",
        "- Families: frontal x {50M, 5F} x {belted, unbelted} x {airbag, no airbag} (8); near "
        "side x {50M, 5F} x {belted, unbelted} x {side airbags, none} (8); rear and far side x "
        "{50M, 5F} x {belted, unbelted}, shared between airbag states because no airbag acts "
        "in those LPMs (rear: the frontal airbag only with an explicit firing time, which is "
        "then outside the surrogates) (8). 24 families.",
        "- Inputs: delta-V 5-120 km/h (above: clamped to 120 and flagged, a lower bound since "
        "the LPMs saturate; below 5: clamped), |angle from the mode axis| within coverage "
        "(frontal 0-30, rear 0-40, sides 0-20 deg; the planar LPMs see only the on-axis "
        "component), posture 0-25 deg, seat track -120..120 mm, haversine duration "
        "40-150 ms (clamped and flagged outside). Delta-V and duration on a log scale.",
        "- Delta-V pieces: one PCE set per piece; a single PCE over 5-120 km/h left 10-16% "
        "median error on HIC and Nij. Pieces cost build time, not request time (one piece "
        "is evaluated per request, two blended with a smoothstep within 10% of a piece's "
        "log width of an edge, so the surrogate is continuous in delta-V).",
        "- Outputs: each measure as log(x + floor), P(ISS>=15) as logit (clipped at "
        f"{LOGIT_CLIP:g}), "
        "ISS directly (clipped to 0-75 after evaluation).",
        f"- Evaluation (version {EVALUATION_VERSION}): P(ISS>=15) is served from the "
        "surrogate measures through the risk curves and the exact ISS sum "
        "(models.injury.batch), the function a direct LPM case applies, not from its own "
        "PCE (still fitted and shipped); Tables B and C use the served value.",
        "- Bootstrap: rows resampled, LAR selection and the number of terms rerun in every "
        "replicate at the point fit's degree; rank-deficient replicates are redrawn.",
        "- Head-strike split: where the head meets the rigid interior (wheel, glass, panel, "
        "dash; side window; far door) in part of a piece's design, HIC15 and Nij are hinged "
        "(flat, then rising with the penetration). Such a piece (both sides with at least "
        f"{cfg.get('split_min_side_runs')} runs) is fitted on each side of the onset, with a "
        "gate PCE of the head's least clearance over the run (mm, signed) choosing the side "
        f"and a smoothstep blend within +-{cfg.get('split_band_mm')} mm of zero (Table E).",
        "- Kriging of the residuals (PC-Kriging, sequential form: Kersaudy et al. 2015, "
        "J. Comput. Phys. 286): each piece's point-PCE residuals on its design runs are "
        "kriged with one anisotropic Matern 3/2 kernel shared by the piece's outputs "
        "(scikit-learn, maximum likelihood) and the correction is added to the point PCE and "
        "to every bootstrap replicate alike (Table F). It recovers part of the hinges the "
        "polynomial rounds off; the request path evaluates it in numpy.",
        "",
        "## Open items",
        "",
        "- Held-out median relative error above 5% (Table B): "
        + _misses(fams, held)
        + ". Causes: hinges in posture, seat track and pulse duration where a contact starts "
        "(the head striking the interior) and where the HIC window or the Nij load case "
        "switches; larger designs shrink them (BuildConfig.n_train_by_mode: what was measured). "
        "tests/surrogate holds HIC15/Nij of its test family to a 20% regression bound and "
        "keeps the 5% check as an xfail.",
        "- ISS15+ decision agreement (P >= 0.5) at or below 97%: "
        + _agreement_misses(fams, held)
        + ".",
        "- ISS is a step function of the measures; its surrogate is a smooth approximation "
        "(median absolute error in Table B); the ISS15+ decision uses P(ISS>=15) >= 0.5.",
        "",
    ]


def _table_a(fams: list[SurrogateFamily]) -> list[str]:
    """Degree, LOO, terms and sensor-error spread of every output."""
    lines = [
        "## Table A: degree and LOO per output (median over the delta-V pieces and the "
        "sides of split pieces [min-max])",
        "",
        "| family | output | degree | LOO | terms | sd at nominal crash |",
        "|---|---|---|---|---|---|",
    ]
    for fam in fams:
        sd = _sd_under_sensor_error(fam)
        for o in fam.outputs:
            fits = [f for p in fam.meta["pieces"] for f in _piece_fits(p, o)]
            deg = [f["degree"] for f in fits]
            loo = [f["loo"] for f in fits]
            terms = [f["n_terms"] for f in fits]
            lines.append(
                f"| {fam.name} | {o} | {int(np.median(deg))} [{min(deg)}-{max(deg)}] | "
                f"{_fmt(float(np.median(loo)))} [{_fmt(min(loo))}-{_fmt(max(loo))}] | "
                f"{int(np.median(terms))} | {_fmt(sd[o])} |"
            )
    lines += [
        "",
        "LOO is relative to the output variance on its fitted scale (log measure, logit "
        "P(ISS>=15), ISS). The sd column is the standard deviation of the physical output "
        "under the default sensor errors (posture 5 deg, seat track 50 mm at 95%) at "
        f"the nominal crash {NOMINAL} (paper Table 2 analogue).",
        "",
    ]
    return lines


def _table_b(
    artifact_dir: Path, fams: list[SurrogateFamily], held: Mapping[str, Mapping[str, Any]]
) -> list[str]:
    """Held-out errors and decision agreement against direct LPM runs."""
    lines = [
        "## Table B: held-out check against direct LPM runs",
        "",
        "Median relative error per measure; P(ISS>=15) and ISS as median absolute error; "
        "ISS15+ agreement: the decision P(ISS>=15) >= 0.5 (and ISS >= 15) of the surrogate "
        "vs the LPM. These held-out points were looked at while the designs were chosen; "
        "VALIDATION.md (`aacn-triage validate-surrogates`) repeats the check on "
        f"{FRESH_N} fresh points per family that no build decision has seen.",
        "",
    ]
    measures = sorted({o for f in fams for o in f.outputs if o not in ("p_iss15", "iss")})
    lines.append(
        "| family | n | "
        + " | ".join(measures)
        + " | P abs | ISS abs | agree P>=0.5 | agree ISS>=15 | LPM ISS15+ share |"
    )
    lines.append("|---" * (len(measures) + 7) + "|")
    for fam in fams:
        h = held[fam.name]
        cells = [f"{100 * h[m]['median_rel_error']:.1f}%" if m in h else "-" for m in measures]
        lines.append(
            f"| {fam.name} | {h['n']} | "
            + " | ".join(cells)
            + f" | {h['p_iss15']['median_abs_error']:.3f} | {h['iss']['median_abs_error']:.1f}"
            f" | {100 * h['decision_agreement_p']:.1f}% | {100 * h['decision_agreement_iss']:.1f}%"
            f" | {100 * h['iss15_share_lpm']:.0f}% |"
        )
    lines += ["", "Pooled over all families:", ""]
    lines += [f"- {k}: {v}" for k, v in _pooled(artifact_dir, fams).items()]
    return lines


def _table_c(lib: SurrogateLibrary, fams: list[SurrogateFamily], coverage_cases: int) -> list[str]:
    """Coverage of the served P(ISS>=15) interval by Monte Carlo LPM runs."""
    cov = coverage_check(lib, coverage_cases)
    hits = sum(c["hit"] for c in cov)
    open_cases = [c for c in cov if 1e-3 < c["mc"] < 1.0 - 1e-3]
    open_hits = sum(c["hit"] for c in open_cases)
    lines = [
        "",
        "## Table C: coverage of the P(ISS>=15) interval",
        "",
        f"{hits} of {len(cov)} cases ({100 * hits / len(cov):.0f}%) have the Monte Carlo "
        f"value (mean of {N_SENSOR_SAMPLES} direct LPM runs at the sensor sample points, "
        "default sensor "
        "errors around random in-domain readings) inside the served 95% interval "
        f"(issue 5 target: >= 90%). Cases with a non-saturated Monte Carlo value "
        f"(0.001 < P < 0.999): {open_hits} of {len(open_cases)}.",
        "",
        "The served interval is the bootstrap interval widened on the logit scale by a "
        "factor calibrated on each family's held-out LPM runs (split-conformal, the 95% "
        "quantile of |logit P_LPM - logit P_surrogate| over the bootstrap standard "
        "deviation, over 1.96): the replicates see how the fit moves with the design, not "
        "the error of the polynomial where the LPM response has kinks (the bare bootstrap "
        "interval of the former P PCE covered 84% of 73 non-saturated cases of this "
        "check). Factors: "
        + "; ".join(f"{f.name} {f.p_interval_inflation:.2f}" for f in fams)
        + ".",
        "",
        "| family | dv, angle, posture, seat, T | P surrogate | 95% interval | P Monte Carlo |"
        " inside |",
        "|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {c['family']} | {c['x']} | {c['p']:.4f} | [{c['ci95'][0]:.4f}, "
        f"{c['ci95'][1]:.4f}] | {c['mc']:.4f} | {'yes' if c['hit'] else 'NO'} |"
        for c in cov
    ]
    return lines


def _scatter_plots(
    plt: ModuleType, artifact_dir: Path, fams: list[SurrogateFamily], out_dir: Path
) -> list[str]:
    """One surrogate-vs-LPM scatter per mode; returns the file names."""
    pngs = []
    for mode in ImpactMode:
        mf = [f for f in fams if f.meta["mode"] == mode.value]
        if not mf:
            continue
        outs = mf[0].outputs
        fig, axes = plt.subplots(
            len(mf), len(outs), figsize=(2.2 * len(outs), 2.0 * len(mf)), squeeze=False
        )
        for i, fam in enumerate(mf):
            xh, yh = _heldout(artifact_dir, fam)
            yp = fam.predict(xh)
            for j, o in enumerate(outs):
                ax = axes[i, j]
                ax.scatter(yh[:, j], yp[:, j], s=4, alpha=0.6)
                lo = float(np.nanmin([yh[:, j].min(), yp[:, j].min()]))
                hi = float(np.nanmax([yh[:, j].max(), yp[:, j].max()]))
                ax.plot([lo, hi], [lo, hi], "k-", lw=0.6)
                if o not in ("p_iss15", "iss") and lo > 0:
                    ax.set_xscale("log")
                    ax.set_yscale("log")
                ax.tick_params(labelsize=5)
                if i == 0:
                    ax.set_title(o, fontsize=7)
                if j == 0:
                    ax.set_ylabel(fam.name.split("__", 1)[1], fontsize=5)
        fig.suptitle(f"{mode.value}: surrogate (y) vs LPM (x), held-out points", fontsize=8)
        fig.tight_layout()
        name = f"report_scatter_{mode.value}.png"
        fig.savefig(out_dir / name, dpi=110)
        plt.close(fig)
        pngs.append(name)
    return pngs


def _band_plot(plt: ModuleType, fams: list[SurrogateFamily], out_dir: Path) -> str:
    """The paper's Figure 8 analogue: P(ISS>=15) against delta-V with its band."""
    fr = [f for f in fams if f.meta["mode"] == "frontal"] or fams
    fig, axes = plt.subplots(1, min(4, len(fr)), figsize=(12, 3), squeeze=False)
    dvs = np.linspace(5.0, 120.0, 93)
    for ax, fam in zip(axes[0], fr[:4], strict=False):
        pts, los, his = [], [], []
        for dv in dvs:
            r = fam.propagate(
                delta_v_kmh=float(dv),
                angle_deg=0.0,
                posture_deg=NOMINAL["posture_deg"],
                seat_track_mm=NOMINAL["seat_track_mm"],
                duration_ms=NOMINAL["duration_ms"],
            )
            pts.append(r.p_iss15)
            los.append(r.p_iss15_ci95[0])
            his.append(r.p_iss15_ci95[1])
        ax.fill_between(dvs, los, his, alpha=0.3, label="bPCE 95%")
        ax.plot(dvs, pts, "b-", lw=1, label="aPCE")
        dv_check, p_check = _lpm_band_points(fam)
        ax.plot(dv_check, p_check, "ko", ms=3, label="LPM (mean over sensor samples)")
        ax.set_title(fam.name.split("__", 1)[1], fontsize=7)
        ax.set_xlabel("delta-V (km/h)", fontsize=7)
        ax.set_ylabel("P(ISS>=15)", fontsize=7)
        ax.tick_params(labelsize=6)
        ax.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(out_dir / "report_p_iss15_band.png", dpi=110)
    plt.close(fig)
    return "report_p_iss15_band.png"


def write_report(artifact_dir: Path, out_dir: Path, coverage_cases: int = COVERAGE_CASES) -> Path:
    """Write ``REPORT.md`` and ``report_*.png`` into `out_dir` from the artifacts.

    Parameters
    ----------
    artifact_dir : Path
    out_dir : Path
    coverage_cases : int, optional
        Cases of :func:`coverage_check` (``N_SENSOR_SAMPLES`` LPM runs each; 0 skips it).

    Returns
    -------
    Path
        The report file.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lib = SurrogateLibrary.load(artifact_dir, require_all=False)
    timings: dict[str, Any] = {}
    tpath = out_dir / "build_timings.json"
    if tpath.exists():
        timings = json.loads(tpath.read_text())
    fams = [lib.families()[s.name] for s in FAMILIES if s.name in lib.family_names]
    held = {f.name: heldout_metrics(artifact_dir, f) for f in fams}
    lines = _header(lib) + _design_choices(fams, held, lib.manifest.get("config", {}))
    if timings:
        lines += [
            f"Build time: {timings['total_seconds']:.0f} s with {timings['workers']} worker "
            f"processes for {len(timings['families'])} families (see benchmarks/RESULTS.md).",
            "",
        ]
    lines += _table_a(fams)
    lines += _table_b(artifact_dir, fams, held)
    if coverage_cases:
        lines += _table_c(lib, fams, coverage_cases)
        lines += _measure_coverage_table(lib, artifact_dir, coverage_cases)
    lines += _split_table(artifact_dir, fams)
    lines += _kriging_table(artifact_dir, fams)
    out_dir.mkdir(parents=True, exist_ok=True)
    pngs = _scatter_plots(plt, artifact_dir, fams, out_dir)
    pngs.append(_band_plot(plt, fams, out_dir))
    lines += ["", "## Plots", ""] + [f"![{p}]({p})" for p in pngs]
    lines += [
        "",
        "`report_p_iss15_band.png`: P(ISS>=15) of frontal families against delta-V at the "
        "nominal posture, seat track and 90 ms duration, with the default sensor errors; the "
        "band is the served 95% interval, the dots the mean P(ISS>=15) of direct LPM runs "
        "at the same sensor samples (paper Figure 8 analogue).",
        "",
    ]
    path = out_dir / "REPORT.md"
    path.write_text("\n".join(lines))
    return path


def _heldout(
    artifact_dir: Path, fam: SurrogateFamily
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    from models.surrogate.store import read_artifact

    arrays, _ = read_artifact(artifact_dir / f"{fam.name}.npz")
    return np.asarray(arrays["heldout_x"]), np.asarray(arrays["heldout_y"])


def _piece_fits(piece: Mapping[str, Any], output: str) -> list[Mapping[str, Any]]:
    """Fit records of one output in a piece: both sides of a split piece."""
    split = piece.get("split")
    if split is None:
        return [piece["fits"][output]]
    return [split["fits"][side][output] for side in ("contact", "free")]


def _split_table(artifact_dir: Path, fams: list[SurrogateFamily]) -> list[str]:
    """Table E: the pieces split at the head-strike onset and how well the gate sorts."""
    from models.surrogate.store import read_artifact

    rows = []
    for fam in fams:
        pieces = fam.meta["pieces"]
        if not any("split" in p for p in pieces):
            continue
        arrays, _ = read_artifact(artifact_dir / f"{fam.name}.npz")
        xh = np.asarray(arrays["heldout_x"])
        ch = np.asarray(arrays["heldout_head_clearance_mm"])
        gate = fam.head_clearance(xh)
        for p in pieces:
            sp = p.get("split")
            if sp is None:
                continue
            lo, hi = p["delta_v_kmh"]
            inside = (xh[:, 0] >= lo) & (xh[:, 0] < hi) & np.isfinite(ch) & np.isfinite(gate)
            n_in = int(inside.sum())
            agree = float(np.mean((gate[inside] < 0.0) == (ch[inside] < 0.0))) if n_in else 0.0
            g = sp["fits"]["gate"][HEAD_CLEARANCE]
            rows.append(
                f"| {fam.name} | {lo:g}-{hi:g} | {sp['n_struck']} / {sp['n_free']} | "
                f"{g['degree']} | {_fmt(g['loo'])} | "
                + (f"{100 * agree:.0f}% of {n_in}" if n_in else "-")
                + " |"
            )
    if not rows:
        return []
    return [
        "",
        "## Table E: delta-V pieces split at the head-strike onset",
        "",
        "Design runs with the head striking the rigid interior / staying clear; the gate PCE "
        "of the head clearance (degree, relative LOO); how often its sign matches the LPM's on "
        "the held-out points of the piece's interval.",
        "",
        "| family | delta-V km/h | runs struck / clear | gate degree | gate LOO | "
        "sign agreement (held out) |",
        "|---|---|---|---|---|---|",
        *rows,
    ]


def without_kriging(fam: SurrogateFamily, artifact_dir: Path) -> SurrogateFamily:
    """The family with the Kriging of its residuals left out: its PCEs alone."""
    from models.surrogate.store import read_artifact

    arrays, meta = read_artifact(artifact_dir / f"{fam.name}.npz")
    meta = dict(meta)
    meta["pieces"] = [{k: v for k, v in p.items() if k != "kriging"} for p in meta["pieces"]]
    return SurrogateFamily.from_arrays(arrays, meta)


#: Measures of Table F (the ones with held-out medians above 5 % before the Kriging).
_KRIGING_TABLE_MEASURES: Final[tuple[str, ...]] = (
    "hic15",
    "nij",
    "chest_deflection_mm",
    "chest_vc_m_s",
)


def _kriging_table(artifact_dir: Path, fams: list[SurrogateFamily]) -> list[str]:
    """Table F: held-out errors of the PCEs alone and with the Kriging of their residuals."""

    rows = []
    for fam in fams:
        if not any(p.get("kriging") for p in fam.meta["pieces"]):
            continue
        spec = next(s for s in FAMILIES if s.name == fam.name)
        xh, yh = _heldout(artifact_dir, fam)
        both = heldout_scores(spec, yh, fam.predict(xh))
        alone = heldout_scores(spec, yh, without_kriging(fam, artifact_dir).predict(xh))
        cells = [
            f"{100 * alone[m]['median_rel_error']:.1f} -> {100 * both[m]['median_rel_error']:.1f}%"
            if m in both
            else "-"
            for m in _KRIGING_TABLE_MEASURES
        ]
        rows.append(
            f"| {fam.name} | "
            + " | ".join(cells)
            + f" | {100 * alone['decision_agreement_p']:.1f} -> "
            f"{100 * both['decision_agreement_p']:.1f}% |"
        )
    if not rows:
        return []
    return [
        "",
        "## Table F: the Kriging of the PCE residuals (held out)",
        "",
        "Each piece's residuals on its design runs (LPM minus point PCE, fitted scale) are "
        "kriged (Matern 3/2, one anisotropic kernel per piece shared by its outputs; "
        "models.surrogate.kriging, after Kersaudy et al. 2015) and the correction is added to "
        "the point PCE and every bootstrap replicate. Median relative error and ISS15+ "
        "agreement on the held-out points: PCE alone -> PCE + Kriging.",
        "",
        "| family | " + " | ".join(_KRIGING_TABLE_MEASURES) + " | agree P>=0.5 |",
        "|---" * (len(_KRIGING_TABLE_MEASURES) + 2) + "|",
        *rows,
    ]


#: Delta-V values (km/h) of the direct LPM check points on the band plot.
BAND_CHECK_DELTA_V_KMH = (10.0, 25.0, 40.0, 55.0, 70.0, 85.0, 100.0, 115.0)


def _lpm_band_points(fam: SurrogateFamily) -> tuple[list[float], list[float]]:
    """Mean LPM P(ISS >= 15) over the sensor samples at the band plot's nominal inputs."""
    from models.surrogate.evaluate import (
        _NORMALS,
        DEFAULT_POSTURE_SD_DEG,
        DEFAULT_SEAT_TRACK_SD_MM,
    )

    spec = next(s for s in FAMILIES if s.name == fam.name)
    out = []
    for dv in BAND_CHECK_DELTA_V_KMH:
        x = np.tile(
            [dv, 0.0, NOMINAL["posture_deg"], NOMINAL["seat_track_mm"], NOMINAL["duration_ms"]],
            (_NORMALS.shape[0], 1),
        )
        x[:, 2] = np.clip(x[:, 2] + DEFAULT_POSTURE_SD_DEG * _NORMALS[:, 0], 0.0, 25.0)
        x[:, 3] = np.clip(x[:, 3] + DEFAULT_SEAT_TRACK_SD_MM * _NORMALS[:, 1], -120.0, 120.0)
        y, _ = lpm_outputs(spec, x)
        out.append(float(np.nanmean(y[:, spec.outputs.index("p_iss15")])))
    return list(BAND_CHECK_DELTA_V_KMH), out


def heldout_metrics(artifact_dir: Path, fam: SurrogateFamily) -> dict[str, Any]:
    """Held-out figures of a family with the current evaluation (Table B).

    Recomputed from the artifact's stored held-out LPM runs rather than read
    from its metadata (written at build time): a change of the evaluation,
    such as P(ISS >= 15) from the measures (evaluation version 3), shows
    without a rebuild.
    """

    spec = next(s for s in FAMILIES if s.name == fam.name)
    xh, yh = _heldout(artifact_dir, fam)
    return heldout_scores(spec, yh, fam.predict(xh))


def _misses(fams: list[SurrogateFamily], held: Mapping[str, Mapping[str, Any]]) -> str:
    out = []
    for fam in fams:
        h = held[fam.name]
        bad = [
            f"{o} {100 * h[o]['median_rel_error']:.0f}%"
            for o in fam.outputs
            if o in h
            and "median_rel_error" in h[o]
            and h[o]["median_rel_error"] > MEDIAN_ERROR_TARGET
        ]
        if bad:
            out.append(f"{fam.name} ({', '.join(bad)})")
    return "; ".join(out) if out else "none"


def _agreement_misses(fams: list[SurrogateFamily], held: Mapping[str, Mapping[str, Any]]) -> str:
    out = [
        f"{f.name} {100 * held[f.name]['decision_agreement_p']:.1f}%"
        for f in fams
        if held[f.name]["decision_agreement_p"] <= AGREEMENT_TARGET
    ]
    return "; ".join(out) if out else "none"


def _pooled(artifact_dir: Path, fams: list[SurrogateFamily]) -> dict[str, str]:

    rel: dict[str, list[float]] = {}
    agree: list[bool] = []
    agree_iss: list[bool] = []
    agree_service: list[bool] = []
    for fam in fams:
        thr = service_raw_threshold(fam.name, fam.outputs)
        xh, yh = _heldout(artifact_dir, fam)
        ok = np.all(np.isfinite(yh), axis=1)
        xh, yh = xh[ok], yh[ok]
        yp = fam.predict(xh)
        for k, o in enumerate(fam.outputs):
            if o == "p_iss15":
                agree += list((yh[:, k] >= 0.5) == (yp[:, k] >= 0.5))
                agree_service += list((yh[:, k] >= thr) == (yp[:, k] >= thr))
            elif o == "iss":
                agree_iss += list((yh[:, k] >= 15) == (yp[:, k] >= 15))
            else:
                r = relative_error(yp[:, k], yh[:, k])
                rel.setdefault(o, []).extend(r.tolist())
    out = {
        f"{o} median relative error": f"{100 * float(np.median(v)):.1f}%" for o, v in rel.items()
    }
    out["ISS15+ agreement (P >= 0.5)"] = f"{100 * float(np.mean(agree)):.1f}%"
    out["ISS15+ agreement (ISS >= 15)"] = f"{100 * float(np.mean(agree_iss)):.1f}%"
    out[
        "ISS15+ agreement at the service's decision (zero-load-corrected P >= 0.10 frontal/rear,"
        " 0.05 side)"
    ] = f"{100 * float(np.mean(agree_service)):.1f}%"
    return out
