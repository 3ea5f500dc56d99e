"""The drift alarm: observed against predicted ISS 15+ over the last linked occupants.

A score test of calibration-in-the-large on a window of the last ``N`` linked
occupants (by case received, newest last): with ``y`` the outcome (ISS 15+), ``p``
the decided probability and ``w`` the weight,

    O = sum w y,  E = sum w p,  V = sum w^2 p (1 - p),  z = (O - E) / sqrt(V).

Under a calibrated model (each ``y`` Bernoulli with its ``p``, outcomes independent)
``z`` is approximately standard normal, so the alarm (``|z|`` beyond the two-sided
quantile of the stated false-alarm rate, default 1 %) fires on a calibrated model in
about that share of disjoint windows. The normal approximation needs enough expected
events: the test is not made while ``E`` is under :data:`MIN_EXPECTED_EVENTS` (the
alarm is then "insufficient", never fired). Each alarm names the next step.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from statistics import NormalDist
from typing import Final, Literal

from prometheus_client.core import GaugeMetricFamily, Metric
from prometheus_client.registry import Collector
from pydantic import BaseModel, Field

from service.outcomes.stats import normal_two_sided_p

__all__ = [
    "MIN_EXPECTED_EVENTS",
    "NEXT_STEP",
    "DriftCollector",
    "DriftSettings",
    "DriftStatus",
    "drift_status",
]

#: Least expected ISS 15+ (weighted) in the window for the normal approximation of the
#: score test. [R] The textbook rule for a normal approximation to a binomial count
#: (n p >= 5).
MIN_EXPECTED_EVENTS: Final[float] = 5.0
#: What an alarm asks of the operator.
NEXT_STEP: Final[str] = (
    "Recalibrate the field model on the linked local outcomes "
    "(`aacn-triage outcomes recalibrate --site NAME`: a logistic recalibration, its operating "
    "thresholds re-derived, written as a new version), compare it with the served model on the "
    "stored cases (`aacn-triage cases rescore --model VERSION`), and switch only then; until "
    "then read the decided probabilities as {direction} (docs/outcomes.md)."
)


@dataclass(frozen=True)
class DriftSettings:
    """Window (linked occupants) and false-alarm rate of the drift alarm."""

    window: int = 400
    false_alarm_rate: float = 0.01


class DriftStatus(BaseModel):
    """The drift alarm's state over the last linked occupants."""

    state: Literal["ok", "alarm", "insufficient"] = Field(
        description="`alarm`: observed differs from predicted beyond the false-alarm rate; "
        "`insufficient`: too few expected ISS 15+ in the window for the test."
    )
    window: int = Field(description="Linked occupants the window holds at most.")
    occupants: int = Field(description="Linked occupants in the window.")
    observed: float = Field(description="Weighted ISS 15+ observed in the window.")
    predicted: float = Field(description="Weighted sum of the decided probabilities.")
    observed_over_predicted: float | None = Field(description="observed / predicted.")
    z: float | None = Field(description="Score statistic (O - E) / sqrt(V).")
    p_value: float | None = Field(description="Two-sided p-value of z.")
    false_alarm_rate: float = Field(description="Stated false-alarm rate per window (alpha).")
    z_threshold: float = Field(description="|z| at or beyond which the alarm fires.")
    min_expected_events: float = Field(description="Least `predicted` for the test to be made.")
    message: str = Field(description="What the state means, and the next step on an alarm.")


