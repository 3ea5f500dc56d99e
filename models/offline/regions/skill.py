"""The occupant models region by region against the real region outcomes (issue 39, item 3).

On every usable NASS-CDS 1997-2014 occupant an occupant model answers for
(:mod:`models.offline.regions.table`: front outboard seats, PDOF inside a
mode's coverage), each region's real outcome (the highest AIS in the AIS 1990
body region, :mod:`models.offline.regions.rows`) is set against:

- the occupant models' measures of that region (head: HIC15; neck: Nij;
  thorax: chest or rib deflection, VC, 3 ms acceleration, CTI; abdomen:
  abdominal VC);
- the published dummy risk curves' P(AIS >= 3) of the region as the engine
  combines them, and the region AIS level the engine shows (the body map);
- delta-V alone;
- the field-calibrated region risk (``occupants[].region_risk``, fitted by
  the field model's tools), when its cross-validated predictions are given
  (``--region-risk``): a CSV keyed by ``year, psu, caseno, vehno, occno`` with
  a column ``region_risk_<region>`` per region.

Outcomes: AIS 3+ in the region; the neck at AIS 2+ (AIS 3+ neck injuries are
too rare, and AIS 1990 codes the cervical spine in the spine region, which is
also given against Nij). Figures are survey-weighted (``ratwgt``) unless
marked; 95 % intervals from :class:`models.offline.regions.stats.CrashBootstrap`.
Calibration of the map: the share of occupants the models give AIS 3+ in the
region against the weighted share who had it; of the published curves'
probability: its weighted mean against the weighted observed rate.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np
import pandas as pd

from models.arrays import FloatArray
from models.offline.regions.stats import CrashBootstrap, Interval, crash_ids, weighted_auc

__all__ = [
    "MODES",
    "REGION_SPECS",
    "AisSixRow",
    "RegionSpec",
    "ScoreSkill",
    "ais_six_check",
    "analysis_frame",
    "region_skill",
]

#: The occupant models' modes, in report order.
MODES: Final[tuple[str, ...]] = ("frontal", "near_side", "far_side", "rear")


@dataclass(frozen=True)
class RegionSpec:
    """A region's outcome and the occupant-model scores held against it.

    Attributes
    ----------
    name : str
        Report label.
    outcome : tuple of str
        ``max_ais_<region>`` columns (the region's AIS is their maximum).
    level : int
        The outcome is AIS >= level.
    scores : tuple of (label, column)
        Occupant-model columns of the physics table, higher = worse.
    curve : str or None
        Column of the published curves' P(AIS >= 3) of the ISS region.
    map_column : str
        Column of the region AIS level the engine shows.
    risk_region : str or None
        Name of the field-calibrated region risk (``region_risk_<name>``).
    """

    name: str
    outcome: tuple[str, ...]
    level: int
    scores: tuple[tuple[str, str], ...]
    curve: str | None
    map_column: str
    risk_region: str | None


REGION_SPECS: Final[tuple[RegionSpec, ...]] = (
    RegionSpec(
        "head",
        ("max_ais_head",),
        3,
        (("HIC15", "hic15"),),
        "lpm_p_ais3_head_neck",
        "lpm_ais_head_neck",
        "head",
    ),
    RegionSpec(
        "neck",
        ("max_ais_neck",),
        2,
        (("Nij", "nij"),),
        None,
        "lpm_ais_head_neck",
        "neck",
    ),
    RegionSpec(
        "spine (cervical spine is here in AIS 1990)",
        ("max_ais_spine",),
        3,
        (("Nij", "nij"),),
        None,
        "lpm_ais_head_neck",
        "spine",
    ),
    RegionSpec(
        "thorax",
        ("max_ais_thorax",),
        3,
        (
            ("chest deflection", "chest_deflection_mm"),
            ("chest VC", "chest_vc_m_s"),
            ("chest a3ms", "chest_a3ms_g"),
            ("CTI", "chest_cti"),
        ),
        "lpm_p_ais3_chest",
        "lpm_ais_chest",
        "thorax",
    ),
    RegionSpec(
        "abdomen",
        ("max_ais_abdomen",),
        3,
        (("abdomen VC", "abdomen_vc_m_s"),),
        "lpm_p_ais3_abdomen",
        "lpm_ais_abdomen",
        "abdomen",
    ),
    RegionSpec(
        "extremities",
        ("max_ais_upper_extremity", "max_ais_lower_extremity"),
        3,
        (),
        None,
        "lpm_ais_extremities",
        None,
    ),
)


def analysis_frame(table: pd.DataFrame, outcomes: pd.DataFrame) -> pd.DataFrame:
    """The occupants an occupant model answered, with their outcomes and crash ids."""
    keys = ["year", "psu", "caseno", "vehno", "occno"]
    frame = table.merge(outcomes, on=keys, how="inner", validate="one_to_one")
    frame = frame[frame["lpm_ok"] == 1].reset_index(drop=True)
    frame["crash"] = crash_ids(frame)
    return frame


def outcome(frame: pd.DataFrame, spec: RegionSpec) -> FloatArray:
    """1.0 where the region's AIS reaches the spec's level."""
    ais = frame[list(spec.outcome)].max(axis=1).to_numpy(dtype=np.float64)
    return (ais >= spec.level).astype(np.float64)


@dataclass(frozen=True)
class ScoreSkill:
    """One score against one region's outcome."""

    region: str
    label: str
    n: int
    positives: int
    auc: Interval
    auc_unweighted: float


def _auc_skill(
    frame: pd.DataFrame, y: FloatArray, column: pd.Series, region: str, label: str
) -> ScoreSkill:
    """AUC of a score over the rows where it exists (a measure a mode does not produce is NaN)."""
    score = column.to_numpy(dtype=np.float64)
    has = np.isfinite(score)
    ys, ss = y[has], score[has]
    boot = CrashBootstrap(
        frame.loc[has, "crash"].to_numpy(), frame.loc[has, "ratwgt"].to_numpy(dtype=np.float64)
    )
    return ScoreSkill(
        region=region,
        label=label,
        n=int(has.sum()),
        positives=int(ys.sum()),
        auc=boot.interval(lambda w: weighted_auc(ys, ss, w)),
        auc_unweighted=weighted_auc(ys, ss, None),
    )


@dataclass(frozen=True)
class MapCalibration:
    """The body map's AIS 3+ share and the published curves' mean P, against the field."""

    region: str
    observed: Interval
    map_share: float
    curve_mean: float | None
    #: predicted / observed, with the crash-bootstrap interval: the map's AIS >= 3 share
    #: and the published curves' mean P
    map_ratio: Interval
    curve_ratio: Interval | None


@dataclass(frozen=True)
class RegionSkill:
    """Every score of one region, and the calibration of its map."""

    spec: RegionSpec
    scores: tuple[ScoreSkill, ...]
    calibration: MapCalibration
    by_mode: dict[str, dict[str, float]]


def region_skill(
    frame: pd.DataFrame, spec: RegionSpec, region_risk: pd.Series | None = None
) -> RegionSkill:
    """Every score of `spec` on `frame` (:func:`analysis_frame`), pooled and by mode."""
    y = outcome(frame, spec)
    w = frame["ratwgt"].to_numpy(dtype=np.float64)
    boot = CrashBootstrap(frame["crash"].to_numpy(), w)
    columns = [*spec.scores]
    if spec.curve is not None:
        columns.append(("published curves' P(AIS 3+)", spec.curve))
    columns.append(("body map: region AIS", spec.map_column))
    columns.append(("delta-V alone", "delta_v_kmh"))
    skills = [_auc_skill(frame, y, frame[col], spec.name, label) for label, col in columns]
    if region_risk is not None:
        skills.append(_auc_skill(frame, y, region_risk, spec.name, "region risk"))
    level = frame[spec.map_column].to_numpy(dtype=np.float64)
    high = (level >= 3).astype(np.float64)
    curve = None if spec.curve is None else frame[spec.curve].to_numpy(dtype=np.float64)

    def ratio(pred: FloatArray) -> Interval:
        return boot.interval(
            lambda ww: (
                float(np.average(pred, weights=ww) / np.average(y, weights=ww))
                if np.average(y, weights=ww) > 0
                else float("nan")
            )
        )

    cal = MapCalibration(
        region=spec.name,
        observed=boot.interval(lambda ww: float(np.average(y, weights=ww))),
        map_share=float(np.average(level >= 3, weights=w)),
        curve_mean=(
            None
            if spec.curve is None
            else float(np.average(frame[spec.curve].to_numpy(dtype=np.float64), weights=w))
        ),
        map_ratio=ratio(high),
        curve_ratio=None if curve is None else ratio(curve),
    )
    by_mode: dict[str, dict[str, float]] = {}
    for mode in MODES:
        m = (frame["mode"] == mode).to_numpy()
        ym, wm = y[m], w[m]
        row = {"n": float(m.sum()), "positives": float(ym.sum())}
        for label, col in columns:
            s = frame.loc[m, col].to_numpy(dtype=np.float64)
            has = np.isfinite(s)
            row[label] = (
                weighted_auc(ym[has], s[has], wm[has]) if ym[has].sum() >= 5 else float("nan")
            )
        by_mode[mode] = row
    return RegionSkill(spec, tuple(skills), cal, by_mode)


@dataclass(frozen=True)
class AisSixRow:
    """The occupant models' AIS 6 against real AIS 5+ injuries, one mode."""

    mode: str
    n: int
    #: share given head/neck AIS 6 by the occupant models' own level rule
    model_ais6: float
    #: share given AIS 6 as the service reports it (after the cap, if any)
    reported_ais6: float
    #: share given AIS 5+ as the service reports it
    reported_ais5: float
    #: share with a real AIS 5+ injury in any region (MAIS 5+)
    real_mais5: float
    #: share with a real head or neck AIS 5+ injury
    real_head5: float
    #: of those the models put at AIS 6: share with a real AIS 5+ injury, share who died,
    #: median real ISS
    agree_mais5: float
    died: float
    median_iss: float


def ais_six_check(frame: pd.DataFrame, reported_column: str) -> list[AisSixRow]:
    """Per mode (and all), unweighted shares of occupants: model AIS 6 against real AIS 5+."""
    out = []
    for mode in (*MODES, "all"):
        f = frame if mode == "all" else frame[frame["mode"] == mode]
        six = f["lpm_ais_head_neck"] == 6
        sel = f[six]
        out.append(
            AisSixRow(
                mode=mode,
                n=len(f),
                model_ais6=float(six.mean()),
                reported_ais6=float((f[reported_column] == 6).mean()),
                reported_ais5=float((f[reported_column] >= 5).mean()),
                real_mais5=float((f["mais"] >= 5).mean()),
                real_head5=float(((f["max_ais_head"] >= 5) | (f["max_ais_neck"] >= 5)).mean()),
                agree_mais5=float((sel["mais"] >= 5).mean()) if len(sel) else float("nan"),
                died=float(sel["died"].fillna(0).mean()) if len(sel) else float("nan"),
                median_iss=float(sel["iss"].median()) if len(sel) else float("nan"),
            )
        )
    return out
