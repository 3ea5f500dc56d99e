"""The quality page's reliability plot: observed against predicted ISS 15+ by decile, as
SVG geometry computed on the server (the case page's drawing style,
``service/pages/drawing.py``; the template's macro is ``templates/_reliability.html``).

Both axes share one linear scale from 0 to a round value above the largest decile
mean and interval bound, so the diagonal (perfect calibration) is at 45 degrees.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

from service.axis_ticks import nice_ticks

__all__ = ["RELIABILITY_SIZE", "ReliabilityPlot", "Dot", "reliability_plot"]

#: Side of the square viewBox and its margins (left, right, top, bottom).
RELIABILITY_SIZE: Final[float] = 360.0
_LEFT, _RIGHT, _TOP, _BOTTOM = 52.0, 14.0, 14.0, 40.0


@dataclass(frozen=True)
class Dot:
    """One decile: its point and its observed share's 95 % interval (screen units)."""

    x: float
    y: float
    y_low: float
    y_high: float
    label: str


@dataclass(frozen=True)
class ReliabilityPlot:
    dots: tuple[Dot, ...]
    ticks: tuple[tuple[float, float, str], ...]  # (x on the x axis, y on the y axis, text)
    diagonal: tuple[float, float, float, float]
    caption: str
    left: float = _LEFT
    right: float = RELIABILITY_SIZE - _RIGHT
    top: float = _TOP
    bottom: float = RELIABILITY_SIZE - _BOTTOM
    size: float = RELIABILITY_SIZE


def reliability_plot(
    deciles: Sequence[tuple[float, float, float, float, int]], caption: str
) -> ReliabilityPlot:
    """Geometry of the plot.

    Parameters
    ----------
    deciles : sequence of (mean predicted, observed, observed low, observed high, n)
        One per calibration group, shares 0-1.
    caption : str
        The plot's accessible name.
    """
    top_value = max([0.05, *(max(d[0], d[3]) for d in deciles)])
    ticks = nice_ticks(0.0, min(1.0, top_value), 4)
    scale_max = ticks[-1]
    width = RELIABILITY_SIZE - _LEFT - _RIGHT
    height = RELIABILITY_SIZE - _TOP - _BOTTOM

    def sx(v: float) -> float:
        return round(_LEFT + width * min(v, scale_max) / scale_max, 2)

    def sy(v: float) -> float:
        return round(RELIABILITY_SIZE - _BOTTOM - height * min(v, scale_max) / scale_max, 2)

    dots = tuple(
        Dot(
            x=sx(p),
            y=sy(o),
            y_low=sy(lo),
            y_high=sy(hi),
            label=f"predicted {100 * p:.1f} %, observed {100 * o:.1f} % of {n}",
        )
        for p, o, lo, hi, n in deciles
    )
    return ReliabilityPlot(
        dots=dots,
        ticks=tuple((sx(t), sy(t), f"{100 * t:g} %") for t in ticks),
        diagonal=(sx(0.0), sy(0.0), sx(scale_max), sy(scale_max)),
        caption=caption,
    )
