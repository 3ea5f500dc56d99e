"""Plot of one LPM simulation: pulse, occupant snapshots, measures vs limits."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import numpy.typing as npt

from models.impact_mode import ImpactMode
from models.injury.criteria import (
    FMVSS208_CHEST_A3MS_LIMIT_G,
    FMVSS208_CHEST_DEFLECTION_LIMIT_MM,
    FMVSS208_HIC15_LIMIT,
    NIJ_INTERCEPTS,
)
from models.injury.filters import cfc_filter
from models.lpm.simulate import LpmResult
from models.notification import Body

__all__ = ["plot_simulation"]

_SNAP_MS = (0, 40, 60, 80, 100, 120, 150)


def _nij_terms(
    h: Mapping[str, npt.NDArray[np.float64]], t_ms: npt.NDArray[np.float64], body: Body
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """The two normalised terms of Nij over time, as the measure computes them.

    The neck channels filtered at CFC 600, the moment taken at the occipital
    condyle, each term divided by the intercept of its own sign (tension or
    compression, flexion or extension), as in :func:`models.injury.criteria.nij`
    (whose peak over time of their sum is the reported Nij).
    """
    ic = NIJ_INTERCEPTS[body]
    fs = 1000.0 / float(t_ms[1] - t_ms[0])
    fx, fz, my = (cfc_filter(h[k], fs, 600) for k in ("neck_fx_n", "neck_fz_n", "neck_my_nm"))
    moc = my - ic.condyle_offset_m * fx
    n_force = np.where(fz >= 0.0, fz / ic.tension_n, -fz / ic.compression_n)
    n_moment = np.where(moc >= 0.0, moc / ic.flexion_nm, -moc / ic.extension_nm)
    return n_force, n_moment


def plot_simulation(
    result: LpmResult, path: str | Path, *, body: Body = Body.MALE_50TH, title: str | None = None
) -> Path:
    """Draw the pulse, segment snapshots and each measure's history against its limit.

    Parameters
    ----------
    result : LpmResult
    path : str or Path
        Output image (PNG, SVG or PDF by extension).
    body : Body
        Selects the dummy limits (chest deflection, neck intercepts).
    title : str, optional

    Returns
    -------
    Path
        The written file.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    h = result.histories
    t_ms = result.time_s * 1000.0
    fig, axes = plt.subplots(2, 3, figsize=(15, 8))
    ax = axes[0, 0]
    ax.plot(t_ms, h["vehicle_accel_g"], color="k")
    if result.mode in (ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE):
        ax2 = ax.twinx()
        ax2.plot(t_ms, 1000.0 * h["door_intrusion_m"], color="tab:brown")
        ax2.set_ylabel("door intrusion (mm)", color="tab:brown")
    ax.set_title(f"pulse on the model axis ({result.mode.value}, {result.angle_deg:.0f} deg)")
    ax.set_xlabel("t (ms)")
    ax.set_ylabel("vehicle acceleration (g)")

    ax = axes[0, 1]
    chain = ("hip", "lumbar", "t1", "oc", "head")
    cmap = plt.get_cmap("viridis")
    for j, ms in enumerate(_SNAP_MS):
        i = int(np.searchsorted(t_ms, ms))
        if i >= t_ms.size:
            break
        xs = [h[f"{c}_x_m"][i] for c in chain]
        zs = [h[f"{c}_z_m"][i] for c in chain]
        ax.plot(xs, zs, "o-", color=cmap(j / len(_SNAP_MS)), label=f"{ms} ms")
    ax.set_aspect("equal")
    ax.set_title("segments (vehicle frame)")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.legend(fontsize=7)

    ax = axes[0, 2]
    ax.plot(t_ms, h["head_accel_g"], label="head resultant")
    hic = result.measures.hic15
    ax.set_title(
        f"head: HIC15 = {hic:.0f} (limit {FMVSS208_HIC15_LIMIT:.0f})" if hic is not None else "head"
    )
    ax.set_xlabel("t (ms)")
    ax.set_ylabel("acceleration (g)")

    ax = axes[1, 0]
    n_force, n_moment = _nij_terms(h, t_ms, body)
    ax.plot(t_ms, n_force, label="Fz / Fzc (tension or compression)")
    ax.plot(t_ms, n_moment, label="Moc / Myc (flexion or extension)")
    ax.plot(t_ms, n_force + n_moment, "k", lw=0.8, label="Nij(t)")
    ax.axhline(1.0, color="r", ls="--")
    nij = result.measures.nij
    ax.set_title(f"upper neck: Nij = {nij:.2f} (limit 1.0)" if nij is not None else "neck")
    ax.set_xlabel("t (ms)")
    ax.legend(fontsize=7)

    ax = axes[1, 1]
    ax.plot(t_ms, h["chest_deflection_mm"], label="chest / rib deflection")
    if result.mode in (ImpactMode.FRONTAL, ImpactMode.REAR):
        ax.axhline(
            FMVSS208_CHEST_DEFLECTION_LIMIT_MM[body], color="r", ls="--", label="FMVSS 208 limit"
        )
    ax.set_xlabel("t (ms)")
    ax.set_ylabel("deflection (mm)")
    ax.legend(fontsize=7)
    ax.set_title("chest")

    ax = axes[1, 2]
    ax.plot(t_ms, h["chest_accel_g"], label="chest (spine) resultant")
    ax.axhline(FMVSS208_CHEST_A3MS_LIMIT_G, color="r", ls="--", label="60 g (3 ms) limit")
    for name, v in h.items():
        if name.startswith("belt_") and name.endswith("_n"):
            ax.plot(t_ms, v / 1000.0, ls=":", label=f"{name[:-2]} (kN)")
    ax.set_xlabel("t (ms)")
    ax.legend(fontsize=7)
    ax.set_title("chest acceleration, belt forces")

    m = result.measures
    a = result.assessment
    text = ", ".join(f"{k}={v:.2f}" for k, v in vars(m).items() if v is not None)
    if a is not None:
        text += f" | ISS {a.iss}, P(ISS>=15) {a.p_iss15:.2f}"
    fig.suptitle((title + "\n" if title else "") + text, fontsize=9)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
