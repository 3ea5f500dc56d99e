"""Issue 50, item 5: the NASS-CDS 2011-2014 crashes as local outcomes, with a known shift.

Writes ``docs/outcomes/weighted.png`` (with the survey weights: as they are, and with the
odds halved) and ``docs/outcomes/recalibrated.png`` (unit weights, as a registry's: the
served model, and the recalibration fitted on one half of the crashes applied to the
other), and prints the figures quoted in ``docs/outcomes.md``. Run from the repository
root: ``PYTHONPATH=. python docs/outcomes/shift_demo.py`` (about 10 s).

Everything is the project's own machinery: the served model's decided probabilities
(``models.offline.field.local_shift``), the quality page's calibration by decile
(``service.outcomes.quality.figures_of``), the drift alarm
(``service.outcomes.drift``), the recalibration (``models.field.recalibration``).
"""

from __future__ import annotations

import sys
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from models.field.recalibration import (
    apply_recalibration,
    fit_recalibration,
    precision_plan,
    weighted_ratio,
)
from models.field.risk_model import load_default
from models.offline.field.local_shift import (
    LocalOutcomes,
    crash_halves,
    decisions,
    halve_odds,
    nass_local_outcomes,
)
from models.tiers import Tier
from service.outcomes.drift import DriftSettings, DriftStatus, drift_status
from service.outcomes.quality import CalibrationOut, LinkedOccupant, figures_of

OUT = Path(__file__).resolve().parent
ALARM = DriftSettings(window=100_000, false_alarm_rate=0.01)
SEED = 0
SPLITS = 20
POWER_RUNS = 200


def _say(text: str) -> None:
    sys.stdout.write(text + "\n")


def calibration(data: LocalOutcomes) -> CalibrationOut:
    flagged, high = decisions(data, load_default())
    at = datetime(2026, 11, 1, tzinfo=UTC)
    occupants = [
        LinkedOccupant(
            case_id=str(c),
            received_at=at,
            month="2026-11",
            operating_point="sens85",
            tier=Tier.HIGH if h else Tier.MODERATE if f else Tier.NONE,
            flagged=bool(f),
            probability=float(p),
            crash_mode="frontal",
            age_group="adult_16_64",
            seat_row=1,
            serious=bool(y),
            weight=float(w),
        )
        for c, p, y, w, f, h in zip(
            data.crash, data.probability, data.serious, data.weight, flagged, high, strict=True
        )
    ]
    return figures_of(occupants).calibration


def alarm(data: LocalOutcomes) -> DriftStatus:
    return drift_status(
        [bool(y) for y in data.serious], list(data.probability), list(data.weight), ALARM
    )


def plot(path: Path, curves: dict[str, CalibrationOut], title: str) -> Path:
    """Reliability by decile on log-log axes (most probabilities are small); a decile with
    no ISS 15+ observed is drawn at the axis floor as an open marker."""
    floor = 1e-4
    fig = Figure(figsize=(6.4, 5.2))
    ax = fig.subplots()
    for name, cal in curves.items():
        xs = [d.mean_predicted for d in cal.deciles]
        rates = [d.observed.rate or 0.0 for d in cal.deciles]
        ys = [max(r, floor) for r in rates]
        low = [max((d.observed.ci95 or (0.0, 0.0))[0], floor) for d in cal.deciles]
        high = [max((d.observed.ci95 or (0.0, 0.0))[1], floor) for d in cal.deciles]
        ratio = cal.observed_over_predicted or float("nan")
        ci = cal.observed_over_predicted_ci95 or (float("nan"), float("nan"))
        line = ax.errorbar(
            xs,
            ys,
            yerr=[
                [y - lo for y, lo in zip(ys, low, strict=True)],
                [hi - y for y, hi in zip(ys, high, strict=True)],
            ],
            marker="o",
            capsize=3,
            label=f"{name}: O/P {ratio:.2f} ({ci[0]:.2f}-{ci[1]:.2f})",
        )
        zero = [(x, floor) for x, r in zip(xs, rates, strict=True) if r == 0.0]
        if zero:
            ax.plot(*zip(*zero, strict=True), "o", mfc="white", color=line[0].get_color())
    ax.plot([floor, 1.0], [floor, 1.0], color="grey", linestyle="--", label="ideal")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(floor, 1.0)
    ax.set_ylim(floor * 0.8, 1.0)
    ax.set_xlabel("mean decided P(ISS 15+), decile")
    ax.set_ylabel("observed ISS 15+ share (95 % Wilson interval)")
    ax.set_title(title, fontsize=10)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return path


