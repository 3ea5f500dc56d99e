"""Round tick values for the axes of the pages' SVG drawings (the case page's pulse plot,
the quality page's reliability plot)."""

from __future__ import annotations

import math

__all__ = ["nice_ticks"]


def nice_ticks(lo: float, hi: float, target: int = 5) -> list[float]:
    """Round tick values spanning [lo, hi] (1, 2, 5 x 10^n steps)."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return [0.0, 1.0]
    if hi - lo < 1e-9:
        lo, hi = lo - 1.0, hi + 1.0
    raw = (hi - lo) / max(target, 1)
    mag = 10.0 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1.0, 2.0, 5.0, 10.0) if m * mag >= raw)
    start = math.floor(lo / step) * step
    stop = math.ceil(hi / step) * step
    n = round((stop - start) / step)
    return [round(start + i * step, 10) for i in range(n + 1)]
