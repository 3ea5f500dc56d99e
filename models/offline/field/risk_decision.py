"""A decision-only refit: ISS 15+ refitted, the region models carried from an earlier artifact.

``aacn-triage fit-field --regions-from VERSION`` runs :func:`fit_decision`.
The whole fit (:func:`models.offline.field.risk_run.fit_risk`) refits every
outcome; this one refits the decision (P(ISS 15+)) alone, on the population
and feature set of this code (children included, feature set 3), and takes the
eight region models of the artifact of `VERSION` as they are (their figures
are that artifact's; they were fitted on the population that artifact names).
It reuses the whole fit's stage cache (the drift treatment and the ISS 15+
selection) and caches its own stages, so it resumes where it stopped.

The ISS 15+ model keeps the groups the selection kept and, always, the child
terms (:data:`models.field.risk_children.CHILD_GROUPS`): the selection's
backward pass scores a group by the log loss over every occupant, of whom
children are a ninth with a sixteenth of the positives, so it may drop terms
that only children need (their age enters no other column: set 1 clamps every
age below 16 to 16). Each fold's model is fitted once and scores its held-out
occupants two ways: as sent, and with age, sex, stature and mass unknown
(integrated, :mod:`models.field.unknowns`). Each fold's model is kept (a
stage), and the measured-delta-V consistency check
(:mod:`models.offline.field.risk_measured`) scores the held-out occupants
through it with the delta-V a vehicle would have measured. The operating
points' held-out figures take each fold's threshold from the other folds'
held-out predictions (the whole fit refits inside each training part; the
card names the method).
"""

from __future__ import annotations

from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from models.arrays import FloatArray, IntArray
from models.field.risk_children import CHILD_GROUPS
from models.field.versions import artifact_for_version
from models.offline.field.risk_fit import (
    REGRESSION_GROUPS,
    RiskConfig,
    RiskData,
    Spec,
    _Cache,
    choose_drift,
    fit_spec,
    load_risk_data,
    served_x,
    temporal_probability,
)
from models.offline.field.risk_knowledge import (
    donor_table_of,
    integrated_probability,
    knowledge_extras,
    knowledge_groups,
)
from models.offline.field.risk_measured import (
    MEASURED_DRAWS,
    MEASURED_SEED,
    READINGS,
    check_document,
    measured_check,
    measured_oof,
)
from models.offline.field.risk_metrics import crash_resamples, score
from models.offline.field.risk_run import (
    PLAIN_COLUMNS,
    RiskFit,
    _diff_ci,
    _document,
    _iss_extras,
    _oof_threshold_flags,
    _outcome_stage,
    _round,
    _tier_extras,
    crash_folds_cached,
    target_with_margin,
)

__all__ = ["check_served", "decision_spec", "fit_decision", "served_spec"]


def decision_spec(selected: Spec) -> Spec:
    """The selection's ISS 15+ spec with the child terms always kept (module docstring)."""
    groups = (*selected.groups, *(g for g in CHILD_GROUPS if g not in selected.groups))
    return replace(selected, groups=groups)


def _fold_predictions(
    d: RiskData,
    y: FloatArray,
    spec: Spec,
    folds: list[tuple[IntArray, IntArray]],
    cfg: RiskConfig,
) -> dict[str, FloatArray]:
    """Held-out P two ways, each fold's model fitted once (module docstring)."""
    out = {k: np.empty(y.size) for k in ("oof", "sensed_only")}
    for tr, te in tqdm(folds, desc="decision: folds by crash", leave=False):
        f = fit_spec(d, y, tr, spec, cfg)
        year = float(d.year[tr].max())
        out["oof"][te] = f.probability(served_x(d, te, year))
        table = donor_table_of(d, tr)
        out["sensed_only"][te] = integrated_probability(f, d, te, table, year)
    return out