def drift_status(
    outcomes: Sequence[bool],
    predicted: Sequence[float],
    weights: Sequence[float],
    settings: DriftSettings,
) -> DriftStatus:
    """The drift alarm on linked occupants given oldest first (the last `window` are used)."""
    k = settings.window
    y, p, w = outcomes[-k:], predicted[-k:], weights[-k:]
    observed = math.fsum(wi for yi, wi in zip(y, w, strict=True) if yi)
    expected = math.fsum(wi * pi for pi, wi in zip(p, w, strict=True))
    variance = math.fsum(wi * wi * pi * (1.0 - pi) for pi, wi in zip(p, w, strict=True))
    z_threshold = NormalDist().inv_cdf(1.0 - settings.false_alarm_rate / 2.0)
    base = {
        "window": k,
        "occupants": len(y),
        "observed": observed,
        "predicted": expected,
        "observed_over_predicted": observed / expected if expected > 0 else None,
        "false_alarm_rate": settings.false_alarm_rate,
        "z_threshold": z_threshold,
        "min_expected_events": MIN_EXPECTED_EVENTS,
    }
    if expected < MIN_EXPECTED_EVENTS or variance <= 0.0:
        return DriftStatus(
            state="insufficient",
            z=None,
            p_value=None,
            message=f"Too few linked outcomes for the test: {expected:.1f} ISS 15+ expected in "
            f"the window, {MIN_EXPECTED_EVENTS:g} needed.",
            **base,
        )
    z = (observed - expected) / math.sqrt(variance)
    if abs(z) < z_threshold:
        return DriftStatus(
            state="ok",
            z=z,
            p_value=normal_two_sided_p(z),
            message=f"Observed ISS 15+ agree with predicted over the last {len(y)} linked "
            f"occupants (|z| {abs(z):.2f} < {z_threshold:.2f}).",
            **base,
        )
    direction = "too high" if z < 0 else "too low"
    return DriftStatus(
        state="alarm",
        z=z,
        p_value=normal_two_sided_p(z),
        message=f"Drift: over the last {len(y)} linked occupants the model predicted "
        f"{expected:.1f} ISS 15+ and {observed:.1f} were observed (z = {z:.2f}, false-alarm "
        f"rate {settings.false_alarm_rate:g}): its probabilities are {direction}. "
        + NEXT_STEP.format(direction=direction),
        **base,
    )


_GAUGES: Final = (
    "aacn_drift_alarm",
    "aacn_drift_z",
    "aacn_drift_observed_over_predicted",
    "aacn_drift_window_occupants",
    "aacn_drift_false_alarm_rate",
)


class DriftCollector(Collector):
    """Prometheus gauges of the drift alarm, read from the store at most once a `ttl_s`.

    Parameters
    ----------
    read : callable
        Returns the current :class:`DriftStatus` (queries the store); an exception
        leaves the last status (or none) in place, so a store outage does not break
        the scrape.
    """

    def __init__(self, read: Callable[[], DriftStatus], ttl_s: float = 60.0) -> None:
        self._read = read
        self._ttl_s = ttl_s
        self._at = -math.inf
        self._status: DriftStatus | None = None

    def _current(self) -> DriftStatus | None:
        now = time.monotonic()
        if now - self._at >= self._ttl_s:
            try:
                self._status = self._read()
                self._at = now
            except Exception:  # an outage: keep the last state; /readyz reports the store
                pass
        return self._status

    def describe(self) -> Iterator[Metric]:
        """The gauges' names, without reading the store (registration calls this)."""
        for name in _GAUGES:
            yield GaugeMetricFamily(name, "")

    def collect(self) -> Iterator[Metric]:
        status = self._current()
        if status is None:
            return
        alarm = GaugeMetricFamily(
            "aacn_drift_alarm",
            "1 when observed ISS 15+ differ from predicted over the last linked occupants "
            "beyond the stated false-alarm rate (then recalibrate: docs/outcomes.md).",
        )
        alarm.add_metric([], 1.0 if status.state == "alarm" else 0.0)
        yield alarm
        gauges = (
            ("aacn_drift_z", "Score statistic of observed against predicted ISS 15+.", status.z),
            (
                "aacn_drift_observed_over_predicted",
                "Weighted observed / predicted ISS 15+ over the window.",
                status.observed_over_predicted,
            ),
            ("aacn_drift_window_occupants", "Linked occupants in the window.", status.occupants),
            (
                "aacn_drift_false_alarm_rate",
                "The alarm's stated false-alarm rate per window.",
                status.false_alarm_rate,
            ),
        )
        for name, text, value in gauges:
            if value is None:
                continue
            g = GaugeMetricFamily(name, text)
            g.add_metric([], float(value))
            yield g
