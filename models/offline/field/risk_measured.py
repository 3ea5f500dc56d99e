"""The measured-delta-V consistency check: held out by crash, delta-V as a vehicle measures it.

A notification's delta-V is measured by the vehicle; the field data's was
reconstructed. The service reads a measured value as the reconstruction it
stands for (:mod:`models.field.measurement`). This module checks that reading
the only way the data allow: each held-out occupant's delta-V is replaced by
one a vehicle could have measured in that crash, drawn from the measurement
model, and scored through each fold's model as served. It is a consistency
check, not a validation: the measurements pass through the model they check.

Two readings of the scatter between the two (``SD_KMH`` = 8.6 km/h, the SD of
their difference, n = 228), each drawn ``n_draws`` times per occupant (every
draw is scored; the figures are over all draws, each weighted 1 / n_draws):

``no_scatter``
    ``measured = reconstructed / f_d``, within the measurement's own tolerance
    (``MEASURED_TOLERANCE_SD``): the served reading's premise, and what the
    sources' direction implies for the check. The reconstruction is the noisier
    reading (:mod:`models.field.measurement`, "Which reading is the noisier"),
    so the risk curves, fitted on it, already carry its scatter; a precise
    measurement adds none.
``measurement_noisier``
    The opposite, as the bound of what the scatter would cost were the sources
    wrong: ``measured = (reconstructed - eps) / f_d``, ``eps ~ Normal(0,
    SD_KMH)``: the measured values are more spread than the reconstructions,
    and the served reading takes them at face value.

Why the sources' direction is not simulated with its scatter: drawing the
measured value from its posterior given the reconstruction keeps the outcome
independent of the measurement given the reconstruction, the opposite of that
direction's premise (the outcome follows the vehicle's delta-V, which the
measurement is). Such a draw can only lose information: tried on this fit (a
log-normal prior, the scatter at the population's root-mean-square delta-V),
it gave AUC 0.845 and predicted/observed 0.67 for adults, an artefact of the
simulation, not a property of measured delta-V.

``f_d`` is the served measurement model's ratio for the direction of the
occupant's delta-V (side or longitudinal).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Final

import numpy as np
from tqdm import tqdm

from models.arrays import FloatArray, IntArray
from models.field.measurement import MEASUREMENT_MODEL, SD_KMH, is_side
from models.field.risk_features import MAX_DELTA_V_KMH
from models.offline.field.metrics import threshold_for_sensitivity
from models.offline.field.risk_fit import AnyFitted, RiskConfig, RiskData
from models.offline.field.risk_knowledge import (
    SENSED_UNKNOWN,
    donor_table_of,
    integrated_probability,
)
from models.offline.field.risk_metrics import (
    crash_resamples,
    score,
    target_with_margin,
    triage_figures,
)

__all__ = [
    "CHECK_FILE",
    "MEASURED_DRAWS",
    "MEASURED_SEED",
    "READINGS",
    "check_document",
    "load_check",
    "measured_check",
    "measured_oof",
    "simulated_measured_kmh",
    "write_check",
]

#: The readings of the scatter (module docstring), the sources' direction first.
READINGS: Final[tuple[str, ...]] = ("no_scatter", "measurement_noisier")

#: Smallest simulated measurement, km/h (the largest is the wire's and the features' bound,
#: :data:`models.field.risk_features.MAX_DELTA_V_KMH`).
_MIN_KMH: Final[float] = 1.0


def _ratio(pdof_deg: FloatArray) -> FloatArray:
    """The served measurement model's mean ratio reconstructed / measured, shape (n,)."""
    side = np.array([is_side(p) for p in np.asarray(pdof_deg, dtype=np.float64)])
    out: FloatArray = np.where(
        side, MEASUREMENT_MODEL.mean_ratio(90.0), MEASUREMENT_MODEL.mean_ratio(0.0)
    )
    return out


