"""The occupant models' triage against real crashes: NASS-CDS frontal occupants.

The occupant models (LPMs) are built from dummy physics, not from crash
records, and their P(ISS >= 15) is not calibrated on field outcomes (README,
"Known limitation"). This check runs the service's own occupant-model answer
over the real front-seat occupants of frontal crashes in the shipped NASS-CDS
1997-2000 extract (`models/offline/data`, the baseline's training data) and
asks how well it ranks and flags the outcome recorded there.

What is compared, per occupant of a frontal crash (NASS ``frontal`` = 1):

* the LPM's zero-load-corrected P(ISS >= 15), exactly as the service computes
  it for a summary notification (delta-V = the band midpoint of ``dvcat``,
  PDOF 0, the occupant's seat, belt, frontal airbag state, age; body from sex:
  male -> Hybrid III 50th male, female -> 5th female; posture and seat track
  unknown -> the service defaults);
* the statistical baseline's probability (fitted on these very rows, so its
  figures are in-sample and flattering);
* delta-V alone.

Outcome: ``injSeverity`` 3 or 4, the police rating "incapacitating or
killed", the proxy the baseline is fitted to. It is **not** ISS >= 15: it is
broader (weighted prevalence about 11 %), so the LPM's probabilities are not
expected to match its rates; the ranking (AUC) and the share of serious cases
the LPM's decision flags (sensitivity) are what the check is about.

Restraint effects (:func:`restraint_effects`): the difference the belt, and
the frontal airbag with and without the belt, make to the outcome rate in the
field and to the occupant models' P, each standardised over the delta-V
bands (a weighted mean of the within-band differences, with the band's
weight in the compared rows), per sex and pooled (the pooled rows are not
standardised over sex). The field differences carry 95 % intervals from a
bootstrap over the survey's primary sampling units (PSUs, the first field of
``caseid``, 24 in the extract: NASS-CDS is a cluster sample, so resampling
rows would understate the spread). The bootstrap is a simple one: it ignores
the survey's strata and draws n of the n PSUs (the Rao-Wu form draws n - 1,
which widens the intervals by about 2 %), and a replicate that lacks one of
the groups in a band the point estimate uses is dropped (the share dropped is
reported). The data are observational: airbag-equipped vehicles are newer
(model years 1992-2000 against 1979-1994, 5th-95th percentiles of the rows),
so each field difference is also given over the vehicles of model year
:data:`COMMON_MODEL_YEAR` and later. The outcome is broader than
ISS >= 15, so signs and whether an effect is distinguishable from zero
compare, and sizes only one way (a model P above the field rate is too
harsh).

Run::

    python -m models.offline.field_check [--out DIR]

Writes ``field_check.md`` and ``field_check.png`` to ``DIR`` (default: this
package's directory) and prints the summary.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from sklearn.metrics import roc_auc_score, roc_curve

from models.arrays import BoolArray, FloatArray, IntArray
from models.impact_mode import ImpactMode
from models.injury.assessment import assess
from models.notification import (
    AirbagState,
    Body,
    Occupant,
    Seat,
    summary_notification,
)
from models.offline.baseline.fit import (
    DELTA_V_BAND_MIDPOINTS_KMH,
    NOT_SERIOUS_SEVERITIES,
    SERIOUS_SEVERITIES,
    default_data_path,
    triage_rates,
)
from models.offline.paths import docs_dir
from models.risk_calibration import corrected_probability, zero_load_probability
from models.triage import LPM_THRESHOLDS, EngineModels, load_engine_models, simulate_notification

__all__ = [
    "FieldCase",
    "FieldCheck",
    "GroupRate",
    "RestraintEffect",
    "field_cases",
    "group_rates",
    "lpm_probabilities",
    "restraint_effects",
    "run_field_check",
]


#: NASS ``dvcat`` bands in order (labels as in the data).
BANDS: tuple[str, ...] = tuple(DELTA_V_BAND_MIDPOINTS_KMH)
#: Frontal thresholds tabulated (the service's 0.10 among them; 0.02 Lubbe & Kiuchi,
#: 0.20 CDC 2008: crash-data-and-triage.md section 1).
THRESHOLDS: tuple[float, ...] = (0.02, 0.03, 0.05, 0.075, 0.10, 0.15, 0.20)
#: Seed of the PSU bootstrap of the restraint effects. [R] Fixed so that the
#: shipped field_check.md is reproduced bit for bit.
BOOTSTRAP_SEED = 20261203
#: PSU resamples of the bootstrap. [R] Measured 2026-12-03 against seeds 1, 2,
#: 3 and 777: the interval bounds moved by up to 2.4 percentage points with
#: 2000 replicates (the tails of the small subsets) and by about 1 point with
#: 10,000, which take 0.15 s.
BOOTSTRAP_REPLICATES = 10_000
#: First vehicle model year of the restricted comparison. [R] In the frontal
#: rows the airbag-equipped vehicles span model years 1992-2000 and the others
#: 1979-1994 (5th-95th percentiles of the rows); from 1994 on both kinds occur
#: in every delta-V band, belted and unbelted, though only about 10 % of those
#: rows are without an airbag (2-128 per band), hence the wide intervals.
COMMON_MODEL_YEAR = 1994
#: Distance of an interval bound from zero (percentage points) under which the
#: report calls the verdict "distinguishable from zero" or not borderline. [R]
#: About the seed-to-seed movement of a bound (BOOTSTRAP_REPLICATES, above).
BORDERLINE_POINTS = 1.0
#: The compared restraint contrasts, name -> description (the rows each compares
#: and which of them are "with" the restraint: :func:`_contrast`).
CONTRASTS: dict[str, str] = {
    "belt": "belted vs unbelted",
    "airbag_belted": "frontal airbag vs none, belted",
    "airbag_unbelted": "frontal airbag vs none, unbelted",
}
#: Populations of the restraint effects.
POPULATIONS: tuple[str, ...] = ("male", "female", "all")
#: Restraint groups of the rate table, name -> (belted, frontal airbag fitted).
RESTRAINT_GROUPS: dict[str, tuple[bool, bool]] = {
    "belt + airbag": (True, True),
    "belt only": (True, False),
    "airbag only": (False, True),
    "unrestrained": (False, False),
}


@dataclass(frozen=True)
class FieldCase:
    """One NASS-CDS front-seat occupant of a frontal crash."""

    band: str
    delta_v_kmh: float
    seat: Seat
    belted: bool
    frontal_airbag: AirbagState
    male: bool
    age_years: float
    serious: bool
    weight: float
    #: primary sampling unit (first field of ``caseid``)
    psu: int
    #: vehicle model year (None when not recorded)
    vehicle_year: int | None


def field_cases(csv_path: Path | None = None) -> list[FieldCase]:
    """The frontal-crash occupants of the NASS-CDS extract with a known outcome.

    Rows are excluded as the baseline excludes them (``injSeverity`` empty, 5
    or 6, weight 0), and so are non-frontal crashes.
    """
    path = default_data_path() if csv_path is None else csv_path
    out = []
    with path.open(newline="", encoding="utf-8") as fh:
        for rec in csv.DictReader(fh):
            sev_text = rec["injSeverity"].strip()
            if sev_text in ("", "NA") or rec["frontal"] != "1":
                continue
            sev = int(float(sev_text))
            weight = float(rec["weight"])
            if sev not in SERIOUS_SEVERITIES | NOT_SERIOUS_SEVERITIES or weight <= 0.0:
                continue
            if rec["airbag"] == "none":
                bag = AirbagState.ABSENT
            else:
                bag = AirbagState.DEPLOYED if rec["deploy"] == "1" else AirbagState.NOT_DEPLOYED
            out.append(
                FieldCase(
                    band=rec["dvcat"],
                    delta_v_kmh=DELTA_V_BAND_MIDPOINTS_KMH[rec["dvcat"]],
                    seat=Seat.DRIVER if rec["occRole"] == "driver" else Seat.FRONT_PASSENGER,
                    belted=rec["seatbelt"] == "belted",
                    frontal_airbag=bag,
                    male=rec["sex"] == "m",
                    age_years=float(rec["ageOFocc"]),
                    serious=sev in SERIOUS_SEVERITIES,
                    weight=weight,
                    psu=int(rec["caseid"].split(":")[0]),
                    vehicle_year=_year(rec["yearVeh"]),
                )
            )
    return out


def _year(text: str) -> int | None:
    t = text.strip()
    return None if t in ("", "NA") else int(float(t))


def _body(case: FieldCase) -> Body:
    return Body.MALE_50TH if case.male else Body.FEMALE_5TH


def lpm_probabilities(cases: Sequence[FieldCase], models: EngineModels) -> FloatArray:
    """The service's occupant-model P(ISS >= 15) for each case.

    One LPM run per distinct (delta-V, seat, belt, airbag, body), assessed at
    each occupant's age and corrected for the zero-load floor, as
    :func:`models.triage.triage` does for a summary notification.

    Returns
    -------
    ndarray, shape (n,)
    """
    runs = {}
    for case in cases:
        key = (case.delta_v_kmh, case.seat, case.belted, case.frontal_airbag, _body(case))
        if key in runs:
            continue
        occupant = Occupant(
            seat=case.seat, body=key[4], belted=case.belted, frontal_airbag=case.frontal_airbag
        )
        notification = summary_notification(
            (occupant,), case.delta_v_kmh, 0.0, event_id="field-check"
        )
        _, sims, _ = simulate_notification(notification, models)
        result = sims[0].result
        if result is None or result.assessment is None:
            raise RuntimeError(f"occupant model failed for {key}")
        runs[key] = result.measures
    p = np.empty(len(cases))
    for i, case in enumerate(cases):
        body = _body(case)
        measures = runs[(case.delta_v_kmh, case.seat, case.belted, case.frontal_airbag, body)]
        raw = assess(measures, body, case.age_years, ImpactMode.FRONTAL.value).p_iss15
        p0 = zero_load_probability(measures, body, case.age_years, ImpactMode.FRONTAL)
        p[i] = corrected_probability(raw, p0)
    return p


@dataclass(frozen=True)
class RestraintEffect:
    """A restraint's effect on the outcome in the field and on the models' P.

    Differences are "with" minus "without" (negative: the restraint lowers
    the risk), standardised over the delta-V bands.
    """

    population: str
    contrast: str
    n_with: int
    n_without: int
    field: float
    field_ci95: tuple[float, float]
    #: the same over the vehicles of model year COMMON_MODEL_YEAR and later
    field_recent: float
    field_recent_ci95: tuple[float, float]
    model: float
    #: shares of the bootstrap replicates dropped (a group missing from a band)
    dropped: float = 0.0
    dropped_recent: float = 0.0


def _columns(cases: Sequence[FieldCase]) -> tuple[FloatArray, FloatArray, IntArray, IntArray]:
    """Outcome (0/1), survey weight, delta-V band index and PSU of each case."""
    y = np.array([1.0 if c.serious else 0.0 for c in cases])
    w = np.array([c.weight for c in cases])
    band = np.array([BANDS.index(c.band) for c in cases], dtype=np.int64)
    psu = np.array([c.psu for c in cases], dtype=np.int64)
    return y, w, band, psu


def _psu_draws(psu: IntArray, replicates: int, seed: int) -> tuple[IntArray, FloatArray]:
    """The survey's PSUs and, per bootstrap replicate, how often each is drawn.

    Returns
    -------
    all_psus : ndarray, shape (n_psu,)
    draws : ndarray, shape (replicates, n_psu)
        Multiplicities (each row sums to n_psu): PSUs drawn with replacement.
    """
    all_psus = np.unique(psu)
    if len(all_psus) < 2:
        raise ValueError("a cluster bootstrap needs at least two PSUs")
    rng = np.random.default_rng(seed)
    draws = rng.multinomial(
        len(all_psus), np.full(len(all_psus), 1.0 / len(all_psus)), size=replicates
    ).astype(np.float64)
    return all_psus, draws


def _masks(cases: Sequence[FieldCase]) -> dict[str, BoolArray]:
    return {
        "male": np.array([c.male for c in cases]),
        "belted": np.array([c.belted for c in cases]),
        "airbag": np.array([c.frontal_airbag is not AirbagState.ABSENT for c in cases]),
        "recent": np.array(
            [c.vehicle_year is not None and c.vehicle_year >= COMMON_MODEL_YEAR for c in cases]
        ),
    }


def _contrast(name: str, m: dict[str, BoolArray]) -> tuple[BoolArray, BoolArray]:
    """Rows compared and rows "with" of a contrast (boolean masks)."""
    every = np.ones(m["belted"].shape, dtype=bool)
    if name == "belt":
        return every, m["belted"]
    if name == "airbag_belted":
        return m["belted"], m["airbag"]
    if name == "airbag_unbelted":
        return ~m["belted"], m["airbag"]
    raise ValueError(f"unknown contrast {name!r}")


def _standardised(swy: FloatArray, sw: FloatArray, bands: BoolArray | None = None) -> FloatArray:
    """Band-standardised difference from sums by (..., band, without/with).

    Parameters
    ----------
    swy, sw : ndarray, shape (..., n_bands, 2)
        Weighted outcome sums and weight sums of the "without" (0) and "with"
        (1) rows per band.
    bands : ndarray of bool, shape (n_bands,), optional
        The bands to use (a bootstrap replicate uses those of its point
        estimate); a result that lacks a group in one of them is NaN. By
        default every band holding both groups is used.

    Returns
    -------
    ndarray, shape (...)
        The weighted mean of the within-band differences "with" - "without",
        each band weighted by its total weight; NaN where nothing compares.
    """
    both = (sw[..., 0] > 0.0) & (sw[..., 1] > 0.0)
    rate = np.divide(swy, sw, out=np.zeros_like(swy), where=sw > 0.0)
    use = both if bands is None else np.broadcast_to(bands, both.shape)
    band_w = np.where(use, sw.sum(axis=-1), 0.0)
    diff = rate[..., 1] - rate[..., 0]
    num = np.asarray((band_w * diff).sum(axis=-1), dtype=np.float64)
    den = np.asarray(band_w.sum(axis=-1), dtype=np.float64)
    valid = den > 0.0
    if bands is not None:
        valid &= np.all(both | ~use, axis=-1)
    return np.divide(num, den, out=np.full_like(num, np.nan), where=valid)


def _psu_sums(
    value: FloatArray, weight: FloatArray, band: IntArray, group: IntArray, psu: IntArray
) -> tuple[IntArray, FloatArray, FloatArray]:
    """Weighted sums by (PSU, band, group).

    Returns
    -------
    psus : ndarray, shape (n_psu,)
        The PSUs present, sorted.
    swy, sw : ndarray, shape (n_psu, n_bands, 2)
        Sums of ``weight * value`` and of ``weight``.
    """
    psus, pidx = np.unique(psu, return_inverse=True)
    cell = (pidx * len(BANDS) + band) * 2 + group
    size = len(psus) * len(BANDS) * 2
    shape = (len(psus), len(BANDS), 2)
    # (float even for an empty selection, where bincount returns integers)
    swy = np.bincount(cell, weights=weight * value, minlength=size).astype(np.float64)
    sw = np.bincount(cell, weights=weight, minlength=size).astype(np.float64)
    return psus, swy.reshape(shape), sw.reshape(shape)


def _field_replicates(
    y: FloatArray,
    w: FloatArray,
    band: IntArray,
    group: IntArray,
    psu: IntArray,
    draws: FloatArray,
    all_psus: IntArray,
) -> tuple[float, FloatArray]:
    """Point difference and its PSU-bootstrap replicates.

    A cluster bootstrap written here rather than ``scipy.stats.bootstrap``,
    which resamples observations, not clusters: each replicate draws the
    survey's PSUs with replacement (``draws``, their multiplicities) and
    recomputes the difference from per-PSU sums, so the replicates cost one
    matrix product.

    Parameters
    ----------
    y, w : ndarray, shape (n,)
        Outcome (0/1, or the models' P) and survey weight of the compared rows.
    band, group, psu : ndarray of int, shape (n,)
        Delta-V band index, 1 "with" / 0 "without", PSU.
    draws : ndarray, shape (replicates, n_psu)
        Multiplicity of every PSU of the survey in each replicate (:func:`_psu_draws`).
    all_psus : ndarray, shape (n_psu,)
        The survey's PSUs, sorted (the columns of ``draws``).

    Returns
    -------
    point : float
        NaN when no band holds both groups.
    replicates : ndarray, shape (replicates,)
        NaN for a replicate lacking a group in a band the point uses.
    """
    psus, swy, sw = _psu_sums(y, w, band, group, psu)
    tot_y, tot_w = swy.sum(axis=0), sw.sum(axis=0)
    point = float(_standardised(tot_y, tot_w))
    bands = (tot_w[:, 0] > 0.0) & (tot_w[:, 1] > 0.0)
    mult = draws[:, np.searchsorted(all_psus, psus)]
    reps = _standardised(
        np.einsum("bp,pkg->bkg", mult, swy), np.einsum("bp,pkg->bkg", mult, sw), bands
    )
    return point, reps


def _interval(reps: FloatArray) -> tuple[tuple[float, float], float]:
    """Percentile 95 % interval of the valid replicates, and the share dropped (NaN)."""
    ok = np.isfinite(reps)
    if not ok.any():
        return (math.nan, math.nan), 1.0
    lo, hi = np.percentile(reps[ok], [2.5, 97.5])
    return (float(lo), float(hi)), float(1.0 - ok.mean())


def restraint_effects(
    cases: Sequence[FieldCase],
    p_lpm: FloatArray,
    *,
    replicates: int = BOOTSTRAP_REPLICATES,
    seed: int = BOOTSTRAP_SEED,
) -> tuple[RestraintEffect, ...]:
    """Belt and airbag effects in the field and in the occupant models.

    Parameters
    ----------
    cases : sequence of FieldCase
    p_lpm : ndarray, shape (n,)
        The occupant models' P(ISS >= 15) of each case (:func:`lpm_probabilities`).
    replicates : int, optional
        PSU bootstrap replicates.
    seed : int, optional
        Seed of the PSU resamples (:func:`group_rates` draws the same ones).

    Returns
    -------
    tuple of RestraintEffect
        One per population (:data:`POPULATIONS`) and contrast (:data:`CONTRASTS`).
    """
    y, w, band, psu = _columns(cases)
    # the same PSU resamples for every contrast (paired intervals)
    all_psus, draws = _psu_draws(psu, replicates, seed)
    m = _masks(cases)
    pop_mask = {"male": m["male"], "female": ~m["male"], "all": np.ones(len(cases), dtype=bool)}
    out = []
    for pop in POPULATIONS:
        for name in CONTRASTS:
            rows, with_ = _contrast(name, m)
            sel = rows & pop_mask[pop]
            group = with_.astype(np.int64)
            fields = []
            for subset in (sel, sel & m["recent"]):
                point, reps = _field_replicates(
                    y[subset], w[subset], band[subset], group[subset], psu[subset], draws, all_psus
                )
                ci, dropped = _interval(reps) if math.isfinite(point) else ((point, point), 1.0)
                fields.append((point, ci, dropped))
            _, swy, sw = _psu_sums(p_lpm[sel], w[sel], band[sel], group[sel], psu[sel])
            out.append(
                RestraintEffect(
                    population=pop,
                    contrast=name,
                    n_with=int((sel & with_).sum()),
                    n_without=int((sel & ~with_).sum()),
                    field=fields[0][0],
                    field_ci95=fields[0][1],
                    field_recent=fields[1][0],
                    field_recent_ci95=fields[1][1],
                    model=float(_standardised(swy.sum(axis=0), sw.sum(axis=0))),
                    dropped=fields[0][2],
                    dropped_recent=fields[1][2],
                )
            )
    return tuple(out)


@dataclass(frozen=True)
class GroupRate:
    """The outcome rate of one restraint group in one delta-V band, field and models."""

    group: str
    band: str
    n: int
    field: float
    field_ci95: tuple[float, float]
    #: the occupant models' mean P(ISS >= 15) over the same occupants (weighted)
    model: float
    #: share of the bootstrap replicates dropped (none of the cell's PSUs drawn)
    dropped: float = 0.0


def group_rates(
    cases: Sequence[FieldCase],
    p_lpm: FloatArray,
    *,
    replicates: int = BOOTSTRAP_REPLICATES,
    seed: int = BOOTSTRAP_SEED,
) -> tuple[GroupRate, ...]:
    """Weighted outcome rate and the models' mean P per restraint group and band.

    The field rates carry 95 % intervals from the PSU bootstrap of
    :func:`restraint_effects` (the same resamples for the same seed).

    Parameters
    ----------
    cases : sequence of FieldCase
    p_lpm : ndarray, shape (n,)
        The occupant models' P(ISS >= 15) of each case.
    replicates : int, optional
        PSU bootstrap replicates.
    seed : int, optional
        Seed of the PSU resamples.

    Returns
    -------
    tuple of GroupRate
        One per group of :data:`RESTRAINT_GROUPS` and band with occupants.
    """
    y, w, band, psu = _columns(cases)
    all_psus, draws = _psu_draws(psu, replicates, seed)
    m = _masks(cases)
    out = []
    for name, (belted, airbag) in RESTRAINT_GROUPS.items():
        in_group = (m["belted"] == belted) & (m["airbag"] == airbag)
        for k, label in enumerate(BANDS):
            sel = in_group & (band == k)
            if not sel.any():
                continue
            psus, pidx = np.unique(psu[sel], return_inverse=True)
            swy = np.bincount(pidx, weights=(w * y)[sel], minlength=len(psus))
            sw = np.bincount(pidx, weights=w[sel], minlength=len(psus))
            mult = draws[:, np.searchsorted(all_psus, psus)]
            num, den = mult @ swy, mult @ sw
            reps = np.divide(num, den, out=np.full_like(num, np.nan), where=den > 0.0)
            ci, dropped = _interval(reps)
            out.append(
                GroupRate(
                    group=name,
                    band=label,
                    n=int(sel.sum()),
                    field=float(swy.sum() / sw.sum()),
                    field_ci95=ci,
                    model=float(np.average(p_lpm[sel], weights=w[sel])),
                    dropped=dropped,
                )
            )
    return tuple(out)


@dataclass(frozen=True)
class FieldCheck:
    """Weighted figures of the occupant models against the NASS frontal outcomes."""

    n: int
    #: primary sampling units among the cases (the bootstrap's clusters)
    n_psu: int
    prevalence: float
    auc_lpm: float
    auc_baseline: float
    auc_delta_v: float
    threshold: float
    sensitivity: float
    flagged_share: float
    over_triage: float
    #: per dvcat band: (n, observed weighted serious rate, mean LPM P, mean baseline P)
    by_band: dict[str, tuple[int, float, float, float]]
    #: per frontal threshold on the LPM's corrected P: (flagged share, sensitivity,
    #: over-triage), weighted
    by_threshold: dict[float, tuple[float, float, float]]
    #: belt and airbag effects, field against models (:func:`restraint_effects`)
    restraints: tuple[RestraintEffect, ...]
    #: outcome rate and models' P per restraint group and band (:func:`group_rates`)
    rates: tuple[GroupRate, ...]
    y: FloatArray
    weight: FloatArray
    p_lpm: FloatArray
    p_baseline: FloatArray
    delta_v: FloatArray


def run_field_check(models: EngineModels, csv_path: Path | None = None) -> FieldCheck:
    """Run the check (about 120 occupant-model runs and 8,000 assessments)."""
    cases = field_cases(csv_path)
    y = np.array([1.0 if c.serious else 0.0 for c in cases])
    w = np.array([c.weight for c in cases])
    dv = np.array([c.delta_v_kmh for c in cases])
    p_lpm = lpm_probabilities(cases, models)
    x = np.array(
        [
            [
                c.delta_v_kmh,
                1.0 if c.belted else 0.0,
                1.0 if c.frontal_airbag is AirbagState.DEPLOYED else 0.0,
                1.0,
                c.age_years,
                1.0 if c.male else 0.0,
            ]
            for c in cases
        ]
    )
    p_base = np.asarray(models.baseline.predict_many(x).probability, dtype=np.float64)
    threshold = LPM_THRESHOLDS[ImpactMode.FRONTAL]
    ut, ot = triage_rates(y, p_lpm, w, threshold)
    by_band = {}
    for band in BANDS:
        m = np.array([c.band == band for c in cases])
        if m.any():
            by_band[band] = (
                int(m.sum()),
                float(np.average(y[m], weights=w[m])),
                float(np.average(p_lpm[m], weights=w[m])),
                float(np.average(p_base[m], weights=w[m])),
            )
    by_threshold = {}
    for t in THRESHOLDS:
        ut_t, ot_t = triage_rates(y, p_lpm, w, t)
        by_threshold[t] = (float(np.average(p_lpm >= t, weights=w)), 1.0 - ut_t, ot_t)
    return FieldCheck(
        n=len(cases),
        n_psu=len({c.psu for c in cases}),
        prevalence=float(np.average(y, weights=w)),
        auc_lpm=float(roc_auc_score(y, p_lpm, sample_weight=w)),
        auc_baseline=float(roc_auc_score(y, p_base, sample_weight=w)),
        auc_delta_v=float(roc_auc_score(y, dv, sample_weight=w)),
        threshold=threshold,
        sensitivity=1.0 - ut,
        flagged_share=float(np.average(p_lpm >= threshold, weights=w)),
        over_triage=ot,
        by_band=by_band,
        by_threshold=by_threshold,
        restraints=restraint_effects(cases, p_lpm),
        rates=group_rates(cases, p_lpm),
        y=y,
        weight=w,
        p_lpm=p_lpm,
        p_baseline=p_base,
        delta_v=dv,
    )


def _markdown(fc: FieldCheck) -> str:
    lines = [
        "# The occupant models against real frontal crashes (NASS-CDS 1997-2000)",
        "",
        "Generated by `python -m models.offline.field_check` (see its docstring for the method and",
        "the caveats). Outcome: police-reported incapacitating or fatal injury, a broader",
        "proxy for ISS >= 15; all figures survey-weighted.",
        "",
        f"- Occupants of frontal crashes: {fc.n:,}; weighted share with the outcome "
        f"{100 * fc.prevalence:.1f} %.",
        f"- Weighted AUC: occupant models {fc.auc_lpm:.3f}; statistical baseline "
        f"{fc.auc_baseline:.3f} (in-sample: fitted on these rows); delta-V band alone "
        f"{fc.auc_delta_v:.3f}.",
        f"- The service's frontal decision (corrected P >= {fc.threshold:.2f}) flags "
        f"{100 * fc.flagged_share:.1f} % of these occupants and "
        f"{100 * fc.sensitivity:.1f} % of those with the outcome (sensitivity); "
        f"{100 * fc.over_triage:.1f} % of those without it (over-triage).",
        "",
        "| delta-V band (km/h) | occupants | outcome rate (weighted) | mean LPM P(ISS>=15) |"
        " mean baseline P |",
        "|---|---:|---:|---:|---:|",
    ]
    for band, (n, obs, p_l, p_b) in fc.by_band.items():
        lines.append(f"| {band} | {n:,} | {obs:.3f} | {p_l:.3f} | {p_b:.3f} |")
    lines += [
        "",
        "The frontal decision at other thresholds on the same corrected P (a choice for the",
        "trauma system; sensitivity and over-triage against the police-serious outcome):",
        "",
        "| threshold | flagged | sensitivity | over-triage |",
        "|---:|---:|---:|---:|",
    ]
    for t, (flagged, se, ot) in fc.by_threshold.items():
        mark = " (service)" if t == fc.threshold else ""
        lines.append(
            f"| {t:.3f}{mark} | {100 * flagged:.1f} % | {100 * se:.1f} % | {100 * ot:.1f} % |"
        )
    lines += _restraint_markdown(fc.restraints, fc.n_psu)
    lines += _rates_markdown(fc.rates)
    lines += [
        "",
        "Reading: the LPM probability is of ISS >= 15 for a dummy in a 2010 compact sedan,",
        "the outcome is a police rating in 1997-2000 vehicles; the ranking, the share",
        "flagged and the direction of the restraint effects compare, and sizes only one way",
        "(a model P above the field rate of the broader outcome is too harsh). The gap between",
        "the ranking by the LPM and by delta-V alone is what the occupant physics adds (belt,",
        "airbag, body, age) for these crashes.",
        "",
    ]
    return "\n".join(lines)


def _pp(x: float) -> str:
    """A difference of rates in percentage points, signed ("+0.0", not "-0.0")."""
    text = f"{100 * x:+.1f}"
    return "+0.0" if text == "-0.0" else text


def _ci(ci: tuple[float, float]) -> str:
    return f"[{_pp(ci[0])}, {_pp(ci[1])}]"


def _excludes_zero(ci: tuple[float, float]) -> bool:
    return ci[0] > 0.0 or ci[1] < 0.0


def _restraint_markdown(effects: Sequence[RestraintEffect], n_psu: int) -> list[str]:
    lines = [
        "",
        "## Restraint effects: the field against the occupant models",
        "",
        "Difference in percentage points, with the restraint minus without (negative: the",
        "restraint lowers the risk), standardised over the delta-V bands; the field's 95 %",
        f"intervals from {BOOTSTRAP_REPLICATES:,} bootstrap resamples of the {n_psu} primary",
        f"sampling units (seed {BOOTSTRAP_SEED}). Observational data: the airbag-equipped",
        "vehicles are newer, so the field difference is also given over vehicles of model",
        f"year {COMMON_MODEL_YEAR} and later.",
        "",
        "| population | contrast | occupants with / without | field | field, MY >= "
        f"{COMMON_MODEL_YEAR} | occupant models |",
        "|---|---|---:|---:|---:|---:|",
    ]
    for e in effects:
        lines.append(
            f"| {e.population} | {CONTRASTS[e.contrast]} | {e.n_with:,} / {e.n_without:,} | "
            f"{_pp(e.field)} {_ci(e.field_ci95)} | {_pp(e.field_recent)} "
            f"{_ci(e.field_recent_ci95)} | {_pp(e.model)} |"
        )
    pooled = {e.contrast: e for e in effects if e.population == "all"}
    lines.append("")
    for name, e in pooled.items():
        verdict = (
            "distinguishable from zero"
            if _excludes_zero(e.field_ci95)
            else "not distinguishable from zero"
        )
        if min(abs(e.field_ci95[0]), abs(e.field_ci95[1])) < BORDERLINE_POINTS / 100.0:
            verdict += f"; a bound within {BORDERLINE_POINTS:g} point of zero: borderline"
        lines.append(
            f"- {CONTRASTS[name].capitalize()}, all occupants: field {_pp(e.field)} points "
            f"({verdict}), occupant models {_pp(e.model)} points."
        )
    worst = max(effects, key=lambda e: max(e.dropped, e.dropped_recent))
    where = f"MY >= {COMMON_MODEL_YEAR}" if worst.dropped_recent > worst.dropped else "all vehicles"
    lines.append(
        "- Bootstrap replicates dropped for lack of a group in a band the estimate uses: at"
        f" most {100 * max(worst.dropped, worst.dropped_recent):.1f} % ({worst.population},"
        f" {CONTRASTS[worst.contrast]}, {where})."
    )
    belted = pooled["airbag_belted"]
    finding = (
        "shows no benefit of the bag to belted occupants distinguishable from zero"
        if belted.field_ci95[1] >= 0.0
        else f"shows a benefit of the bag to belted occupants ({_pp(belted.field)} points)"
    )
    lines += [
        "",
        "The occupant models' airbag effect for belted occupants bears on an open item of",
        "the occupant models (docs/lpm/notes.md: the bag adds head and chest load to a",
        "belted small driver whose head does not reach the wheel without it); the field",
        f"{finding} in these crashes.",
    ]
    return lines


def _rates_markdown(rates: Sequence[GroupRate]) -> list[str]:
    lines = [
        "",
        "## Outcome rate by restraint and delta-V: the field against the occupant models",
        "",
        "Weighted police-serious rate of each restraint group (frontal airbag fitted or not)",
        "with its 95 % PSU-bootstrap interval, and the occupant models' mean P(ISS >= 15) over",
        "the same occupants. ISS >= 15 is the narrower outcome, so a model P above the field",
        "interval is harsher than the field on any reading.",
        "",
        "| restraint | delta-V band (km/h) | occupants | field rate | occupant models' P |",
        "|---|---|---:|---:|---:|",
    ]
    for r in rates:
        lines.append(
            f"| {r.group} | {r.band} | {r.n:,} | {100 * r.field:.1f} % "
            f"[{100 * r.field_ci95[0]:.1f}, {100 * r.field_ci95[1]:.1f}] | {100 * r.model:.1f} % |"
        )
    above = [r for r in rates if r.model > r.field_ci95[1]]
    lines.append("")
    if above:
        cells = "; ".join(
            f"{r.group} {r.band} km/h ({100 * r.model:.1f} % against {100 * r.field_ci95[1]:.1f} %)"
            for r in above
        )
        lines.append(
            f"The occupant models' P is above the field interval in: {cells}. Everywhere else it"
            " is inside or below it."
        )
    else:
        lines.append("The occupant models' P is nowhere above the field interval.")
    return lines


def _plot(fc: FieldCheck, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ((ax1, ax2), (ax3, ax4)) = plt.subplots(2, 2, figsize=(14, 9.5))
    for label, score, auc in (
        ("occupant models", fc.p_lpm, fc.auc_lpm),
        ("baseline (in-sample)", fc.p_baseline, fc.auc_baseline),
        ("delta-V band", fc.delta_v, fc.auc_delta_v),
    ):
        fpr, tpr, _ = roc_curve(fc.y, score, sample_weight=fc.weight)
        ax1.plot(fpr, tpr, label=f"{label} (AUC {auc:.3f})")
    ax1.plot([0, 1], [0, 1], "k:", lw=0.8)
    ax1.set_xlabel("false positive rate (weighted)")
    ax1.set_ylabel("true positive rate (weighted)")
    ax1.set_title("NASS-CDS frontal occupants")
    ax1.legend(fontsize=8, loc="lower right")
    bands = list(fc.by_band)
    xs = np.arange(len(bands))
    ax2.plot(xs, [fc.by_band[b][1] for b in bands], "o-", label="outcome rate (police)")
    ax2.plot(xs, [fc.by_band[b][2] for b in bands], "s-", label="mean LPM P(ISS>=15)")
    ax2.plot(xs, [fc.by_band[b][3] for b in bands], "^-", label="mean baseline P")
    ax2.axhline(fc.threshold, color="k", lw=0.8)
    ax2.set_xticks(xs, bands)
    ax2.set_xlabel("delta-V band (km/h)")
    ax2.set_ylabel("probability / rate")
    ax2.legend(fontsize=8)
    effects = fc.restraints
    ys = np.arange(len(effects))[::-1]
    field = np.array([100 * e.field for e in effects])
    err = np.array(
        [
            [100 * (e.field - e.field_ci95[0]) for e in effects],
            [100 * (e.field_ci95[1] - e.field) for e in effects],
        ]
    )
    ax3.errorbar(field, ys, xerr=err, fmt="o", capsize=3, label="field (95 % PSU bootstrap)")
    ax3.plot([100 * e.model for e in effects], ys, "s", label="occupant models")
    ax3.axvline(0.0, color="k", lw=0.8)
    ax3.set_yticks(ys, [f"{e.population}: {CONTRASTS[e.contrast]}" for e in effects], fontsize=8)
    ax3.set_xlabel("with - without, percentage points (band-standardised)")
    ax3.set_title("restraint effects: the field against the occupant models")
    ax3.legend(fontsize=8, loc="upper right")
    xs = np.arange(len(BANDS))
    for i, group in enumerate(RESTRAINT_GROUPS):
        rows = {r.band: r for r in fc.rates if r.group == group}
        bx = np.array([k for k, b in enumerate(BANDS) if b in rows], dtype=float)
        sel = [rows[b] for b in BANDS if b in rows]
        shift = 0.06 * (i - 1.5)
        line = ax4.errorbar(
            bx + shift,
            [100 * r.field for r in sel],
            yerr=[
                [100 * (r.field - r.field_ci95[0]) for r in sel],
                [100 * (r.field_ci95[1] - r.field) for r in sel],
            ],
            fmt="o-",
            capsize=2,
            lw=1.0,
            label=f"{group}: field",
        )
        ax4.plot(
            bx + shift,
            [100 * r.model for r in sel],
            "s--",
            color=line[0].get_color(),
            lw=1.0,
            label=f"{group}: occupant models",
        )
    ax4.set_xticks(xs, BANDS)
    ax4.set_xlabel("delta-V band (km/h)")
    ax4.set_ylabel("field rate / models' P(ISS>=15), %")
    ax4.set_title("by restraint: field (police-serious) and occupant models")
    ax4.legend(fontsize=7, ncol=2, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    """Command line entry point."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=docs_dir("field_check"))
    args = ap.parse_args(list(argv) if argv is not None else None)
    args.out.mkdir(parents=True, exist_ok=True)
    fc = run_field_check(load_engine_models(use_surrogates=False))
    text = _markdown(fc)
    (args.out / "field_check.md").write_text(text)
    _plot(fc, args.out / "field_check.png")
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
