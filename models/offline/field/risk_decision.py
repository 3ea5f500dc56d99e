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

from collections.abc import Sequence
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from models.arrays import FloatArray, IntArray
from models.field.risk_children import CHILD_GROUPS
from models.field.versions import artifact_for_version
from models.offline.field.risk_children_fit import (
    ChildrenAware,
    children_calibration_of,
    children_stage,
)
from models.offline.field.risk_fit import (
    REGRESSION_GROUPS,
    AnyFitted,
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
    _cols,
    _diff_ci,
    _document,
    _fixed_oof,
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


def _fold_models(
    d: RiskData, y: FloatArray, spec: Spec, folds: list[tuple[IntArray, IntArray]], cfg: RiskConfig
) -> list[AnyFitted]:
    """Each fold's decision model, fitted on its training part."""
    return [fit_spec(d, y, tr, spec, cfg) for tr, _ in tqdm(folds, desc="decision: fold models")]


def _shared_oof(
    d: RiskData, models: Sequence[AnyFitted], folds: list[tuple[IntArray, IntArray]]
) -> FloatArray:
    """Held-out P of each fold's model as fitted (the accident year as served), shape (n,)."""
    p = np.empty(d.x.shape[0])
    for f, (tr, te) in zip(models, folds, strict=True):
        p[te] = f.probability(served_x(d, te, float(d.year[tr].max())))
    return p


def _sensed_only(
    d: RiskData, models: Sequence[ChildrenAware], folds: list[tuple[IntArray, IntArray]]
) -> FloatArray:
    """Held-out P with age, sex, stature and mass unknown, integrated as served, shape (n,)."""
    p = np.empty(d.x.shape[0])
    for f, (tr, te) in tqdm(
        list(zip(models, folds, strict=True)), desc="decision: integrated over unknown inputs"
    ):
        p[te] = integrated_probability(f, d, te, donor_table_of(d, tr), float(d.year[tr].max()))
    return p


def _served_folds(
    d: RiskData,
    cfg: RiskConfig,
    cache: _Cache,
    spec: Spec,
    folds: list[tuple[IntArray, IntArray]],
) -> tuple[dict[str, Any], list[ChildrenAware]]:
    """The children's stage and each fold's model as served (children calibrated), cached."""
    y = d.outcomes[0].y
    models = cache.get("decision_fold_models", lambda: _fold_models(d, y, spec, folds, cfg))
    shared = cache.get("decision_shared_oof", lambda: _shared_oof(d, models, folds))
    groups = knowledge_groups(d)
    children = cache.get(
        "decision_children",
        lambda: children_stage(
            d,
            y,
            shared,
            spec,
            folds,
            cfg,
            PLAIN_COLUMNS,
            {k: v for k, v in groups.items() if k.startswith("children")},
        ),
    )
    aware = [
        ChildrenAware(f, c) for f, c in zip(models, children["fold_coefficients"], strict=True)
    ]
    return children, aware


def selection_from(
    version: str, d: RiskData, folds: list[tuple[IntArray, IntArray]]
) -> tuple[tuple[str, dict[str, Any]], dict[str, Any]]:
    """The drift choice and the ISS 15+ selection of the artifact of `version`, as stages.

    ``fit-field --regions-from R --selection-from V`` takes them instead of
    re-running the selection (the costly part of the fit): the selected
    groups, penalty, kind and trees, its selection, plain-regression and
    delta-V-alone figures as that artifact holds them; the plain regression's
    held-out probabilities (the subgroups' comparison) are refitted (cheap).
    """
    doc = _old_document(version)
    iss = doc["outcomes"]["iss15"]
    spec = replace(served_spec(doc), groups=tuple(iss.get("groups_selected") or iss["groups"]))
    plain_oof = _fixed_oof(d, d.outcomes[0].y, _cols(PLAIN_COLUMNS), folds, None)
    selected = {
        "spec": spec,
        "selection": iss["selection"],
        "plain": iss["plain"],
        "plain_oof": plain_oof,
        "delta_v_alone": iss["delta_v_alone"],
        "selection_from": version,
    }
    return (spec.drift, doc["drift"]["inner_temporal"]), selected


def fit_decision(
    config: RiskConfig,
    cache_dir: Path | None,
    regions_from: str,
    selection_from_version: str | None = None,
) -> RiskFit:
    """Refit ISS 15+, carry the region models of `regions_from` (module docstring)."""
    cfg = config
    d = load_risk_data(cfg.subsample, cfg.seed)
    cache = _Cache(cache_dir, cfg.key())
    folds = crash_folds_cached(d, cfg)
    resamples = crash_resamples(d.crash, cfg.n_metric_bootstrap, cfg.seed + 1)
    iss = d.outcomes[0]
    if selection_from_version is not None:
        (drift, drift_table), selected = cache.get(
            f"selection_from_{selection_from_version}",
            lambda: selection_from(selection_from_version, d, folds),
        )
    else:
        drift, drift_table = cache.get(
            "drift", lambda: choose_drift(d, iss.y, REGRESSION_GROUPS, 1.0, cfg, folds)
        )
        selected = cache.get(
            "outcome_iss15", lambda: _outcome_stage(d, iss, drift, folds, resamples, cfg)
        )
    spec = decision_spec(selected["spec"])
    children, aware = _served_folds(d, cfg, cache, spec, folds)
    sensed_only = cache.get("decision_sensed_only", lambda: _sensed_only(d, aware, folds))
    p = children["oof"]

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
        lambda: knowledge_extras(
            d, stage, folds, cfg, PLAIN_COLUMNS, sensed_only, children["choice"]
        ),
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
    if "selection_from" in selected:
        doc["outcomes"]["iss15"]["selection_from"] = selected["selection_from"]
    doc["children_calibration"] = children_calibration_of(children).to_document()
    from models.field.risk_model import canonical_content_sha256

    doc.pop("content_sha256", None)
    doc["content_sha256"] = canonical_content_sha256(doc)
    figures["measured_check"] = _measured_stage(d, cfg, cache, aware, folds, doc)
    oof = {"iss15": p, "iss15_sensed_only": sensed_only}
    return RiskFit(artifact=doc, figures=figures, oof=oof, data=d)


def _measured_stage(
    d: RiskData,
    cfg: RiskConfig,
    cache: _Cache,
    fold_models: Sequence[Any],
    folds: list[tuple[IntArray, IntArray]],
    doc: dict[str, Any],
) -> dict[str, Any]:
    """The measured-delta-V consistency check of `doc` through each fold's model as served."""

    def simulate(reading: str) -> dict[str, FloatArray]:
        return measured_oof(
            d, fold_models, folds, reading, MEASURED_DRAWS, MEASURED_SEED, sensed_only=True
        )

    sims = {
        reading: cache.get(f"decision_measured_children_{reading}", partial(simulate, reading))
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
    settings: dict[str, Any] = {
        k: tuple(v) if isinstance(v, list) else v for k, v in doc["config"].items()
    }
    cfg = RiskConfig(**settings)
    d = load_risk_data(cfg.subsample, cfg.seed)
    cache = _Cache(cache_dir, cfg.key())
    folds = crash_folds_cached(d, cfg)
    spec = served_spec(doc)
    models: Sequence[Any]
    if "children_calibration" in doc:
        _, models = _served_folds(d, cfg, cache, spec, folds)
    else:  # an artifact before the children's calibration: each fold's model as fitted
        models = cache.get(
            "decision_fold_models", lambda: _fold_models(d, d.outcomes[0].y, spec, folds, cfg)
        )
    return _measured_stage(d, cfg, cache, models, folds, doc)


def _old_document(version: str) -> dict[str, Any]:
    import json

    doc: dict[str, Any] = json.loads(artifact_for_version(version).read_text(encoding="utf-8"))
    return doc