def simulated_measured_kmh(
    reading: str,
    reconstructed_kmh: FloatArray,
    pdof_deg: FloatArray,
    rng: np.random.Generator,
) -> FloatArray:
    """One draw of what a vehicle would have measured, per occupant, km/h, shape (n,).

    Parameters
    ----------
    reading : str
        One of :data:`READINGS`.
    reconstructed_kmh, pdof_deg : ndarray, shape (n,)
        The reconstruction and the direction of its delta-V (side or longitudinal).
    rng : numpy.random.Generator
    """
    rec = np.asarray(reconstructed_kmh, dtype=np.float64)
    ratio = _ratio(pdof_deg)
    tolerance = 1.0 + MEASUREMENT_MODEL.tolerance_sd * rng.standard_normal(rec.size)
    if reading == "no_scatter":
        true_kmh = rec / ratio
    elif reading == "measurement_noisier":
        true_kmh = (rec - rng.normal(0.0, SD_KMH, rec.size)) / ratio
        tolerance = np.ones_like(rec)  # the scatter is the measurement's own
    else:
        raise ValueError(f"unknown reading {reading!r}")
    out: FloatArray = np.clip(true_kmh * tolerance, _MIN_KMH, MAX_DELTA_V_KMH)
    return out


def measured_oof(
    d: RiskData,
    fold_models: Sequence[AnyFitted],
    folds: Sequence[tuple[IntArray, IntArray]],
    reading: str,
    n_draws: int,
    seed: int,
    sensed_only: bool,
) -> dict[str, FloatArray]:
    """Held-out P with simulated measured delta-V, as served.

    Returns
    -------
    dict
        ``p`` shape (n_draws, n): the probability with the occupant's inputs
        sent; ``p_sensed`` (when `sensed_only`) with age, sex, stature and mass
        unknown; ``measured_kmh`` shape (n_draws, n).
    """
    n = d.x.shape[0]
    rec = np.asarray(d.arrays["delta_v_kmh"], dtype=np.float64)
    pdof = np.asarray(d.arrays["pdof_deg"], dtype=np.float64)
    rng = np.random.default_rng(seed)
    out = {"p": np.empty((n_draws, n)), "measured_kmh": np.empty((n_draws, n))}
    if sensed_only:
        out["p_sensed"] = np.empty((n_draws, n))
    for (tr, te), f in tqdm(
        list(zip(folds, fold_models, strict=True)), desc=f"measured: {reading}", leave=False
    ):
        table = donor_table_of(d, tr)
        year = float(d.year[tr].max())
        for k in range(n_draws):
            m = simulated_measured_kmh(reading, rec[te], pdof[te], rng)
            out["measured_kmh"][k, te] = m
            out["p"][k, te] = integrated_probability(f, d, te, table, year, (), m)
            if sensed_only:
                out["p_sensed"][k, te] = integrated_probability(
                    f, d, te, table, year, SENSED_UNKNOWN, m
                )
    return out


def _stack(y: FloatArray, w: FloatArray, p: FloatArray) -> tuple[FloatArray, ...]:
    """Draws stacked as rows: y, p, w / n_draws, each shape (n_draws * n,)."""
    k = p.shape[0]
    return np.tile(y, k), p.reshape(-1), np.tile(w, k) / k


