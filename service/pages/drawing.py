"""Geometry of the case page's SVG drawings, computed on the server.

Each function returns plain numbers and strings that a template lays out as
SVG elements (no styling here: colours come from the static stylesheet by class,
so the page needs no inline style and passes a strict Content-Security-Policy).
Screen coordinates: x right, y down.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from service.axis_ticks import nice_ticks

__all__ = [
    "BODY_REGIONS",
    "Arrow",
    "Axis",
    "Bar",
    "CarDiagram",
    "Plot",
    "RegionShape",
    "SeatMark",
    "Series",
    "car_diagram",
    "probability_bar",
    "pulse_plot",
]

# ------------------------------------------------------------------ probability bar

#: Width and horizontal padding of the probability bar's viewBox.
BAR_WIDTH, BAR_PAD = 400.0, 18.0


@dataclass(frozen=True)
class Bar:
    """A probability, its 95% interval and the threshold on a 0-100 % scale."""

    x_point: float
    x_low: float
    x_high: float
    x_threshold: float
    ticks: tuple[tuple[float, str], ...]
    width: float = BAR_WIDTH


def _bar_x(p: float) -> float:
    return round(BAR_PAD + min(max(p, 0.0), 1.0) * (BAR_WIDTH - 2 * BAR_PAD), 2)


def probability_bar(probability: float, low: float, high: float, threshold: float) -> Bar:
    """Positions of the probability bar (linear 0-100 % scale)."""
    return Bar(
        x_point=_bar_x(probability),
        x_low=_bar_x(low),
        x_high=_bar_x(high),
        x_threshold=_bar_x(threshold),
        ticks=tuple((_bar_x(q / 4), f"{25 * q} %") for q in range(5)),
    )


# ------------------------------------------------------------------ car and PDOF

#: Car drawing: viewBox size, body centre and half-width / half-length.
CAR_VIEW_W, CAR_VIEW_H = 300.0, 400.0
CAR_CX, CAR_CY, CAR_HALF_W, CAR_HALF_L = 150.0, 200.0, 55.0, 115.0
#: Length of the PDOF arrow outside the car.
ARROW_LENGTH = 52.0


@dataclass(frozen=True)
class Arrow:
    """The PDOF arrow: tail outside the car, head on its outline, pointing in."""

    x1: float
    y1: float
    x2: float
    y2: float
    head: str  # polygon points
    label_x: float
    label_y: float


@dataclass(frozen=True)
class SeatMark:
    """An occupied seat on the car outline."""

    seat: str
    x: float
    y: float
    flagged: bool
    label: str


@dataclass(frozen=True)
class CarDiagram:
    """Top view of the car, nose up, with the PDOF arrow and the occupied seats."""

    cx: float
    cy: float
    half_w: float
    half_l: float
    arrow: Arrow
    seats: tuple[SeatMark, ...]
    width: float = CAR_VIEW_W
    height: float = CAR_VIEW_H

    @property
    def outline(self) -> tuple[float, float, float, float]:
        """x, y, width, height of the body."""
        return (self.cx - self.half_w, self.cy - self.half_l, 2 * self.half_w, 2 * self.half_l)

    @property
    def windshield(self) -> str:
        x0, x1 = self.cx - self.half_w, self.cx + self.half_w
        y0 = self.cy - self.half_l
        pts = ((x0 + 8, y0 + 56), (x1 - 8, y0 + 56), (x1 - 15, y0 + 82), (x0 + 15, y0 + 82))
        return " ".join(f"{x:.1f},{y:.1f}" for x, y in pts)

    @property
    def rear_window(self) -> str:
        x0, x1 = self.cx - self.half_w, self.cx + self.half_w
        y1 = self.cy + self.half_l
        pts = ((x0 + 15, y1 - 48), (x1 - 15, y1 - 48), (x1 - 9, y1 - 26), (x0 + 9, y1 - 26))
        return " ".join(f"{x:.1f},{y:.1f}" for x, y in pts)

    @property
    def wheels(self) -> tuple[tuple[float, float], ...]:
        """Top-left corners of the four 9 x 36 wheels."""
        xl, xr = self.cx - self.half_w - 9, self.cx + self.half_w
        yf, yr = self.cy - self.half_l + 30, self.cy + self.half_l - 66
        return ((xl, yf), (xr, yf), (xl, yr), (xr, yr))


def _seat_xy(seat: str, drive_side: str) -> tuple[float, float]:
    left, right = CAR_CX - 25.0, CAR_CX + 25.0
    driver_x, passenger_x = (left, right) if drive_side != "right" else (right, left)
    return {
        "driver": (driver_x, CAR_CY - 14.0),
        "front_passenger": (passenger_x, CAR_CY - 14.0),
        "rear_left": (left, CAR_CY + 48.0),
        "rear_middle": (CAR_CX, CAR_CY + 48.0),
        "rear_right": (right, CAR_CY + 48.0),
        "front_middle": (CAR_CX, CAR_CY - 14.0),
        "third_row_left": (left, CAR_CY + 92.0),
        "third_row_middle": (CAR_CX, CAR_CY + 92.0),
        "third_row_right": (right, CAR_CY + 92.0),
    }.get(seat, (CAR_CX, CAR_CY))


def car_diagram(
    pdof_deg: float, drive_side: str, seats: Sequence[tuple[str, bool, str]]
) -> CarDiagram:
    """The PDOF arrow and seat marks for a car drawn nose up.

    Parameters
    ----------
    pdof_deg : float
        Principal direction of force, deg clockwise from straight ahead (0: the
        force comes from the front; 90: from the right side).
    drive_side : str
        ``left`` or ``right`` (where the driver sits).
    seats : sequence of (seat, flagged, label)
    """
    theta = math.radians(pdof_deg)
    ux, uy = math.sin(theta), -math.cos(theta)
    # ray from the centre in direction u meets the outline at t
    t = min(
        CAR_HALF_W / abs(ux) if abs(ux) > 1e-9 else math.inf,
        CAR_HALF_L / abs(uy) if abs(uy) > 1e-9 else math.inf,
    )
    hx, hy = CAR_CX + (t + 3.0) * ux, CAR_CY + (t + 3.0) * uy
    tx, ty = CAR_CX + (t + ARROW_LENGTH) * ux, CAR_CY + (t + ARROW_LENGTH) * uy
    # arrowhead: tip at the outline, base 12 units back along the arrow
    bx, by = hx + 12.0 * ux, hy + 12.0 * uy
    px, py = -uy, ux
    head = " ".join(
        f"{x:.1f},{y:.1f}"
        for x, y in ((hx, hy), (bx + 6.0 * px, by + 6.0 * py), (bx - 6.0 * px, by - 6.0 * py))
    )
    lx, ly = CAR_CX + (t + ARROW_LENGTH + 10.0) * ux, CAR_CY + (t + ARROW_LENGTH + 10.0) * uy
    arrow = Arrow(
        x1=round(tx, 1),
        y1=round(ty, 1),
        x2=round(bx, 1),
        y2=round(by, 1),
        head=head,
        label_x=round(min(max(lx, 30.0), CAR_VIEW_W - 30.0), 1),
        label_y=round(min(max(ly, 14.0), CAR_VIEW_H - 6.0), 1),
    )
    marks = tuple(
        SeatMark(seat=s, x=x, y=y, flagged=flagged, label=label)
        for s, flagged, label in seats
        for x, y in [_seat_xy(s, drive_side)]
    )
    return CarDiagram(
        cx=CAR_CX, cy=CAR_CY, half_w=CAR_HALF_W, half_l=CAR_HALF_L, arrow=arrow, seats=marks
    )


# ------------------------------------------------------------------ body map

#: An SVG shape: tag and attributes.
Shape = tuple[str, tuple[tuple[str, str], ...]]


@dataclass(frozen=True)
class RegionShape:
    """The shapes of one ISS body region on the body map and where its AIS label goes."""

    key: str
    shapes: tuple[Shape, ...]
    label_x: float
    label_y: float


def _rect(x: int, y: int, w: int, h: int, rx: int = 0) -> Shape:
    attrs = (("x", str(x)), ("y", str(y)), ("width", str(w)), ("height", str(h)))
    return ("rect", attrs + ((("rx", str(rx)),) if rx else ()))


#: A simple front-view body map, viewBox 200 x 340. Drawing order: the external
#: (skin) frame first, the face last (it lies on the head).
BODY_REGIONS: tuple[RegionShape, ...] = (
    RegionShape("external", (_rect(4, 2, 192, 336, 20),), 22.0, 26.0),
    RegionShape(
        "extremities",
        (
            _rect(34, 82, 20, 122, 9),
            _rect(146, 82, 20, 122, 9),
            _rect(70, 208, 27, 124, 10),
            _rect(103, 208, 27, 124, 10),
        ),
        83.5,
        274.0,
    ),
    RegionShape("chest", (_rect(58, 78, 84, 70, 12),), 100.0, 118.0),
    RegionShape("abdomen", (_rect(62, 150, 76, 56, 10),), 100.0, 183.0),
    RegionShape(
        "head_neck",
        (("circle", (("cx", "100"), ("cy", "34"), ("r", "27"))), _rect(89, 58, 22, 20)),
        100.0,
        20.0,
    ),
    RegionShape(
        "face",
        (("ellipse", (("cx", "100"), ("cy", "39"), ("rx", "13"), ("ry", "15"))),),
        100.0,
        44.0,
    ),
)


# ------------------------------------------------------------------ pulse plot

#: Plot viewBox and margins.
PLOT_W, PLOT_H = 600.0, 240.0
PLOT_LEFT, PLOT_RIGHT, PLOT_TOP, PLOT_BOTTOM = 56.0, 12.0, 12.0, 36.0
#: Most points drawn per series (min/max buckets keep the peaks of long series).
MAX_PLOT_POINTS = 600


@dataclass(frozen=True)
class Series:
    """One polyline of the plot."""

    name: str
    css: str
    points: str


@dataclass(frozen=True)
class Axis:
    """Tick positions (screen) and labels of one axis."""

    ticks: tuple[tuple[float, str], ...]
    label: str


@dataclass(frozen=True)
class Plot:
    """A line plot in a PLOT_W x PLOT_H viewBox."""

    series: tuple[Series, ...]
    x_axis: Axis
    y_axis: Axis
    zero_y: float | None
    caption: str
    left: float = PLOT_LEFT
    right: float = PLOT_W - PLOT_RIGHT
    top: float = PLOT_TOP
    bottom: float = PLOT_H - PLOT_BOTTOM
    width: float = PLOT_W
    height: float = PLOT_H


def _fmt_tick(v: float) -> str:
    return f"{v:g}" if abs(v) >= 1e-9 else "0"


def _decimate(
    t: npt.NDArray[np.floating[Any]], y: npt.NDArray[np.float64]
) -> list[tuple[float, float]]:
    """At most MAX_PLOT_POINTS points; each bucket keeps its minimum and maximum, in order."""
    n = len(y)
    if n <= MAX_PLOT_POINTS:
        return list(zip(t.tolist(), y.tolist(), strict=True))
    buckets = MAX_PLOT_POINTS // 2
    k = -(-n // buckets)  # samples per bucket, the last one shorter
    values = np.full(buckets * k, np.nan)
    values[:n] = y
    rows = values.reshape(buckets, k)
    used = ~np.all(np.isnan(rows), axis=1)
    base = np.arange(buckets)[used] * k
    i_min = base + np.nanargmin(rows[used], axis=1)
    i_max = base + np.nanargmax(rows[used], axis=1)
    first, second = np.minimum(i_min, i_max), np.maximum(i_min, i_max)
    order = np.column_stack([first, second]).ravel()
    keep = np.concatenate([[True], order[1:] != order[:-1]])
    picked = order[keep]
    return list(zip(t[picked].tolist(), values[picked].tolist(), strict=True))


def _plot(
    curves: Sequence[tuple[str, str, list[tuple[float, float]]]],
    x_label: str,
    y_label: str,
    caption: str,
) -> Plot:
    xs = [x for _, _, pts in curves for x, _ in pts]
    ys = [y for _, _, pts in curves for _, y in pts] + [0.0]
    x_ticks = nice_ticks(min(xs, default=0.0), max(xs, default=1.0))
    y_ticks = nice_ticks(min(ys), max(ys), 4)
    x0, x1, y0, y1 = x_ticks[0], x_ticks[-1], y_ticks[0], y_ticks[-1]
    left, right = PLOT_LEFT, PLOT_W - PLOT_RIGHT
    top, bottom = PLOT_TOP, PLOT_H - PLOT_BOTTOM

    def sx(x: float) -> float:
        return left + (x - x0) / (x1 - x0) * (right - left)

    def sy(y: float) -> float:
        return bottom - (y - y0) / (y1 - y0) * (bottom - top)

    series = tuple(
        Series(name=name, css=css, points=" ".join(f"{sx(x):.1f},{sy(y):.1f}" for x, y in pts))
        for name, css, pts in curves
    )
    return Plot(
        series=series,
        x_axis=Axis(ticks=tuple((round(sx(v), 1), _fmt_tick(v)) for v in x_ticks), label=x_label),
        y_axis=Axis(ticks=tuple((round(sy(v), 1), _fmt_tick(v)) for v in y_ticks), label=y_label),
        zero_y=round(sy(0.0), 1) if y0 < 0.0 < y1 else None,
        caption=caption,
    )


def _series(value: object) -> npt.NDArray[np.float64] | None:
    """A stored series as a float array, or None unless it is a list of finite numbers."""
    if not isinstance(value, list) or not value:
        return None
    try:  # the stored notification passed validation: numbers, checked here in bulk
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        return None
    return array if array.ndim == 1 and bool(np.isfinite(array).all()) else None


def pulse_plot(pulse: dict[str, object], haversine: dict[str, object] | None = None) -> Plot | None:
    """The crash pulse as sent, or None when the stored pulse cannot be drawn.

    Parameters
    ----------
    pulse : dict
        ``crash.pulse`` of the stored notification (kind ``summary``,
        ``delta_v`` or ``acceleration``).
    haversine : dict, optional
        ``pulse.haversine`` of the stored result: for a summary pulse, the
        haversine a(t) = A sin^2(pi t / T) the engine used is drawn.
    """
    kind = pulse.get("kind")
    if kind == "acceleration":
        rate = pulse.get("sample_rate_hz")
        lon, lat = _series(pulse.get("longitudinal_g")), _series(pulse.get("lateral_g"))
        if not isinstance(rate, int | float) or rate <= 0 or lon is None or lat is None:
            return None
        if len(lon) != len(lat):
            return None
        t = 1000.0 * np.arange(len(lon)) / float(rate)
        return _plot(
            [
                ("longitudinal (x)", "series-x", _decimate(t, lon)),
                ("lateral (y)", "series-y", _decimate(t, lat)),
            ],
            "time (ms)",
            "acceleration (g)",
            f"Vehicle acceleration as sent: {len(lon)} samples at {float(rate):g} Hz.",
        )
    if kind == "delta_v":
        interval = pulse.get("interval_ms", 10.0)
        lon, lat = _series(pulse.get("longitudinal_kmh")), _series(pulse.get("lateral_kmh"))
        if not isinstance(interval, int | float) or lon is None or lat is None:
            return None
        if len(lon) != len(lat):
            return None
        t = float(interval) * np.arange(len(lon))
        return _plot(
            [
                ("longitudinal (x)", "series-x", _decimate(t, lon)),
                ("lateral (y)", "series-y", _decimate(t, lat)),
            ],
            "time (ms)",
            "cumulative delta-V (km/h)",
            f"EDR delta-V record as sent: {len(lon)} samples every {float(interval):g} ms.",
        )
    if kind == "summary" and haversine is not None:
        amp, dur = haversine.get("amplitude_g"), haversine.get("duration_ms")
        if not isinstance(amp, int | float) or not isinstance(dur, int | float) or dur <= 0:
            return None
        n = 120
        pts = [(dur * i / n, float(amp) * math.sin(math.pi * i / n) ** 2) for i in range(n + 1)]
        return _plot(
            [("resultant", "series-r", pts)],
            "time (ms)",
            "deceleration (g)",
            f"Summary pulse (delta-V and PDOF only): the haversine the engine used, "
            f"A = {float(amp):.1f} g over T = {float(dur):.0f} ms.",
        )
    return None
