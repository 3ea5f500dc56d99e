"""Score the service's decision against real outcomes (``aacn-triage evaluate``).

:func:`evaluate_notifications` sends labelled notifications through the engine
(the same :func:`models.triage.triage` the service runs, over a process pool
with a progress bar) and :func:`evaluation_markdown` reports, overall and per
crash mode: the AUC of the decided probability with its bootstrap interval,
its calibration (intercept, slope, Brier, and a reliability plot), and at each
named operating point the sensitivity (1 - under-triage), the flagged share and
the over-triage (1 - PPV). The fit's model card uses the same report on
cross-validated predictions.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt
from matplotlib.figure import Figure
from tqdm import tqdm

from models.arrays import FloatArray
from models.constants import Z_95
from models.field.features import FieldMode
from models.field.model import OperatingPoint
from models.notification import CrashNotification
from models.offline.field.metrics import (
    auc,
    bootstrap_ci,
    calibration,
    stratified_bootstrap_indices,
    triage_rates,
)
from models.triage import EngineModels, load_engine_models, triage

__all__ = [
    "ScoredCase",
    "evaluate_notifications",
    "evaluation_markdown",
    "reliability_plot",
    "score_chunk",
    "write_evaluation",
]


#: Resamples behind each confidence interval of the report.
N_BOOTSTRAP = 1000
#: Seed of the bootstrap.
SEED = 20261204


@dataclass(frozen=True)
class ScoredCase:
    """One labelled notification and the service's answer to it.

    Attributes
    ----------
    event_id : str
    outcome : bool
    probability : float
        The case-level decided probability.
    flagged : bool
        The case-level decision at the models' operating point.
    mode : str
        The field crash mode of the worst occupant.
    by_operating_point : Mapping[str, bool]
        The decision at every named operating point of the field model.
    weight : float
    """

    event_id: str
    outcome: bool
    probability: float
    flagged: bool
    mode: str
    by_operating_point: Mapping[str, bool]
    weight: float = 1.0


_WORKER_MODELS: EngineModels | None = None
#: The operating point `_WORKER_MODELS` were loaded for.
_WORKER_OPERATING_POINT: str | None = None


def _init(operating_point: str | None) -> None:
    global _WORKER_MODELS, _WORKER_OPERATING_POINT
    _WORKER_MODELS = load_engine_models(operating_point=operating_point)
    _WORKER_OPERATING_POINT = operating_point


def score_chunk(
    items: Sequence[tuple[CrashNotification, bool, float]], *, operating_point: str | None = None
) -> list[ScoredCase]:
    """Score labelled notifications in this process, as :func:`evaluate_notifications`
    does in each of its workers (the models are loaded once per process and operating
    point); the task of ``aacn-triage evaluate --scheduler`` on a Dask worker."""
    if _WORKER_MODELS is None or _WORKER_OPERATING_POINT != operating_point:
        _init(operating_point)
    return [_score(item) for item in items]


def _threshold(op: OperatingPoint | float, mode: FieldMode) -> float:
    """An operating point's threshold for `mode` (one per mode for 2.0.0, one for all on)."""
    return op if isinstance(op, float) else op.thresholds[mode]


def _score(item: tuple[CrashNotification, bool, float]) -> ScoredCase:
    notification, outcome, weight = item
    assert _WORKER_MODELS is not None
    assert _WORKER_MODELS.field is not None
    result = triage(notification, _WORKER_MODELS)
    worst = max(result.occupants, key=lambda o: (o.triage.iss15_plus, o.triage.probability))
    field = _WORKER_MODELS.field
    return ScoredCase(
        event_id=notification.event_id,
        outcome=outcome,
        probability=result.triage.probability,
        flagged=result.triage.iss15_plus,
        mode=worst.field_mode.value,
        by_operating_point={
            name: any(
                o.triage.probability >= _threshold(op, o.field_mode) for o in result.occupants
            )
            for name, op in field.operating_points.items()
        },
        weight=weight,
    )


def evaluate_notifications(
    labelled: Sequence[tuple[CrashNotification, bool, float]],
    *,
    operating_point: str | None = None,
    workers: int | None = None,
    progress: bool = True,
) -> list[ScoredCase]:
    """The service's answers to labelled notifications.

    Parameters
    ----------
    labelled : sequence of (CrashNotification, bool, float)
        Notification, outcome, case weight.
    operating_point : str, optional
        The operating point the decision (``flagged``) uses.
    workers : int, optional
        Processes (default the CPU count).
    progress : bool
        Progress bar on stderr.

    Returns
    -------
    list of ScoredCase
        In input order.
    """
    n_workers = workers or os.cpu_count() or 1
    with ProcessPoolExecutor(n_workers, initializer=_init, initargs=(operating_point,)) as pool:
        return list(
            tqdm(
                pool.map(_score, labelled, chunksize=32),
                total=len(labelled),
                desc="triage",
                disable=not progress,
            )
        )