def measured_check(
    d: RiskData,
    cfg: RiskConfig,
    sims: dict[str, dict[str, FloatArray]],
    groups: dict[str, np.ndarray],
    served_thresholds: dict[str, dict[str, float]],
) -> dict[str, Any]:
    """Figures of each reading: scores per group, and each operating point at the
    served thresholds and at thresholds set on the reading's own held-out P.

    Parameters
    ----------
    sims : dict
        Reading -> :func:`measured_oof`'s output.
    groups : dict
        Group name -> mask, shape (n,).
    served_thresholds : dict
        Operating point -> knowledge (``adult``, ``child``, ``age_unknown``) -> threshold.
    """
    y, w = d.outcomes[0].y, d.w
    child, adult = groups["children"], groups["adults"]
    everyone = np.ones_like(child)

    def res(mask: np.ndarray, n_draws: int, seed: int) -> list[IntArray]:
        # resamples by crash of the rows of `mask`, each crash's draws kept together
        idx = np.flatnonzero(mask)
        base = crash_resamples(d.crash[idx], cfg.n_metric_bootstrap, seed)
        return [np.concatenate([r + j * idx.size for j in range(n_draws)]) for r in base]

    out: dict[str, Any] = {}
    for reading, sim in sims.items():
        kdraws = sim["p"].shape[0]
        rec = np.asarray(d.arrays["delta_v_kmh"], dtype=np.float64)
        block: dict[str, Any] = {
            "draws": kdraws,
            "measured_over_reconstructed_weighted": float(
                np.average(sim["measured_kmh"] / rec, weights=np.tile(w, (kdraws, 1)))
            ),
            "age_sent": {},
            "sensed_only": {},
            "operating_points": {},
        }
        kinds = [("age_sent", sim["p"])] + (
            [("sensed_only", sim["p_sensed"])] if "p_sensed" in sim else []
        )
        for kind, p in kinds:
            for j, (name, mask) in enumerate(groups.items()):
                if not mask.any() or y[mask].sum() == 0:
                    continue
                yy, pp, ww = _stack(y[mask], w[mask], p[:, mask])
                block[kind][name] = score(yy, pp, ww, res(mask, kdraws, 231 + j))
        samples = {"adult": (adult, "age_sent"), "child": (child, "age_sent")}
        if "p_sensed" in sim:
            samples["age_unknown"] = (everyone, "sensed_only")
        for op, req in (("sens85", cfg.sensitivity), ("acs_cot", cfg.acs_cot_sensitivity)):
            block["operating_points"][op] = {}
            for j, (know, (mask, kind)) in enumerate(samples.items()):
                p = sim["p"] if kind == "age_sent" else sim["p_sensed"]
                yy, pp, ww = _stack(y[mask], w[mask], p[:, mask])
                r = res(mask, kdraws, 251 + j)
                served = served_thresholds[op][know]
                target = target_with_margin(req, float(y[mask].sum()))
                own = threshold_for_sensitivity(yy, pp, target)
                block["operating_points"][op][know] = {
                    "served_threshold": served,
                    "at_served": triage_figures(yy, pp >= served, ww, r),
                    "own_threshold": own,
                    "target_sensitivity": target,
                    "at_own": triage_figures(yy, pp >= own, ww, r),
                }
        out[reading] = block
    return out


#: Draws of the simulated measurement per held-out occupant and reading. [R] Two:
#: the figures average over them (their spread is a fraction of the intervals by
#: resampling crashes); each draw costs a pass of every occupant through the trees
#: over its 6 quadrature nodes, times 32 donors for the ages unknown.
MEASURED_DRAWS: Final[int] = 2

#: Seed of the simulated measurements.
MEASURED_SEED: Final[int] = 563

#: File name of the check's figures beside the model card (``docs/field``).
CHECK_FILE: Final[str] = "measured_check.json"


def check_document(doc: Mapping[str, Any], figures: Mapping[str, Any]) -> dict[str, Any]:
    """The check's figures bound to the artifact they check (its version and checksum)."""
    return {
        "model": {
            "name": doc["model"]["name"],
            "version": doc["model"]["version"],
            "content_sha256": doc["content_sha256"],
        },
        "measurement_model": {
            "name": doc["measurement_model"]["name"],
            "version": doc["measurement_model"]["version"],
        },
        "readings": list(READINGS),
        "draws": MEASURED_DRAWS,
        "figures": dict(figures),
    }


def load_check(doc: Mapping[str, Any], path: Path) -> dict[str, Any] | None:
    """The check written for `doc` at `path`, or None (absent, or of another artifact)."""
    if not path.is_file():
        return None
    check: dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
    if check.get("model", {}).get("content_sha256") != doc.get("content_sha256"):
        return None
    return check


def write_check(check: Mapping[str, Any], path: Path) -> Path:
    """Write the check's document (sorted keys, one trailing newline)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(check, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return path
