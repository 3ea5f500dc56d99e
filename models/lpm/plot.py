"""Plot of one LPM simulation: pulse, occupant snapshots, measures vs limits."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from models.impact_mode import ImpactMode
from models.injury.criteria import (
    FMVSS208_CHEST_A3MS_LIMIT_G,
    FMVSS208_CHEST_DEFLECTION_LIMIT_MM,
    FMVSS208_HIC15_LIMIT,
    NIJ_INTERCEPTS,
)
from models.lpm.simulate import LpmResult
from models.notification import Body

__all__ = ["plot_simulation"]

_SNAP_MS = (0, 40, 60, 80, 100, 120, 150)


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
    nij_c = NIJ_INTERCEPTS[body]
    ax.plot(t_ms, h["neck_fz_n"] / nij_c.tension_n, label="Fz / Fzc (tension)")
    ax.plot(t_ms, h["neck_my_nm"] / nij_c.flexion_nm, label="My / Myc (flexion)")
    ax.axhline(1.0, color="r", ls="--")
    ax.axhline(-1.0, color="r", ls="--")
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
