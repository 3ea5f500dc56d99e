"""The whole field risk fit (:func:`fit_risk`): stages, figures and the artifact document.

See :mod:`.risk_fit` for the method. Each stage is cached under ``--cache``
(keyed by the settings), so a fit interrupted at any stage resumes there.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np
from sklearn.ensemble import HistGradientBoostingClassifier
from tqdm import tqdm

from models.arrays import FloatArray, IntArray
from models.field.features import FieldInputs, FieldMode
from models.field.measurement import (
    MEASUREMENT_MODEL,
)
from models.field.model import FieldModel
from models.field.risk_children import ALL_COLUMNS_3
from models.field.risk_model import (
    ARTIFACT_SCHEMA,
    OUTCOME,
    canonical_content_sha256,
    feature_code_sha256,
)
from models.field.versions import artifact_for_version
from models.offline.field.metrics import threshold_for_sensitivity
from models.offline.field.occupants import OCCUPANTS_CSV, POPULATION_RULES
from models.offline.field.published import NHTSA_ALL
from models.offline.field.risk_blend import BlendFitted
from models.offline.field.risk_boosted import BoostedFitted
from models.offline.field.risk_core import Fitted, crash_folds, expit, fit_model
from models.offline.field.risk_data import Outcome
from models.offline.field.risk_fit import (
    REGRESSION_GROUPS,
    RiskConfig,
    RiskData,
    Spec,
    _Cache,
    choose_drift,
    fit_spec,
    load_risk_data,
    noisy_or_logit,
    select_spec,
    temporal_probability,
    vehicle_recalibration,
    vehicle_table,
)
from models.offline.field.risk_knowledge import (
    donor_table_of,
    integrated_oof,
    knowledge_extras,
)
from models.offline.field.risk_metrics import (
    crash_resamples,
    score,
    target_with_margin,
    threshold_figures,
    tier_figures,
    triage_figures,
)
from models.tiers import HIGH_RISK_THRESHOLD
from models.units import kmh_to_mph

__all__ = ["MODEL_NAME", "MODEL_VERSION", "RiskFit", "fit_risk", "target_with_margin"]

MODEL_NAME: Final[str] = "field_iss15"
#: 3.0.0 (2026-12-06): ISS 15+ fitted on NASS-CDS 1997-2014 (issue 38); the
#: MAIS 3+ model 2.0.0 stays loadable for recalls.
#: 3.1.0 (2026-12-06): a bag of boosted trees where cross-validation prefers it;
#: held-out figures and the drift treatment scored as served (no accident-year
#: term chosen); the default point's margin over the positives the check counts.
#: 3.2.0 (2026-12-06): feature set 2 (:mod:`models.field.risk_impacts`): the
#: trees may split on the PDOF seen from the occupant's side and the impact count,
#: the regression may keep the count; a third kind, a blend of the two.
#: 3.3.0 (2026-12-07): feature set 3 (:mod:`models.field.risk_children`): the
#: decision fitted on every occupant with a known age, children included, with child
#: terms (a decision-only refit, :mod:`.risk_decision`: the region models are 3.2.0's);
#: unknown inputs integrated over a donor table (:mod:`models.field.unknowns`); a
#: measured delta-V read through the delta-V measurement model
#: (:mod:`models.field.measurement`); thresholds by what is known (adults, children,
#: ages unknown; each with a measured delta-V).
#: 3.3.1 (2026-12-07): the same fitted models and thresholds; a measured delta-V read
#: through the measurement model 1.2.0 (a side crash's ratio of its own, Johnson &
#: Gabler), and the held-out check of that reading with measured delta-V
#: (:mod:`.risk_measured`, the model card and ``docs/field/measured_check.json``).
#: 3.4.0 (2026-12-07): the same shared model (3.3.1's selection, ``--selection-from``),
#: with the children's own calibration by age group and child seat, with the weights
#: (:mod:`models.field.children_calibration`); the thresholds by knowledge and every
#: held-out figure follow it.
MODEL_VERSION: Final[str] = "3.4.0"

#: Groups of the plain regression: linear main effects of every notification
#: field, unpenalised, no splines or interactions (the reference to match).
PLAIN_COLUMNS: Final[tuple[str, ...]] = tuple(
    (
        "intercept delta_v_kmh near_side far_side rear belted airbag_deployed "
        "airbag_not_deployed driver front_middle row2 row3 age_years female stature_cm "
        "mass_kg rollover multiple_impacts impact_count model_year"
    ).split()
)


@dataclass
class RiskFit:
    """What a fit produced: the artifact document, its figures and held-out predictions."""

    artifact: dict[str, Any]
    figures: dict[str, Any]
    oof: dict[str, FloatArray]
    data: RiskData


def _cols(names: Sequence[str]) -> list[int]:
    return [ALL_COLUMNS_3.index(n) for n in names]


def _fixed_oof(
    d: RiskData,
    y: FloatArray,
    cols: Sequence[int],
    folds: Sequence[tuple[IntArray, IntArray]],
    c: float | None,
) -> FloatArray:
    p = np.empty(y.size)
    for tr, te in folds:
        p[te] = fit_model(d.x[tr], y[tr], d.w[tr], cols, c).probability(d.x[te])
    return p


def _hgb_oof(
    d: RiskData, y: FloatArray, folds: Sequence[tuple[IntArray, IntArray]], seed: int
) -> FloatArray:
    """Out-of-fold probability of a boosted model (HistGradientBoosting) on every column."""
    p = np.empty(y.size)
    for tr, te in tqdm(folds, desc="boosted comparison", leave=False):
        m = HistGradientBoostingClassifier(
            max_iter=300, learning_rate=0.05, max_leaf_nodes=15, random_state=seed
        )
        m.fit(d.x[tr], y[tr])
        p[te] = m.predict_proba(d.x[te])[:, 1]
    return p


def _legacy_probability(d: RiskData) -> FloatArray:
    """P(MAIS 3+) of field model 2.0.0 for every row (its own inputs)."""
    model = FieldModel.from_artifact(artifact_for_version("2.0.0"))
    col = {n: d.x[:, i] for i, n in enumerate(ALL_COLUMNS_3)}
    rows = d.rows
    out = np.empty(len(rows))
    for i in range(len(rows)):
        inputs = FieldInputs(
            delta_v_kmh=float(rows["delta_v_kmh"].iat[i]),
            mode=FieldMode(str(d.mode[i])),
            belted=bool(col["belted"][i]),
            multiple_impacts=bool(col["multiple_impacts"][i]),
            age_years=float(rows["age_years"].iat[i]),
            sex=None,
            stature_cm=None if np.isnan(rows["stature_cm"].iat[i]) else rows["stature_cm"].iat[i],
            mass_kg=None if np.isnan(rows["mass_kg"].iat[i]) else rows["mass_kg"].iat[i],
        )
        out[i] = model.predict(inputs).probability
    return out


def _inner_threshold(
    d: RiskData, y: FloatArray, spec: Spec, rows: IntArray, target: float, config: RiskConfig
) -> float:
    """Threshold reaching `target` on out-of-fold predictions inside `rows` (folds by crash)."""
    inner = crash_folds(d.crash[rows], config.n_splits, config.seed + 11)
    p = np.empty(rows.size)
    for tr, te in inner:
        f = fit_spec(d, y, rows[tr], spec, config)
        p[te] = f.probability(d.x[rows[te]])
    return threshold_for_sensitivity(y[rows], p, target)


def _heldout_operating_point(
    d: RiskData,
    y: FloatArray,
    spec: Spec,
    folds: Sequence[tuple[IntArray, IntArray]],
    target: float,
    config: RiskConfig,
) -> np.ndarray:
    """Flags with the threshold chosen inside each training part (its own held-out
    predictions, as the served threshold is chosen on the fit's), shape (n,)."""
    flags = np.zeros(y.size, dtype=bool)
    for tr, te in tqdm(folds, desc="operating point held out", leave=False):
        t = _inner_threshold(d, y, spec, tr, target, config)
        flags[te] = fit_spec(d, y, tr, spec, config).probability(d.x[te]) >= t
    return flags


def _vehicle_heldout(
    d: RiskData, y: FloatArray, p: FloatArray, folds: Sequence[tuple[IntArray, IntArray]]
) -> tuple[FloatArray, FloatArray, FloatArray, IntArray, FloatArray]:
    """Held-out P(anyone ISS 15+) per vehicle from held-out occupant probabilities."""
    ids, anyone, w, crash = vehicle_table(d, y)
    z, zid = noisy_or_logit(p, d.vehicle)
    assert np.array_equal(ids, zid)
    fold_of_crash = np.empty(d.crash.max() + 1, dtype=np.int64)
    for k, (_, te) in enumerate(folds):
        fold_of_crash[d.crash[te]] = k
    vf = fold_of_crash[crash]
    pv = np.empty(ids.size)
    for k in range(len(folds)):
        tr, te = vf != k, vf == k
        a, b = vehicle_recalibration(z[tr], anyone[tr], w[tr])
        pv[te] = expit(a + b * z[te])
    return pv, anyone, w, crash, z


def _subgroups(d: RiskData) -> dict[str, np.ndarray]:
    col = {n: d.x[:, i] for i, n in enumerate(ALL_COLUMNS_3)}
    out = {
        f"mode={m}": d.mode == m for m in ("frontal", "near_side", "far_side", "rear", "rollover")
    }
    out["seat=front outboard"] = (col["row2"] + col["row3"] + col["front_middle"]) == 0
    out["seat=front middle"] = col["front_middle"] > 0
    out["seat=second row"] = col["row2"] > 0
    out["seat=third row"] = col["row3"] > 0
    out["airbag=deployed"] = col["airbag_deployed"] > 0
    out["airbag=not deployed"] = col["airbag_not_deployed"] > 0
    out["airbag=none"] = (col["airbag_deployed"] + col["airbag_not_deployed"]) == 0
    return out


def _outcome_stage(
    d: RiskData,
    o: Any,
    drift: str,
    folds: Sequence[tuple[IntArray, IntArray]],
    resamples: Sequence[IntArray],
    config: RiskConfig,
) -> dict[str, Any]:
    """Selection, held-out figures (the model, the plain regression, delta-V alone), temporal."""
    bar = tqdm(
        total=len(config.c_grid) + len(REGRESSION_GROUPS) + 1,
        desc=f"select {o.name}",
        leave=False,
    )
    spec, selection, p = select_spec(d, o.y, folds, config, drift, bar)
    bar.close()
    plain = _fixed_oof(d, o.y, _cols(PLAIN_COLUMNS), folds, None)
    dv = _fixed_oof(d, o.y, _cols(["intercept", "delta_v_kmh"]), folds, None)
    te, pt, _ = temporal_probability(
        d, o.y, spec, config.temporal_cut, config.temporal_cut + 1, int(d.year.max()), config
    )
    return {
        "spec": spec,
        "selection": selection,
        "oof": p,
        "heldout": score(o.y, p, d.w, resamples),
        "plain": score(o.y, plain, d.w, None),
        "plain_oof": plain,
        "delta_v_alone": score(o.y, dv, d.w, None),
        "auc_minus_plain_ci95": _diff_ci(o.y, p, plain, resamples),
        "temporal": score(o.y[te], pt, d.w[te], None),
        "temporal_rows": te,
        "temporal_p": pt,
    }


def _diff_ci(
    y: FloatArray, p: FloatArray, q: FloatArray, resamples: Sequence[IntArray]
) -> list[float]:
    from sklearn.metrics import roc_auc_score

    diffs = [roc_auc_score(y[ix], p[ix]) - roc_auc_score(y[ix], q[ix]) for ix in resamples]
    lo, hi = np.percentile(diffs, [2.5, 97.5])
    return [float(lo), float(hi)]


#: Bootstrap refits per cached chunk (an interrupted fit resumes at a chunk).
BOOTSTRAP_CHUNK: Final[int] = 10


def bootstrap_chunk(
    d: RiskData, specs: dict[str, Spec], config: RiskConfig, chunk: int
) -> dict[str, tuple[FloatArray, FloatArray]]:
    """Refits ``chunk * BOOTSTRAP_CHUNK ...`` of the bootstrap by crash, per outcome."""
    resamples = crash_resamples(d.crash, config.n_bootstrap, config.seed + 7)
    part = resamples[chunk * BOOTSTRAP_CHUNK : (chunk + 1) * BOOTSTRAP_CHUNK]
    ys = {o.name: o.y for o in d.outcomes}
    out: dict[str, tuple[list[FloatArray], list[FloatArray]]] = {n: ([], []) for n in specs}
    for ix in tqdm(part, desc=f"bootstrap refits by crash ({chunk + 1})", leave=False):
        for name, spec in specs.items():
            if spec.kind != "logistic":  # a bag's members are its bootstrap
                continue
            f = fit_spec(d, ys[name], ix.astype(np.int64), spec, config)
            assert isinstance(f, Fitted)
            out[name][0].append(f.beta)
            out[name][1].append(np.array(f.calibration))
    return {n: (np.array(b), np.array(c)) for n, (b, c) in out.items() if b}


def _bootstrap_refits(
    d: RiskData, specs: dict[str, Spec], config: RiskConfig, cache: _Cache
) -> dict[str, tuple[FloatArray, FloatArray]]:
    """Per outcome, ``(B, k)`` coefficients and ``(B, 2)`` calibrations of refits by crash."""
    chunks = []
    n_chunks = -(-config.n_bootstrap // BOOTSTRAP_CHUNK)
    for c in tqdm(range(n_chunks), desc="bootstrap refits by crash"):

        def compute(c: int = c) -> dict[str, tuple[FloatArray, FloatArray]]:
            return bootstrap_chunk(d, specs, config, c)

        chunks.append(cache.get(f"bootstrap_{c}", compute))
    out = {
        n: (
            np.concatenate([ch[n][0] for ch in chunks]),
            np.concatenate([ch[n][1] for ch in chunks]),
        )
        for n, spec in specs.items()
        if spec.kind == "logistic"
    }
    ys = {o.name: o.y for o in d.outcomes}
    for n, spec in specs.items():
        if spec.kind == "blend":

            def refits(n: str = n, spec: Spec = spec) -> tuple[FloatArray, FloatArray]:
                return blend_refits(d, ys[n], spec, config)

            out[n] = cache.get(f"blend_bootstrap_{n}", refits)
    return out


def blend_refits(
    d: RiskData, y: FloatArray, spec: Spec, config: RiskConfig
) -> tuple[FloatArray, FloatArray]:
    """A blend's regression refitted on its bag's resamples of whole crashes, in order.

    Member ``j`` of the bag and refit ``j`` see the same crashes, so the blend
    of the two is a bootstrap refit of the blend (the served interval's spread).
    Returns ``(B, k)`` coefficients and ``(B, 2)`` calibrations.
    """
    part = spec.part("logistic")
    betas, cals = [], []
    resamples = crash_resamples(d.crash, config.boost_members, config.seed)  # as fit_bag's
    for ix in tqdm(resamples, desc="blend: regression on the bag's resamples", leave=False):
        f = fit_spec(d, y, ix.astype(np.int64), part, config)
        assert isinstance(f, Fitted)
        betas.append(f.beta)
        cals.append(np.array(f.calibration))
    return np.array(betas), np.array(cals)


def _file_sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _round(x: Any) -> Any:
    """Figures rounded for the document (floats to 6 significant digits)."""
    if isinstance(x, float | np.floating):
        return float(f"{float(x):.6g}") if np.isfinite(x) else None
    if isinstance(x, dict):
        return {str(k): _round(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_round(v) for v in x]
    if isinstance(x, np.integer):
        return int(x)
    return x


def fit_risk(config: RiskConfig | None = None, cache_dir: Path | None = None) -> RiskFit:
    """Fit, measure and document the field risk models (module docstring of :mod:`.risk_fit`)."""
    cfg = config or RiskConfig()
    d = load_risk_data(cfg.subsample, cfg.seed)
    cache = _Cache(cache_dir, cfg.key())
    folds = crash_folds_cached(d, cfg)
    resamples = crash_resamples(d.crash, cfg.n_metric_bootstrap, cfg.seed + 1)
    iss = d.outcomes[0]
    drift, drift_table = cache.get(
        "drift", lambda: choose_drift(d, iss.y, REGRESSION_GROUPS, 1.0, cfg, folds)
    )
    stages: dict[str, dict[str, Any]] = {}
    for o in tqdm(d.outcomes, desc="outcomes"):

        def stage(o: Outcome = o) -> dict[str, Any]:
            return _outcome_stage(d, o, drift, folds, resamples, cfg)

        stages[o.name] = cache.get(f"outcome_{o.name}", stage)
    figures = cache.get(
        "iss_extras", lambda: _iss_extras(d, stages["iss15"], folds, resamples, cfg)
    )
    figures["tiers"] = _tier_extras(d, stages["iss15"], figures, folds, resamples, cfg)
    for o in d.outcomes:
        st = stages[o.name]

        def temporal(o: Outcome = o, te: IntArray = st["temporal_rows"]) -> dict[str, Any]:
            pt = stages[o.name]["temporal_p"]
            res = crash_resamples(d.crash[te], cfg.n_metric_bootstrap, 4)
            return score(o.y[te], pt, d.w[te], res)

        st["temporal"] = cache.get(f"temporal_ci_{o.name}", temporal)
    integrated = cache.get(
        "integrated_oof",
        lambda: integrated_oof(d, iss.y, stages["iss15"]["spec"], folds, cfg),
    )
    figures["knowledge"] = cache.get(
        "knowledge",
        lambda: knowledge_extras(d, stages["iss15"], folds, cfg, PLAIN_COLUMNS, integrated),
    )
    specs = {n: s["spec"] for n, s in stages.items()}
    boot = _bootstrap_refits(d, specs, cfg, cache)
    doc = _document(d, cfg, drift, drift_table, stages, figures, boot)
    oof = {n: s["oof"] for n, s in stages.items()} | {
        "iss15_sensed_only": integrated,
    }
    return RiskFit(artifact=doc, figures=figures, oof=oof, data=d)


def crash_folds_cached(d: RiskData, cfg: RiskConfig) -> list[tuple[IntArray, IntArray]]:
    """The folds by crash of the fit."""
    return crash_folds(d.crash, cfg.n_splits, cfg.seed)


def _oof_threshold_flags(
    y: FloatArray, p: FloatArray, folds: Sequence[tuple[IntArray, IntArray]], target: float
) -> np.ndarray:
    """Flags of each fold at the threshold set on the other folds' held-out predictions."""
    flags = np.zeros(y.size, dtype=bool)
    for tr, te in folds:
        flags[te] = p[te] >= threshold_for_sensitivity(y[tr], p[tr], target)
    return flags


def _iss_extras(
    d: RiskData,
    stage: dict[str, Any],
    folds: Sequence[tuple[IntArray, IntArray]],
    resamples: Sequence[IntArray],
    cfg: RiskConfig,
    nested: bool = True,
) -> dict[str, Any]:
    """ISS 15+ only: subgroups, comparisons, operating points, the vehicle answer.

    With `nested` False (a decision-only refit, :mod:`.risk_decision`), each
    fold's held-out flags use the threshold set on the other folds' held-out
    predictions (not refitted inside each training part), and the temporal
    check's threshold is set on the held-out predictions of the years it fits.
    """
    y, w, p, spec = d.outcomes[0].y, d.w, stage["oof"], stage["spec"]
    out: dict[str, Any] = {}
    out["subgroups"] = {
        name: {
            "model": score(y, p, w, resamples, mask),
            "plain": score(y, stage["plain_oof"], w, None, mask),
        }
        for name, mask in tqdm(_subgroups(d).items(), desc="subgroups", leave=False)
        if mask.any()
    }
    hgb = _hgb_oof(d, y, folds, cfg.seed)
    out["boosted"] = score(y, hgb, w, None, calibration=False)
    out["boosted"]["auc_minus_model_ci95"] = _diff_ci(y, hgb, p, resamples)
    legacy = _legacy_probability(d)
    out["legacy_2_0_0"] = score(y, legacy, w, resamples)
    nhtsa = expit(NHTSA_ALL.intercept + NHTSA_ALL.slope_per_mph * kmh_to_mph_array(d))
    out["nhtsa_mais3_curve"] = score(y, nhtsa, w, None)
    recent = d.year >= 2010
    mais3 = (d.rows["mais"] >= 3).to_numpy(dtype=np.float64)
    out["nhtsa_mais3_curve_on_mais3_2010_2014"] = score(mais3, nhtsa, w, None, recent)
    # operating points: thresholds on all held-out predictions (served), and held out
    points = {}
    flags_of: dict[str, np.ndarray] = {}
    for name, req in (("sens85", cfg.sensitivity), ("acs_cot", cfg.acs_cot_sensitivity)):
        target = target_with_margin(req, float(y.sum()))
        t = threshold_for_sensitivity(y, p, target)
        te, pt = stage["temporal_rows"], stage["temporal_p"]
        tr = np.flatnonzero(d.year <= cfg.temporal_cut)
        if nested:
            flags = _heldout_operating_point(d, y, spec, folds, target, cfg)
            t_tr = _inner_threshold(d, y, spec, tr, target, cfg)
        else:
            flags = _oof_threshold_flags(y, p, folds, target)
            t_tr = threshold_for_sensitivity(y[tr], p[tr], target)
        flags_of[name] = flags
        old_target = target_with_margin(req, float(y.sum()) / cfg.n_splits)
        t_old = threshold_for_sensitivity(y, p, old_target)
        points[name] = {
            "required_sensitivity": req,
            "target_sensitivity": target,
            "threshold": t,
            "fold_margin": {  # the margin used until 2026-12-06, on the held-out predictions
                "target_sensitivity": old_target,
                "heldout_predictions": triage_figures(y, p >= t_old, w, None),
            },
            "heldout": triage_figures(y, flags, w, resamples),
            "temporal": triage_figures(
                y[te], pt >= t_tr, w[te], crash_resamples(d.crash[te], cfg.n_metric_bootstrap, 5)
            ),
            "temporal_threshold": t_tr,
            "threshold_method": "nested" if nested else "other_folds_heldout",
        }
    out["operating_points"] = points
    out["heldout_flags"] = flags_of  # the risk tiers' figures (_tier_extras)
    # the vehicle answer
    pv, anyone, vw, vcrash, z = _vehicle_heldout(d, y, p, folds)
    vres = crash_resamples(vcrash, cfg.n_metric_bootstrap, cfg.seed + 3)
    out["vehicle"] = score(anyone, pv, vw, vres)
    a, b = vehicle_recalibration(z, anyone, vw)
    boots = []
    n_boot = cfg.boost_members if spec.kind in ("boosted", "blend") else cfg.n_bootstrap
    for ix in crash_resamples(vcrash, n_boot, cfg.seed + 9):
        boots.append(vehicle_recalibration(z[ix], anyone[ix], vw[ix]))
    out["vehicle_calibration"] = [a, b]
    out["vehicle_bootstrap_calibration"] = [list(t) for t in boots]
    out["vehicle_oof"] = pv
    return out


#: The operating point whose held-out flags the risk tiers' figures use (the default).
TIER_OPERATING_POINT: Final[str] = "sens85"


def _tier_extras(
    d: RiskData,
    stage: dict[str, Any],
    extras: dict[str, Any],
    folds: Sequence[tuple[IntArray, IntArray]],
    resamples: Sequence[IntArray],
    cfg: RiskConfig,
) -> dict[str, Any]:
    """Held-out figures of the risk tiers (``models.tiers``) at the default operating point,
    and of the vehicle answer at the high-risk threshold (beside OnStar's ISP at 0.20).

    The occupants' tiers are those served: flagged by the operating point held out
    (threshold chosen inside each training part), high where the held-out probability
    is also at or above :data:`models.tiers.HIGH_RISK_THRESHOLD`.
    """
    y, w, p = d.outcomes[0].y, d.w, stage["oof"]
    flags = extras.get("heldout_flags", {}).get(TIER_OPERATING_POINT)
    if flags is None:  # figures cached before the tiers: the same flags, computed again
        target = target_with_margin(cfg.sensitivity, float(y.sum()))
        flags = _heldout_operating_point(d, y, stage["spec"], folds, target, cfg)
    _, anyone, vw, vcrash = vehicle_table(d, y)
    vres = crash_resamples(vcrash, cfg.n_metric_bootstrap, cfg.seed + 3)  # as the vehicle's
    return {
        "operating_point": TIER_OPERATING_POINT,
        "high_threshold": HIGH_RISK_THRESHOLD,
        "heldout": tier_figures(y, p, flags, w, HIGH_RISK_THRESHOLD, resamples),
        "vehicle_at_high_threshold": threshold_figures(
            anyone, extras["vehicle_oof"], vw, HIGH_RISK_THRESHOLD, vres
        ),
    }


def kmh_to_mph_array(d: RiskData) -> FloatArray:
    """Delta-V of every row in mph (explicit conversion)."""
    kmh = d.rows["delta_v_kmh"].to_numpy(dtype=np.float64)
    return np.array([kmh_to_mph(v) for v in kmh])


def _boosted_doc(f: BoostedFitted) -> dict[str, Any]:
    return {
        "kind": "boosted",
        "trees": f.bag.to_document(ALL_COLUMNS_3),
        "trees_per_member": f.n_trees,
        "calibration": list(f.calibration),
    }


def _logistic_doc(f: Fitted, boot: tuple[FloatArray, FloatArray]) -> dict[str, Any]:
    betas, cals = boot
    return {
        "kind": "logistic",
        "columns": [ALL_COLUMNS_3[i] for i in f.columns],
        "coefficients": f.beta.tolist(),
        "calibration": list(f.calibration),
        "bootstrap_coefficients": betas.tolist(),
        "bootstrap_calibration": cals.tolist(),
    }


def _document(
    d: RiskData,
    cfg: RiskConfig,
    drift: str,
    drift_table: dict[str, Any],
    stages: dict[str, dict[str, Any]],
    extras: dict[str, Any],
    boot: dict[str, tuple[FloatArray, FloatArray]],
    carried: dict[str, dict[str, Any]] | None = None,
) -> dict[str, Any]:
    """The artifact document (figures included), its content checksum last.

    `carried`: outcome documents taken as they are from an earlier artifact
    (a decision-only refit carries the region models, :mod:`.risk_decision`).
    """
    outcomes_doc = {}
    for o in d.outcomes:
        if carried is not None and o.name in carried:
            outcomes_doc[o.name] = carried[o.name]
            continue
        st = stages[o.name]
        spec: Spec = st["spec"]
        f = fit_spec(d, o.y, np.arange(o.y.size), spec, cfg)
        if isinstance(f, BlendFitted):
            model: dict[str, Any] = {
                "kind": "blend",
                "weight_boosted": f.weight,
                "logistic": _logistic_doc(f.logistic, boot[o.name]),
                "boosted": _boosted_doc(f.boosted),
            }
        elif isinstance(f, BoostedFitted):
            model = _boosted_doc(f)
        else:
            model = _logistic_doc(f, boot[o.name])
        outcomes_doc[o.name] = {
            "label": o.label,
            "ais_level": o.ais_level,
            "groups": list(spec.groups),
            "tree_groups": list(spec.tree_groups),
            "penalty_c": spec.c,
            **model,
            "selection": _round(st["selection"]),
            "heldout": _round(st["heldout"]),
            "plain": _round(st["plain"]),
            "delta_v_alone": _round(st["delta_v_alone"]),
            "auc_minus_plain_ci95": _round(st["auc_minus_plain_ci95"]),
            "temporal": _round(st["temporal"]),
        }
    points = {
        name: {
            "description": (
                "flag when P(ISS15+) >= threshold: finds >= "
                f"{100 * pt['required_sensitivity']:.0f} % of the ISS 15+ occupants held out "
                f"(threshold set at {pt['target_sensitivity']:.3f} on held-out predictions)"
                + (" (ACS-COT: under-triage <= 5 %)" if name == "acs_cot" else "")
            ),
            "threshold": pt["threshold"],
            "thresholds_by_knowledge": {
                k: v["threshold"]
                for k, v in extras["knowledge"]["thresholds_by_knowledge"][name].items()
            },
            "figures": _round({k: v for k, v in pt.items() if k != "threshold"}),
        }
        for name, pt in extras["operating_points"].items()
    }
    doc: dict[str, Any] = {
        "schema": ARTIFACT_SCHEMA,
        "model": {"name": MODEL_NAME, "version": MODEL_VERSION},
        "outcome": OUTCOME,
        "feature_code_sha256": feature_code_sha256(),
        "candidate_columns": list(ALL_COLUMNS_3),
        "imputation": asdict(d.imputation) | {"impact_count": d.impact_count_imputed},
        "data": {
            "file": OCCUPANTS_CSV.name,
            "sha256": _file_sha256(OCCUPANTS_CSV),
            "rows": int(len(d.rows)),
            "crashes": int(np.unique(d.crash).size),
            "vehicles": int(np.unique(d.vehicle).size),
            "years": [int(d.year.min()), int(d.year.max())],
            "delta_v_max_kmh": float(d.rows["delta_v_kmh"].max()),
            "population": [
                {"rule": r, "text": t, "removed": n}
                for (r, t), (_, n) in zip(POPULATION_RULES, d.removed, strict=True)
            ],
        },
        "config": asdict(cfg),
        "drift": {"chosen": drift, "inner_temporal": _round(drift_table)},
        "outcomes": outcomes_doc,
        "vehicle": {
            "calibration": list(extras["vehicle_calibration"]),
            "bootstrap_calibration": extras["vehicle_bootstrap_calibration"],
            "heldout": _round(extras["vehicle"]),
        },
        "operating_points": points,
        "unknowns": {
            "donors": donor_table_of(d, np.arange(d.x.shape[0])).to_document(),
            "figures": _round(extras["knowledge"]),
        },
        "measurement_model": MEASUREMENT_MODEL.document(),
        "default_operating_point": "sens85",
        "tiers": _round(extras["tiers"]),
        "comparisons": _round(
            {k: extras[k] for k in ("boosted", "legacy_2_0_0", "nhtsa_mais3_curve")}
            | {
                "nhtsa_mais3_curve_on_mais3_2010_2014": extras[
                    "nhtsa_mais3_curve_on_mais3_2010_2014"
                ]
            }
        ),
        "subgroups": _round(extras["subgroups"]),
    }
    doc["content_sha256"] = canonical_content_sha256(doc)
    return doc