def _pct(x: float) -> str:
    return "n/a" if not np.isfinite(x) else f"{100.0 * x:.1f} %"


def _ci(ci: tuple[float, float], pct: bool = False) -> str:
    if not all(np.isfinite(ci)):
        return "n/a"
    if pct:
        return f"[{100.0 * ci[0]:.1f}, {100.0 * ci[1]:.1f}]"
    return f"[{ci[0]:.3f}, {ci[1]:.3f}]"


def evaluation_markdown(
    title: str,
    y: npt.ArrayLike,
    p: npt.ArrayLike,
    modes: Sequence[str],
    flags: Mapping[str, npt.ArrayLike],
    *,
    w: npt.ArrayLike | None = None,
    plot_name: str | None = None,
    n_boot: int = N_BOOTSTRAP,
    seed: int = SEED,
    heading: str = "##",
) -> str:
    """A Markdown report of probabilities and decisions against outcomes.

    Parameters
    ----------
    title : str
    y : array_like, shape (n,)
        0/1 outcome.
    p : array_like, shape (n,)
        Decided probability.
    modes : sequence of str
        Crash mode of each row.
    flags : Mapping[str, array_like]
        Decision (0/1, shape (n,)) at each named operating point.
    w : array_like, shape (n,), optional
        Case weights (survey weights); the figures are then weighted.
    plot_name : str, optional
        File name of the reliability plot to link.
    n_boot, seed : int
        Bootstrap of the intervals (rows resampled within outcome).
    heading : str
        Markdown heading level of the title.

    Returns
    -------
    str
    """
    yy = np.asarray(y, dtype=float)
    pp = np.asarray(p, dtype=float)
    ww = None if w is None else np.asarray(w, dtype=float)
    mode_arr = np.asarray(list(modes))
    idx = stratified_bootstrap_indices(yy, n_boot, seed)
    weighted = " (survey-weighted)" if ww is not None else ""
    lines = [f"{heading} {title}", ""]
    groups = [("all", np.arange(yy.size))] + [
        (m.value, np.flatnonzero(mode_arr == m.value))
        for m in FieldMode
        if np.any(mode_arr == m.value)
    ]
    lines += [
        f"Discrimination and calibration of the decided probability{weighted}; 95 % "
        f"intervals from {n_boot} bootstrap resamples of the rows (within outcome).",
        "",
        "| crash mode | occupants | positives | AUC [95 % CI] | calibration intercept | "
        "slope | Brier |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, sel in groups:
        ys, ps = yy[sel], pp[sel]
        ws = None if ww is None else ww[sel]
        local = _restrict(idx, sel)
        a = auc(ys, ps, ws)
        ci = bootstrap_ci(_auc_statistic(ys, ps, ws), local)
        if 0 < ys.sum() < ys.size and ys.sum() >= 5:
            c = calibration(ys, ps, ws)
            cal = f"{c.intercept:+.2f} | {c.slope:.2f} | {c.brier:.4f}"
        else:
            cal = "n/a | n/a | n/a"
        lines.append(
            f"| {name} | {sel.size} | {int(ys.sum())} | "
            f"{'n/a' if not np.isfinite(a) else f'{a:.3f}'} {_ci(ci)} | {cal} |"
        )
    lines += [""]
    if plot_name:
        lines += [f"![reliability]({plot_name})", ""]
    for op, f in flags.items():
        fl = np.asarray(f, dtype=bool)
        lines += [
            f"Operating point `{op}`{weighted}: sensitivity = 1 - under-triage; "
            "over-triage = 1 - PPV.",
            "",
            "| crash mode | sensitivity [95 % CI] | flagged [95 % CI] | PPV | over-triage |",
            "|---|---|---|---|---|",
        ]
        for name, sel in groups:
            ys, fs = yy[sel], fl[sel]
            ws = None if ww is None else ww[sel]
            local = _restrict(idx, sel)
            r = triage_rates(ys, fs, ws)
            ci_s = bootstrap_ci(_rate_statistic(ys, fs, ws, "sensitivity"), local)
            ci_f = bootstrap_ci(_rate_statistic(ys, fs, ws, "flagged"), local)
            lines.append(
                f"| {name} | {_pct(r.sensitivity)} {_ci(ci_s, True)} | "
                f"{_pct(r.flagged)} {_ci(ci_f, True)} | {_pct(r.ppv)} | {_pct(r.over_triage)} |"
            )
        lines += [""]
    return "\n".join(lines)


def _auc_statistic(
    y: FloatArray, p: FloatArray, w: FloatArray | None
) -> Callable[[npt.NDArray[np.int64]], float]:
    def statistic(ix: npt.NDArray[np.int64]) -> float:
        return auc(y[ix], p[ix], None if w is None else w[ix])

    return statistic


def _rate_statistic(
    y: FloatArray, flagged: npt.NDArray[np.bool_], w: FloatArray | None, name: str
) -> Callable[[npt.NDArray[np.int64]], float]:
    def statistic(ix: npt.NDArray[np.int64]) -> float:
        rates = triage_rates(y[ix], flagged[ix], None if w is None else w[ix])
        return float(getattr(rates, name))

    return statistic


def _restrict(
    indices: Sequence[npt.NDArray[np.int64]], sel: npt.NDArray[np.int64]
) -> list[npt.NDArray[np.int64]]:
    """Bootstrap resamples restricted to rows `sel`, as positions within `sel`."""
    if sel.size == 0:
        return []
    pos = np.full(int(max(int(ix.max()) for ix in indices)) + 1, -1, dtype=np.int64)
    pos[sel] = np.arange(sel.size)
    out = []
    for ix in indices:
        local = pos[ix]
        out.append(local[local >= 0])
    return out


def reliability_plot(
    path: Path,
    curves: Mapping[str, tuple[npt.ArrayLike, npt.ArrayLike]],
    *,
    title: str,
    bins: int = 10,
) -> Path:
    """Observed outcome rate against mean predicted probability, by decile of prediction.

    Parameters
    ----------
    path : Path
        PNG to write.
    curves : Mapping[str, (y, p)]
        One curve per model.
    title : str
    bins : int
        Quantile bins of the prediction.
    """
    fig = Figure(figsize=(6.0, 5.0))
    ax = fig.subplots()
    top = 0.0
    for name, (y, p) in curves.items():
        yy, pp = np.asarray(y, dtype=float), np.asarray(p, dtype=float)
        edges = np.unique(np.quantile(pp, np.linspace(0.0, 1.0, bins + 1)))
        which = np.clip(np.searchsorted(edges, pp, side="right") - 1, 0, edges.size - 2)
        xs, obs, lo, hi = [], [], [], []
        for b in range(edges.size - 1):
            sel = which == b
            if not sel.any():
                continue
            n = int(sel.sum())
            k = float(yy[sel].sum())
            rate = k / n
            # Wilson 95 % interval of the observed rate
            z = Z_95
            centre = (rate + z * z / (2 * n)) / (1 + z * z / n)
            half = z * np.sqrt(rate * (1 - rate) / n + z * z / (4 * n * n)) / (1 + z * z / n)
            xs.append(float(pp[sel].mean()))
            obs.append(rate)
            lo.append(max(0.0, rate - (centre - half)))
            hi.append(max(0.0, (centre + half) - rate))
        ax.errorbar(xs, obs, yerr=[lo, hi], marker="o", capsize=3, label=name)
        top = max(top, max(xs), max(np.array(obs) + np.array(hi)))
    top = min(1.0, top * 1.05)
    ax.plot([0, top], [0, top], color="grey", linestyle="--", linewidth=1, label="ideal")
    ax.set_xlim(0, top)
    ax.set_ylim(0, top)
    ax.set_xlabel("mean predicted probability (decile of prediction)")
    ax.set_ylabel("observed outcome rate (95 % Wilson interval)")
    ax.set_title(title)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    return path


def write_evaluation(
    cases: Sequence[ScoredCase], out_dir: Path, *, title: str, weighted: bool = False
) -> Path:
    """Write ``evaluation.md`` and ``evaluation_reliability.png`` for scored cases."""
    out_dir.mkdir(parents=True, exist_ok=True)
    y = np.array([c.outcome for c in cases], dtype=float)
    p = np.array([c.probability for c in cases])
    w = np.array([c.weight for c in cases]) if weighted else None
    names = sorted({k for c in cases for k in c.by_operating_point})
    flags = {"decided": np.array([c.flagged for c in cases])} | {
        n: np.array([c.by_operating_point[n] for c in cases]) for n in names
    }
    plot = reliability_plot(
        out_dir / "evaluation_reliability.png", {"decided probability": (y, p)}, title=title
    )
    text = evaluation_markdown(
        title, y, p, [c.mode for c in cases], flags, w=w, plot_name=plot.name, heading="#"
    )
    path = out_dir / "evaluation.md"
    path.write_text(text, encoding="utf-8")
    return path
