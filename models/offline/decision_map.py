"""Where the occupant models would send a driver: their ISS15+ decision over delta-V.

For each impact mode, body and restraint configuration, the driver of the
default vehicle (left-hand drive) is triaged by :func:`models.triage.triage`,
exactly as a notification with a summary pulse (delta-V and PDOF) would be,
over delta-V 5-120 km/h. The map gives, per configuration, the occupant models'
P(ISS >= 15) against delta-V with the mode's threshold, and the lowest delta-V
from which their own decision (``occupant_model``, the physics second opinion)
is positive. The service decides on the field model's P(MAIS 3+) instead
(``docs/field/MODEL_CARD.md`` draws its curves); this map shows why: the
physics alone is milder than the field for belted occupants in frontal
crashes and harsher in near-side ones.

PDOF per mode (deg, clockwise from straight ahead): frontal 0, near side 270
(the driver's side of a left-hand-drive car), far side 90, rear 180.

Run::

    python -m models.offline.decision_map [--out DIR]

Writes ``decision_map.md`` and ``decision_map.png`` to ``DIR`` (default: this
package's directory) and prints the table.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from models.impact_mode import ImpactMode
from models.notification import (
    AirbagState,
    Body,
    CrashNotification,
    Occupant,
    Seat,
    summary_notification,
)
from models.offline.paths import docs_dir
from models.triage import EngineModels, load_engine_models, triage

__all__ = ["DELTA_V_GRID_KMH", "MODE_PDOF_DEG", "DecisionRow", "decision_rows", "first_positive"]

#: PDOF (deg) that puts the driver of a left-hand-drive car in each mode.
MODE_PDOF_DEG: dict[ImpactMode, float] = {
    ImpactMode.FRONTAL: 0.0,
    ImpactMode.NEAR_SIDE: 270.0,
    ImpactMode.FAR_SIDE: 90.0,
    ImpactMode.REAR: 180.0,
}
#: Delta-V grid, km/h (5 km/h steps over the surrogates' design range).
DELTA_V_GRID_KMH: tuple[float, ...] = tuple(float(v) for v in range(5, 125, 5))
#: Restraint configurations (label, belted, airbag deployed): the airbag is the one
#: that acts in the mode's occupant model, the frontal airbag (frontal, rear, far
#: side: there it does not act) or the side and curtain airbags (near side).
RESTRAINTS: tuple[tuple[str, bool, bool], ...] = (
    ("belt + airbag", True, True),
    ("belt", True, False),
    ("airbag", False, True),
    ("none", False, False),
)


@dataclass(frozen=True)
class DecisionRow:
    """The driver's triage in one configuration at one delta-V."""

    mode: ImpactMode
    body: Body
    restraint: str
    delta_v_kmh: float
    probability: float
    threshold: float
    iss15_plus: bool
    #: ISS point estimate (-1 when the answering model gives none: the baseline)
    iss: int
    method: str


def _notification(
    mode: ImpactMode, body: Body, belted: bool, airbag: bool, delta_v_kmh: float
) -> CrashNotification:
    occupant = Occupant(
        seat=Seat.DRIVER,
        body=body,
        belted=belted,
        frontal_airbag=AirbagState.DEPLOYED if airbag else AirbagState.NOT_DEPLOYED,
        side_airbag=(
            AirbagState.DEPLOYED if airbag and mode is ImpactMode.NEAR_SIDE else AirbagState.ABSENT
        ),
    )
    return summary_notification(
        (occupant,), delta_v_kmh, MODE_PDOF_DEG[mode], event_id="decision-map"
    )


def _label(mode: ImpactMode, label: str) -> str:
    """In the near-side model the airbag that acts is the side and curtain airbag."""
    return label.replace("airbag", "side airbags") if mode is ImpactMode.NEAR_SIDE else label


