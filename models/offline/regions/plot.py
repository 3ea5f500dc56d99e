"""The figure of the region report (matplotlib, Agg)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pandas as pd
from scipy.special import expit

from models.arrays import FloatArray
from models.offline.regions.calibrate import CalibratedCurve
from models.offline.regions.skill import MODES, REGION_SPECS, AisSixRow, RegionSkill, outcome

__all__ = ["plot_report"]


def _binned(
    x: FloatArray, y: FloatArray, w: FloatArray, edges: FloatArray
) -> tuple[FloatArray, FloatArray, list[npt.NDArray[np.bool_]]]:
    idx = np.digitize(x, edges) - 1
    centres, rates, means = [], [], []
    for k in range(len(edges) - 1):
        m = idx == k
        if m.sum() >= 30 and w[m].sum() > 0:
            centres.append(np.sqrt(edges[k] * edges[k + 1]))
            rates.append(np.average(y[m], weights=w[m]))
            means.append(m)
    return np.array(centres), np.array(rates), means


def plot_report(
    frame: pd.DataFrame,
    skills: Sequence[RegionSkill],
    ais_six: Sequence[AisSixRow],
    curves: Sequence[CalibratedCurve],
    path: Path,
) -> None:
    """Four panels: AUC by region and score; AIS 6 by mode; head and thorax curves."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ((ax1, ax2), (ax3, ax4)) = plt.subplots(2, 2, figsize=(15, 11))
    ys, labels = [], []
    y0 = 0.0
    for rs in skills:
        for s in rs.scores:
            colour = "C3" if s.label == "delta-V alone" else ("C2" if "map" in s.label else "C0")
            ax1.errorbar(
                s.auc.value,
                y0,
                xerr=[[s.auc.value - s.auc.low], [s.auc.high - s.auc.value]],
                fmt="o",
                color=colour,
                capsize=2,
            )
            ys.append(y0)
            labels.append(f"{rs.spec.name}: {s.label}")
            y0 -= 1.0
        y0 -= 0.6
    ax1.set_yticks(ys, labels, fontsize=7)
    ax1.axvline(0.5, color="k", lw=0.6)
    ax1.set_xlabel("AUC, survey-weighted (95 % crash bootstrap)")
    ax1.set_title("occupant models against real region outcomes (red: delta-V; green: map)")

    rows = [r for r in ais_six if r.mode != "all"]
    x = np.arange(len(rows))
    ax2.bar(x - 0.3, [100 * r.model_ais6 for r in rows], 0.2, label="models' AIS 6 (assessment)")
    ax2.bar(x - 0.1, [100 * r.reported_ais6 for r in rows], 0.2, label="reported AIS 6")
    ax2.bar(x + 0.1, [100 * r.reported_ais5 for r in rows], 0.2, label="reported AIS 5+")
    ax2.bar(x + 0.3, [100 * r.real_mais5 for r in rows], 0.2, label="real MAIS 5+")
    ax2.set_xticks(x, [r.mode for r in rows])
    ax2.set_ylabel("% of occupants")
    ax2.set_title("head/neck AIS 6 from the occupant models against real AIS 5+")
    ax2.legend(fontsize=8)

    w = frame["ratwgt"].to_numpy(float)
    for ax, spec_name, measure, published, edges in (
        (ax3, "head", "hic15", "lpm_p_ais3_head_neck", np.geomspace(1, 50000, 16)),
        (ax4, "thorax", "chest_a3ms_g", "lpm_p_ais3_chest", np.geomspace(2, 600, 14)),
    ):
        spec = next(s for s in REGION_SPECS if s.name == spec_name)
        y = outcome(frame, spec)
        xm = frame[measure].fillna(0.0).to_numpy(float)
        centres, rates, masks = _binned(xm, y, w, edges)
        ax.plot(centres, rates, "ko", label="field AIS 3+ rate (weighted)")
        pub = frame[published].to_numpy(float)
        ax.plot(
            centres,
            [np.average(pub[m], weights=w[m]) for m in masks],
            "s--",
            color="C1",
            label="published curves (mean in bin)",
        )
        curve = next((c for c in curves if c.region == spec_name and c.measure == measure), None)
        if curve is not None:
            grid = np.geomspace(edges[0], edges[-1], 200)
            for i, mode in enumerate(m for m in MODES if m in curve.intercepts):
                ax.plot(
                    grid,
                    expit(curve.intercepts[mode] + curve.slope * np.log1p(grid)),
                    color=f"C{i + 4}",
                    lw=1.0,
                    label=f"field-fitted, {mode}",
                )
        ax.set_xscale("log")
        ax.set_xlabel(measure)
        ax.set_ylabel(f"P({spec_name} AIS 3+)")
        ax.set_title(f"{spec_name}: {measure} against the field")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