def fit_decision(config: RiskConfig, cache_dir: Path | None, regions_from: str) -> RiskFit:
    """Refit ISS 15+, carry the region models of `regions_from` (module docstring)."""
    cfg = config
    d = load_risk_data(cfg.subsample, cfg.seed)
    cache = _Cache(cache_dir, cfg.key())
    folds = crash_folds_cached(d, cfg)
    resamples = crash_resamples(d.crash, cfg.n_metric_bootstrap, cfg.seed + 1)
    iss = d.outcomes[0]
    drift, drift_table = cache.get(
        "drift", lambda: choose_drift(d, iss.y, REGRESSION_GROUPS, 1.0, cfg, folds)
    )
    selected = cache.get(
        "outcome_iss15", lambda: _outcome_stage(d, iss, drift, folds, resamples, cfg)
    )
    spec = decision_spec(selected["spec"])
    preds = cache.get("decision_folds", lambda: _fold_predictions(d, iss.y, spec, folds, cfg))
    p = preds["oof"]

    def temporal() -> tuple[IntArray, FloatArray]:
        te, pt, _ = temporal_probability(
            d, iss.y, spec, cfg.temporal_cut, cfg.temporal_cut + 1, int(d.year.max()), cfg
        )
        return te, pt

    te, pt = cache.get("decision_temporal", temporal)
    tres = crash_resamples(d.crash[te], cfg.n_metric_bootstrap, 4)
    stage: dict[str, Any] = {
        **selected,
        "spec": spec,
        "oof": p,
        "heldout": score(iss.y, p, d.w, resamples),
        "auc_minus_plain_ci95": _diff_ci(iss.y, p, selected["plain_oof"], resamples),
        "temporal": score(iss.y[te], pt, d.w[te], tres),
        "temporal_rows": te,
        "temporal_p": pt,
    }
    figures = cache.get(
        "decision_extras", lambda: _iss_extras(d, stage, folds, resamples, cfg, nested=False)
    )
    if "heldout_flags" not in figures:  # figures cached before the tiers' flags were kept
        figures["heldout_flags"] = {
            name: _oof_threshold_flags(iss.y, p, folds, target_with_margin(req, float(iss.y.sum())))
            for name, req in (("sens85", cfg.sensitivity), ("acs_cot", cfg.acs_cot_sensitivity))
        }
    figures["tiers"] = _tier_extras(d, stage, figures, folds, resamples, cfg)
    figures["knowledge"] = cache.get(
        "decision_knowledge",
        lambda: knowledge_extras(d, stage, folds, cfg, PLAIN_COLUMNS, preds["sensed_only"]),
    )
    old = _old_document(regions_from)
    carried = {k: v for k, v in old["outcomes"].items() if k != "iss15"}
    doc = _document(d, cfg, drift, drift_table, {"iss15": stage}, figures, {}, carried=carried)
    doc["outcomes"]["iss15"]["groups_selected"] = list(selected["spec"].groups)
    doc["regions_from"] = {
        "version": old["model"]["version"],
        "content_sha256": old["content_sha256"],
        "population": old["data"]["population"],
        "rows": old["data"]["rows"],
    }
    from models.field.risk_model import canonical_content_sha256

    doc.pop("content_sha256", None)
    doc["content_sha256"] = canonical_content_sha256(doc)
    figures["measured_check"] = _measured_stage(d, cfg, cache, spec, folds, doc)
    oof = {"iss15": p, "iss15_sensed_only": preds["sensed_only"]}
    return RiskFit(artifact=doc, figures=figures, oof=oof, data=d)


def _measured_stage(
    d: RiskData,
    cfg: RiskConfig,
    cache: _Cache,
    spec: Spec,
    folds: list[tuple[IntArray, IntArray]],
    doc: dict[str, Any],
) -> dict[str, Any]:
    """The measured-delta-V consistency check of `doc` (each fold's model kept as a stage)."""
    y = d.outcomes[0].y
    fold_models = cache.get(
        "decision_fold_models",
        lambda: [
            fit_spec(d, y, tr, spec, cfg)
            for tr, _ in tqdm(folds, desc="decision: fold models", leave=False)
        ],
    )

    def simulate(reading: str) -> dict[str, FloatArray]:
        return measured_oof(
            d, fold_models, folds, reading, MEASURED_DRAWS, MEASURED_SEED, sensed_only=True
        )

    sims = {
        reading: cache.get(f"decision_measured_{reading}", partial(simulate, reading))
        for reading in READINGS
    }
    served = {
        op: dict(doc["operating_points"][op]["thresholds_by_knowledge"])
        for op in ("sens85", "acs_cot")
    }
    figures = measured_check(d, cfg, sims, knowledge_groups(d), served)
    return check_document(doc, _round(figures))


def served_spec(doc: dict[str, Any]) -> Spec:
    """The ISS 15+ spec an artifact document serves (its groups, kind, penalty and trees)."""
    iss = doc["outcomes"]["iss15"]
    return Spec(
        groups=tuple(iss["groups"]),
        c=float(iss["penalty_c"]),
        drift=str(doc["drift"]["chosen"]),
        kind=str(iss["kind"]),
        n_trees=int(iss.get("trees_per_member") or 0),
        tree_groups=tuple(iss.get("tree_groups") or ()),
        weight=float(iss["selection"].get("blend_weight") or 0.0),
    )


def check_served(doc: dict[str, Any], cache_dir: Path | None) -> dict[str, Any]:
    """The measured-delta-V check of a served artifact `doc`, without refitting its selection.

    The folds by crash and each fold's model follow from `doc`'s settings and
    spec (:func:`served_spec`), so the check of a shipped artifact can be run
    (or re-run, resuming from the same stage cache as ``fit-field``) apart from
    the whole fit: ``aacn-triage fit-field --check-measured``.
    """
    cfg = RiskConfig(
        **{k: tuple(v) if isinstance(v, list) else v for k, v in doc["config"].items()}
    )
    d = load_risk_data(cfg.subsample, cfg.seed)
    cache = _Cache(cache_dir, cfg.key())
    return _measured_stage(d, cfg, cache, served_spec(doc), crash_folds_cached(d, cfg), doc)


def _old_document(version: str) -> dict[str, Any]:
    import json

    doc: dict[str, Any] = json.loads(artifact_for_version(version).read_text(encoding="utf-8"))
    return doc
