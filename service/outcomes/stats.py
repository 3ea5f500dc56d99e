"""Shares with Wilson intervals, weighted or not, and a normal tail.

Weighted shares (survey weights) take the Kish effective sample size
``n_eff = (sum w)^2 / sum w^2`` in the Wilson interval (Kish, Survey Sampling, 1965):
with every weight 1 it is the plain count and the interval is Wilson's own (Wilson,
JASA 1927; recommended over the Wald interval by Brown, Cai & DasGupta, Stat Sci 2001).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

__all__ = ["Z95", "Share", "normal_two_sided_p", "share", "wilson"]

#: Two-sided 95 % standard normal quantile.
Z95: Final[float] = 1.959963984540054


def wilson(p: float, n: float, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of a share `p` observed on `n` (possibly effective) trials."""
    if n <= 0:
        return (0.0, 1.0)
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2.0 * n)) / denom
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4.0 * n * n)) / denom
    return (max(0.0, centre - half), min(1.0, centre + half))


@dataclass(frozen=True)
class Share:
    """A share: its counts, weighted sums, value and 95 % Wilson interval (None: no trials)."""

    numerator: int
    denominator: int
    weighted_numerator: float
    weighted_denominator: float
    effective_n: float
    value: float | None
    ci95: tuple[float, float] | None


def share(hits: Sequence[bool], weights: Sequence[float]) -> Share:
    """The (weighted) share of `hits` among the trials, with its Wilson interval."""
    n = len(hits)
    if n == 0:
        return Share(0, 0, 0.0, 0.0, 0.0, None, None)
    w_all = math.fsum(weights)
    w_hit = math.fsum(w for h, w in zip(hits, weights, strict=True) if h)
    n_eff = w_all * w_all / math.fsum(w * w for w in weights)
    value = w_hit / w_all
    return Share(sum(hits), n, w_hit, w_all, n_eff, value, wilson(value, n_eff))


def normal_two_sided_p(z: float) -> float:
    """Two-sided tail probability of a standard normal beyond |z|."""
    return math.erfc(abs(z) / math.sqrt(2.0))