def weighted_part(local: LocalOutcomes) -> None:
    shifted = halve_odds(local, SEED)
    before, after = alarm(local), alarm(shifted)
    _say(f"weighted, as they are: {before.state}, z {before.z:.2f}; {before.message}")
    _say(f"weighted, odds halved (seed {SEED}): {after.state}, z {after.z:.2f}")
    w, p = local.weight, local.probability
    eff = float(np.sum(w * p) ** 2 / np.sum(w * w * p * (1 - p)))
    _say(f"effective expected ISS 15+ (drift test): {eff:.1f}; expected z {-0.5 * eff**0.5:.2f}")
    fired = sum(alarm(halve_odds(local, s)).state == "alarm" for s in range(POWER_RUNS))
    _say(f"odds halved: the alarm fired in {fired} of {POWER_RUNS} seeded resamples")
    plan = precision_plan(p, local.serious, w)
    a, _ = crash_halves(shifted, SEED)
    half = shifted.subset(a)
    plan_half = precision_plan(half.probability, half.serious, half.weight)
    _say(f"recalibration, all crashes: {plan.reason}")
    _say(f"recalibration, half of the shifted crashes: {plan_half.reason}")
    curves = {"as they are": calibration(local), "odds halved": calibration(shifted)}
    for name, cal in curves.items():
        lo, hi = cal.observed_over_predicted_ci95 or (float("nan"), float("nan"))
        ratio = cal.observed_over_predicted or float("nan")
        _say(f"weighted O/P, {name}: {ratio:.2f} ({lo:.2f}-{hi:.2f})")
    plot(
        OUT / "weighted.png",
        curves,
        f"NASS-CDS 2011-2014, survey weights: served model {load_default().version}",
    )


def unit_part(local: LocalOutcomes) -> None:
    data = local.unweighted()
    status = alarm(data)
    _say(f"unit weights: {status.state}, z {status.z:.2f}")
    inside, ratios, silent, fired = 0, [], 0, 0
    for seed in range(SPLITS):  # each split's recalibration fitted once, judged both ways
        a, b = crash_halves(data, seed)
        train, test = data.subset(a), data.subset(b)
        plan = precision_plan(train.probability, train.serious, train.weight)
        fit = fit_recalibration(
            train.probability, train.serious, train.weight, list(train.crash), plan.method
        )
        served = LocalOutcomes(
            apply_recalibration(test.probability, fit.intercept, fit.slope),
            test.serious,
            test.weight,
            test.crash,
            test.age_years,
        )
        r = weighted_ratio(served.probability, test.serious, test.weight)
        ratios.append(r)
        inside += 0.8 <= r <= 1.25
        silent += alarm(served).state == "ok"
        fired += alarm(halve_odds(served, seed)).state == "alarm"
    _say(
        f"recalibrated on half, P/O on the other: {inside} of {SPLITS} splits in 0.8-1.25 "
        f"(median {np.median(ratios):.2f}, range {min(ratios):.2f}-{max(ratios):.2f})"
    )
    _say(
        f"recalibrated on half, the other half as it is: silent in {silent} of {SPLITS}; "
        f"odds halved: fired in {fired} of {SPLITS}"
    )
    # cross-fitted: each half predicted by the recalibration fitted on the other
    a, b = crash_halves(data, SEED)
    held = data.probability.copy()
    for train_mask, test_mask in ((a, b), (b, a)):
        train = data.subset(train_mask)
        plan = precision_plan(train.probability, train.serious, train.weight)
        _say(f"split {SEED}: {plan.reason}")
        fit = fit_recalibration(
            train.probability, train.serious, train.weight, list(train.crash), plan.method
        )
        _say(
            f"  fit: a {fit.intercept:.3f} (SE {fit.intercept_se:.3f}), "
            f"b {fit.slope:.3f} (SE {fit.slope_se:.3f})"
        )
        held[test_mask] = apply_recalibration(data.probability[test_mask], fit.intercept, fit.slope)
    after = LocalOutcomes(held, data.serious, data.weight, data.crash, data.age_years)
    plot(
        OUT / "recalibrated.png",
        {"served": calibration(data), "recalibrated on the other half": calibration(after)},
        "NASS-CDS 2011-2014, unit weights (as a registry's)",
    )
    _say(f"cross-fitted P/O {weighted_ratio(held, data.serious, data.weight):.3f}")


def main() -> None:
    local = nass_local_outcomes()
    _say(
        f"{len(local)} occupants, {np.unique(local.crash).size} crashes, "
        f"{int(local.serious.sum())} ISS 15+"
    )
    weighted_part(local)
    unit_part(local)


if __name__ == "__main__":
    main()