def decision_rows(
    models: EngineModels,
    *,
    modes: Sequence[ImpactMode] = tuple(MODE_PDOF_DEG),
    bodies: Sequence[Body] = tuple(Body),
    restraints: Sequence[tuple[str, bool, bool]] = RESTRAINTS,
    delta_v_kmh: Sequence[float] = DELTA_V_GRID_KMH,
) -> list[DecisionRow]:
    """Triage the driver over the grid (mode x body x restraint x delta-V).

    Returns
    -------
    list of DecisionRow
        In grid order.
    """
    rows = []
    for mode in modes:
        for body in bodies:
            for label, belted, airbag in restraints:
                for dv in delta_v_kmh:
                    result = triage(_notification(mode, body, belted, airbag, dv), models)
                    occ = result.occupants[0]
                    decision = occ.occupant_model
                    if decision is None:
                        raise RuntimeError(f"no occupant model for {mode} at {dv} km/h")
                    rows.append(
                        DecisionRow(
                            mode=mode,
                            body=body,
                            restraint=_label(mode, label),
                            delta_v_kmh=float(dv),
                            probability=decision.probability,
                            threshold=decision.threshold,
                            iss15_plus=decision.iss15_plus,
                            iss=-1 if occ.iss is None else occ.iss.estimate,
                            method=occ.method,
                        )
                    )
    return rows


def first_positive(rows: Sequence[DecisionRow]) -> float | None:
    """Lowest delta-V (km/h) of a positive decision among rows of one configuration."""
    positive = [r.delta_v_kmh for r in rows if r.iss15_plus]
    return min(positive) if positive else None


def _groups(rows: Sequence[DecisionRow]) -> dict[tuple[ImpactMode, Body, str], list[DecisionRow]]:
    out: dict[tuple[ImpactMode, Body, str], list[DecisionRow]] = {}
    for r in rows:
        out.setdefault((r.mode, r.body, r.restraint), []).append(r)
    return out


def _table(rows: Sequence[DecisionRow]) -> str:
    lines = [
        "| mode | body | restraint | threshold | P(ISS>=15) at 5 km/h | at 30 km/h |"
        " at 55 km/h | positive from (km/h) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for (mode, body, restraint), g in _groups(rows).items():
        p = {r.delta_v_kmh: r.probability for r in g}
        first = first_positive(g)
        lines.append(
            f"| {mode.value} | {body.value} | {restraint} | {g[0].threshold:.2f} | "
            f"{p.get(5.0, float('nan')):.3f} | {p.get(30.0, float('nan')):.3f} | "
            f"{p.get(55.0, float('nan')):.3f} | {'never' if first is None else f'{first:.0f}'} |"
        )
    return "\n".join(lines)


def _plot(rows: Sequence[DecisionRow], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    modes = list(dict.fromkeys(r.mode for r in rows))
    fig, axes = plt.subplots(1, len(modes), figsize=(4.2 * len(modes), 3.8), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, mode in zip(axes, modes, strict=True):
        thr = None
        for (m, body, restraint), g in _groups(rows).items():
            if m is not mode:
                continue
            thr = g[0].threshold
            style = "-" if body is Body.MALE_50TH else "--"
            ax.plot(
                [r.delta_v_kmh for r in g],
                [r.probability for r in g],
                style,
                label=f"{body.value}, {restraint}",
            )
        if thr is not None:
            ax.axhline(thr, color="k", lw=0.8)
            ax.text(6, thr * 1.15, f"threshold {thr:.2f}", fontsize=8)
        ax.set_yscale("log")
        ax.set_title(mode.value)
        ax.set_xlabel("delta-V (km/h)")
    axes[0].set_ylabel("P(ISS >= 15), driver")
    axes[-1].legend(fontsize=6, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    """Command line entry point."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=docs_dir("decision_map"))
    args = ap.parse_args(list(argv) if argv is not None else None)
    args.out.mkdir(parents=True, exist_ok=True)
    rows = decision_rows(load_engine_models())
    table = _table(rows)
    _plot(rows, args.out / "decision_map.png")
    (args.out / "decision_map.md").write_text(
        "# Where the driver is sent to a trauma center\n\n"
        "Generated by `python -m models.offline.decision_map` (see its docstring): the service's "
        "triage of the driver of the default vehicle for a summary pulse, per impact mode, "
        "body and restraint, delta-V 5-120 km/h; plot `decision_map.png`.\n\n" + table + "\n"
    )
    sys.stdout.write(table + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
