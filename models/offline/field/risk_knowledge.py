"""Held-out figures by what a notification knows: children, and ages unknown.

The decision's model is fitted on every occupant with a known age (children
included, feature set 3). A notification, though, often knows less: a
telematics unit rarely knows a passenger's age, sex, stature or mass. The
service integrates such unknown inputs over the fitted population's donors
(:mod:`models.field.unknowns`); this module scores that as served, held out
by crash:

- **integrated out-of-fold probability**: each fold's model, with a donor
  table drawn from its training part only, scores the held-out occupants with
  age, sex, stature and mass unknown (seat, restraint and the crash known);
- **thresholds by knowledge**: each operating point's threshold set for
  adults with their age, for children with their age, and for ages unknown,
  each on its own held-out probabilities with the margin of
  :func:`models.offline.field.risk_run.target_with_margin` (the served
  threshold is chosen on the fit's held-out predictions; these figures are
  therefore of the threshold's own sample, as the operating points'
  ``heldout_predictions`` figures are);
- **children**: the shared model with child terms against a regression of the
  same groups fitted on children alone and the plain regression fitted on
  children (the three choices the model card reports).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from typing import Any, Final

import numpy as np
from scipy.linalg import LinAlgWarning
from tqdm import tqdm

from models.arrays import FloatArray, IntArray
from models.field.measurement import over_reconstructed_nodes
from models.field.risk_children import (
    ALL_COLUMNS_3,
    CHILD_GROUPS,
    CHILD_MAX_AGE_YEARS,
    design_columns_3,
)
from models.field.unknowns import DonorTable, build_donors, pick_donors, substitute
from models.offline.field.metrics import threshold_for_sensitivity
from models.offline.field.risk_core import fit_model
from models.offline.field.risk_fit import (
    AnyFitted,
    RiskConfig,
    RiskData,
    Spec,
    fit_spec,
    log_loss,
)
from models.offline.field.risk_metrics import (
    crash_resamples,
    score,
    target_with_margin,
    triage_figures,
)

__all__ = [
    "SENSED_UNKNOWN",
    "donor_table_of",
    "integrated_oof",
    "knowledge_extras",
    "knowledge_groups",
]

#: What a telematics unit does not sense of an occupant (integrated over).
SENSED_UNKNOWN: Final[tuple[str, ...]] = ("age_years", "female", "stature_cm", "mass_kg")

#: Rows scored per chunk of the integrated probability (memory: chunk x donors rows).
_CHUNK: Final[int] = 2000

_NUMERIC: Final[tuple[str, ...]] = ("age_years", "female", "stature_cm", "mass_kg")


def donor_table_of(d: RiskData, rows: IntArray) -> DonorTable:
    """The donor table drawn from `rows` of the fitted population (as the artifact's)."""
    values: dict[str, Any] = {k: np.asarray(d.arrays[k])[rows] for k in _NUMERIC}
    restraint = d.arrays["restraint"]
    values["restraint"] = [restraint[i] for i in rows]
    return build_donors([str(g) for g in d.group[rows]], values, d.w[rows])


def integrated_probability(
    f: AnyFitted,
    d: RiskData,
    rows: IntArray,
    table: DonorTable,
    reference_year: float,
    unknown: Sequence[str] = SENSED_UNKNOWN,
    measured_kmh: FloatArray | None = None,
) -> FloatArray:
    """P of `rows` with the inputs `unknown` integrated over `table`'s donors, shape (n,).

    The donors are picked as the service picks them (seat group, restraint and
    the other known inputs); the accident year is the reference year (as served).
    With `measured_kmh` (shape (n,)), each row's delta-V is that measured value,
    read through the measurement model as served
    (:func:`models.field.measurement.over_reconstructed_nodes`).
    """
    year_col = ALL_COLUMNS_3.index("accident_year")
    picks: dict[tuple[str, str], IntArray] = {}
    out = np.empty(rows.size)
    restraint = d.arrays["restraint"]
    for start in range(0, rows.size, _CHUNK):
        part = rows[start : start + _CHUNK]
        blocks = []
        for k, i in enumerate(part):
            key = (str(d.group[i]), str(restraint[i]))
            if key not in picks:
                picks[key] = pick_donors(
                    table,
                    key[0],
                    age_years=None if "age_years" in unknown else float(d.arrays["age_years"][i]),
                    female=None if "female" in unknown else float(d.arrays["female"][i]),
                    restraint=None if "restraint" in unknown else key[1],
                )
            blocks.append((k, picks[key] if unknown else None, tuple(unknown)))
        sub: dict[str, Any] = {}
        for name, value in d.arrays.items():
            if isinstance(value, np.ndarray):
                sub[name] = value[part]
            else:
                sub[name] = [value[i] for i in part]
        expanded, owner = substitute(sub, blocks, table)
        weight = 1.0 / np.bincount(owner)[owner]
        if measured_kmh is not None:
            chunk = measured_kmh[start : start + part.size]
            expanded, owner, weight = over_reconstructed_nodes(
                expanded, owner, weight, {k: float(v) for k, v in enumerate(chunk)}
            )
        x = design_columns_3(expanded)
        x[:, year_col] = reference_year
        p = f.probability(x)
        out[start : start + part.size] = np.bincount(owner, weight * p, minlength=part.size)
    return out


def integrated_oof(
    d: RiskData,
    y: FloatArray,
    spec: Spec,
    folds: Sequence[tuple[IntArray, IntArray]],
    config: RiskConfig,
) -> FloatArray:
    """Held-out P with age, sex, stature and mass unknown, integrated as served, shape (n,)."""
    p = np.empty(y.size)
    for tr, te in tqdm(folds, desc="integrated over unknown inputs", leave=False):
        f = fit_spec(d, y, tr, spec, config)
        p[te] = integrated_probability(f, d, te, donor_table_of(d, tr), float(d.year[tr].max()))
    return p


def _restricted(
    folds: Sequence[tuple[IntArray, IntArray]], mask: np.ndarray
) -> list[tuple[IntArray, IntArray]]:
    return [(tr[mask[tr]], te[mask[te]]) for tr, te in folds]


def _oof_of(
    fit: Callable[[IntArray], AnyFitted],
    d: RiskData,
    folds: Sequence[tuple[IntArray, IntArray]],
) -> FloatArray:
    p = np.full(d.x.shape[0], np.nan)
    for tr, te in folds:
        f = fit(tr)
        p[te] = f.probability(d.x[te])
    return p


def knowledge_extras(
    d: RiskData,
    stage: dict[str, Any],
    folds: Sequence[tuple[IntArray, IntArray]],
    cfg: RiskConfig,
    plain_columns: Sequence[str],
    integrated: FloatArray,
    children_choice: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Figures and thresholds by what is known (module docstring).

    Parameters
    ----------
    d : RiskData
    stage : dict
        The ISS 15+ outcome stage (``spec``, ``oof``).
    folds : sequence of (train, test)
    cfg : RiskConfig
    plain_columns : sequence of str
        The plain regression's columns (children's plain regression adds the
        child columns).
    integrated : ndarray, shape (n,)
        :func:`integrated_oof` of the ISS 15+ spec.
    children_choice : dict, optional
        The children's ways compared as the fit made them (each calibrated by age
        group and child seat, :mod:`models.offline.field.risk_children_fit`);
        without it, the three ways as fitted (artifacts before 3.4.0).
    """
    y, w, p, spec = d.outcomes[0].y, d.w, stage["oof"], stage["spec"]
    age = np.asarray(d.arrays["age_years"], dtype=np.float64)
    child = age < CHILD_MAX_AGE_YEARS
    adult = ~child

    def res(mask: np.ndarray, seed: int) -> list[IntArray]:
        idx = np.flatnonzero(mask)
        return [idx[r] for r in crash_resamples(d.crash[idx], cfg.n_metric_bootstrap, seed)]

    groups = knowledge_groups(d)
    out: dict[str, Any] = {"age_sent": {}, "sensed_only": {}}
    for k, (name, mask) in enumerate(tqdm(groups.items(), desc="knowledge figures", leave=False)):
        if not mask.any() or y[mask].sum() == 0:
            continue
        r = res(mask, 31 + k)
        out["age_sent"][name] = score(y[mask], p[mask], w[mask], [_local(ix, mask) for ix in r])
        out["sensed_only"][name] = score(
            y[mask], integrated[mask], w[mask], [_local(ix, mask) for ix in r]
        )
    if children_choice is not None:
        out["children_choice"] = children_choice
    else:
        out["children_choice"] = _children_choice(d, y, p, spec, folds, cfg, plain_columns)
    # thresholds by knowledge, each with its own figures
    everyone = np.ones_like(child)
    samples = {"adult": (adult, p), "child": (child, p), "age_unknown": (everyone, integrated)}
    thresholds: dict[str, dict[str, Any]] = {}
    for op, req in (("sens85", cfg.sensitivity), ("acs_cot", cfg.acs_cot_sensitivity)):
        thresholds[op] = {}
        for j, (know, (mask, q)) in enumerate(samples.items()):
            target = target_with_margin(req, float(y[mask].sum()))
            t = threshold_for_sensitivity(y[mask], q[mask], target)
            thresholds[op][know] = {"threshold": t, "target_sensitivity": target}
            figs: dict[str, Any] = {}
            for name, gmask in groups.items():
                sel = gmask & mask
                if not sel.any() or y[sel].sum() == 0:
                    continue
                r = res(sel, 61 + j)
                figs[name] = triage_figures(
                    y[sel], q[sel] >= t, w[sel], [_local(ix, sel) for ix in r]
                )
            if know == "age_unknown":
                r = res(mask, 71)
                figs["everyone"] = triage_figures(y, q >= t, w, r)
            thresholds[op][know]["figures"] = figs
    out["thresholds_by_knowledge"] = thresholds
    return out


def _children_choice(
    d: RiskData,
    y: FloatArray,
    p: FloatArray,
    spec: Spec,
    folds: Sequence[tuple[IntArray, IntArray]],
    cfg: RiskConfig,
    plain_columns: Sequence[str],
) -> dict[str, Any]:
    """The shared model against a separate regression and the plain one, each as fitted."""
    w = d.w
    child = np.asarray(d.arrays["age_years"], dtype=np.float64) < CHILD_MAX_AGE_YEARS
    child_folds = _restricted(folds, child)
    logistic = spec.part("logistic") if spec.kind == "blend" else spec
    if logistic.kind != "logistic":
        logistic = Spec(spec.groups, spec.c, spec.drift)
    separate = _oof_of(lambda tr: fit_spec(d, y, tr, logistic, cfg), d, child_folds)
    child_cols = [ALL_COLUMNS_3.index(c) for c in (*plain_columns, *_child_columns())]

    def plain_fit(tr: IntArray) -> AnyFitted:
        # columns constant among the training children (e.g. the clamped age) are dropped;
        # near-collinear ones (stature and mass clamped at their floors) leave the Newton
        # solver ill-conditioned, and scikit-learn then finishes with lbfgs (said, not wrong)
        cols = [c for c in child_cols if c == 0 or np.ptp(d.x[tr, c]) > 0]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", LinAlgWarning)
            return fit_model(d.x[tr], y[tr], w[tr], cols, None)

    plain = _oof_of(plain_fit, d, child_folds)
    yc, wc = y[child], w[child]
    choice: dict[str, Any] = {
        "shared_with_child_terms": {
            "log_loss": log_loss(yc, p[child]),
            **score(yc, p[child], wc, None),
        },
        "separate_regression": {
            "log_loss": log_loss(yc, separate[child]),
            **score(yc, separate[child], wc, None),
        },
        "plain_regression_on_children": {
            "log_loss": log_loss(yc, plain[child]),
            **score(yc, plain[child], wc, None),
        },
    }
    choice["chosen"] = min(
        ("shared_with_child_terms", "separate_regression"),
        key=lambda k: choice[k]["log_loss"],
    )
    return choice


def knowledge_groups(d: RiskData) -> dict[str, np.ndarray]:
    """The figures' groups by age (children apart) and child seat: name -> mask, shape (n,)."""
    age = np.asarray(d.arrays["age_years"], dtype=np.float64)
    child = age < CHILD_MAX_AGE_YEARS
    adult = ~child
    restraint = np.asarray(d.arrays["restraint"], dtype=object)
    return {
        "children": child,
        "children 0-4": child & (age < 5),
        "children 5-9": child & (age >= 5) & (age < 10),
        "children 10-15": child & (age >= 10),
        "children in a child seat": child & (restraint == "child_seat"),
        "adults": adult,
        "adults 16-44": adult & (age < 45),
        "adults 45-64": adult & (age >= 45) & (age < 65),
        "adults 65+": adult & (age >= 65),
    }


def _child_columns() -> tuple[str, ...]:
    return tuple(c for cols in CHILD_GROUPS.values() for c in cols)


def _local(ix: IntArray, mask: np.ndarray) -> IntArray:
    """Global row indices of a resample as positions within the rows of `mask`."""
    pos = np.cumsum(mask) - 1
    out: IntArray = pos[ix]
    return out
