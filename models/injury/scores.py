"""AIS per ISS body region, the Injury Severity Score and P(ISS >= threshold).

ISS (Baker et al. 1974, J Trauma 14:187 [V]): the sum of the squares of the
highest AIS in each of the three most severely injured of six body regions;
range 0-75; any AIS 6 gives ISS 75. The regions (``injury-criteria.md``
section 3):

* ``head_neck``   head or neck, incl. cervical spine
* ``face``
* ``chest``       incl. thoracic spine
* ``abdomen``     abdomen or pelvic contents, incl. lumbar spine
* ``extremities`` extremities or pelvic girdle
* ``external``

A region missing from a mapping counts as AIS 0 (uninjured).
"""

from __future__ import annotations

import math
import operator
from collections.abc import Mapping, Sequence
from typing import Final

import numpy as np
import numpy.typing as npt

__all__ = [
    "AIS_LEVEL_THRESHOLD",
    "ISS_MAX",
    "ISS_REGIONS",
    "ISS_TRIAGE_THRESHOLD",
    "MAX_AIS",
    "PROBABILITY_SUM_TOLERANCE",
    "ais_distribution_from_cumulative",
    "ais_level",
    "iss",
    "iss_distribution",
    "p_iss_at_least",
]

#: The six ISS body regions, in Baker's order. [V] Baker et al. 1974.
ISS_REGIONS: Final[tuple[str, ...]] = (
    "head_neck",
    "face",
    "chest",
    "abdomen",
    "extremities",
    "external",
)
#: Highest AIS level (6, maximal). [V]
MAX_AIS: Final[int] = 6
#: Largest ISS, and the ISS of anyone with an AIS 6 injury. [V]
ISS_MAX: Final[int] = 75
#: Triage threshold of the reference paper: ISS >= 15 (Wikipedia's "major
#: trauma" is ISS > 15; the paper triages on >= 15). [V] reference section 3.
ISS_TRIAGE_THRESHOLD: Final[int] = 15
#: Tolerance on the sum of a regional distribution P(AIS = 0..6).
PROBABILITY_SUM_TOLERANCE: Final[float] = 1e-6
#: Cumulative probability at which :func:`ais_level` assigns a level: the
#: median of the regional AIS distribution. [R] The reference paper does not
#: state its rule (its Appendix A is missing); the median is the level the
#: distribution is as likely to exceed as not, so it is neither the optimistic
#: argmax of a spread distribution nor the 15 % threshold of one public code.
AIS_LEVEL_THRESHOLD: Final[float] = 0.5


def _check_region(name: str) -> str:
    if name not in ISS_REGIONS:
        raise ValueError(
            f"unknown ISS region {name!r} in `region_ais`; expected one of {ISS_REGIONS}."
        )
    return name


def iss(region_ais: Mapping[str, int]) -> int:
    """Injury Severity Score from the highest AIS of each body region.

    Parameters
    ----------
    region_ais : mapping of str to int
        Highest AIS (0..6) per ISS region (:data:`ISS_REGIONS`); absent regions
        count as 0. Fewer than three injured regions simply add fewer squares.

    Returns
    -------
    int
        ISS in 0..75; 75 whenever any region has AIS 6.

    Raises
    ------
    ValueError
        For an unknown region or an AIS outside 0..6.

    Examples
    --------
    >>> iss({"head_neck": 3, "chest": 2, "extremities": 1})
    14
    """
    levels: list[int] = []
    for name, value in region_ais.items():
        _check_region(name)
        try:
            level = operator.index(value)
        except TypeError:
            raise ValueError(f"AIS of region {name!r} must be an integer, got {value!r}.") from None
        if not 0 <= level <= MAX_AIS:
            raise ValueError(f"AIS of region {name!r} must be in 0..6, got {level}.")
        levels.append(level)
    if MAX_AIS in levels:
        return ISS_MAX
    top = sorted(levels, reverse=True)[:3]
    return sum(a * a for a in top)


def _as_distribution(name: str, probs: Sequence[float] | npt.ArrayLike) -> npt.NDArray[np.float64]:
    p = np.asarray(probs, dtype=np.float64)
    if p.shape != (MAX_AIS + 1,):
        raise ValueError(
            f"distribution of region {name!r} must have 7 entries P(AIS = 0..6), "
            f"got shape {p.shape}."
        )
    if not np.all(np.isfinite(p)) or np.any(p < 0.0):
        raise ValueError(f"distribution of region {name!r} must be finite and non-negative.")
    if abs(float(p.sum()) - 1.0) > PROBABILITY_SUM_TOLERANCE:
        raise ValueError(f"distribution of region {name!r} must sum to 1, got {float(p.sum())!r}.")
    return p


def _iss_of_top3(top: tuple[int, int, int]) -> int:
    if top[0] == MAX_AIS:
        return ISS_MAX
    return top[0] * top[0] + top[1] * top[1] + top[2] * top[2]


def _insert(top: tuple[int, int, int], level: int) -> tuple[int, int, int]:
    a, b, c = top
    if level >= a:
        return (level, a, b)
    if level >= b:
        return (a, level, b)
    if level > c:
        return (a, b, level)
    return top


def iss_distribution(
    region_probabilities: Mapping[str, Sequence[float] | npt.ArrayLike],
) -> dict[int, float]:
    """Exact distribution of ISS for independent regional AIS distributions.

    Dynamic programming over the regions on the sorted three highest levels
    seen so far (84 states), which is the whole of what ISS depends on; the
    result equals brute-force enumeration of all level combinations.

    Parameters
    ----------
    region_probabilities : mapping of str to sequence of float, each shape (7,)
        P(AIS = 0..6) per ISS region; absent regions are AIS 0 with
        probability 1. Each must be non-negative and sum to 1 (within 1e-6).

    Returns
    -------
    dict of int to float
        P(ISS = s) for every reachable s.
    """
    checked = {}
    for name, probs in region_probabilities.items():
        _check_region(name)
        checked[name] = _as_distribution(name, probs)
    return _iss_distribution(checked)


def _iss_distribution(
    region_probabilities: Mapping[str, Sequence[float] | npt.NDArray[np.float64]],
) -> dict[int, float]:
    """:func:`iss_distribution` of distributions already checked (the same numbers)."""
    states: dict[tuple[int, int, int], float] = {(0, 0, 0): 1.0}
    for p in region_probabilities.values():
        support = [(k, float(p[k])) for k in range(MAX_AIS + 1) if p[k] > 0.0]
        new: dict[tuple[int, int, int], float] = {}
        for top, q in states.items():
            for level, pk in support:
                key = _insert(top, level)
                new[key] = new.get(key, 0.0) + q * pk
        states = new
    out: dict[int, float] = {}
    for top, q in states.items():
        s = _iss_of_top3(top)
        out[s] = out.get(s, 0.0) + q
    return out


def p_iss_at_least(
    region_probabilities: Mapping[str, Sequence[float] | npt.ArrayLike], threshold: float = 15
) -> float:
    """Exact P(ISS >= threshold) from independent regional AIS distributions.

    Parameters
    ----------
    region_probabilities : mapping of str to sequence of float, each shape (7,)
        P(AIS = 0..6) per ISS region (see :func:`iss_distribution`).
    threshold : float, optional
        ISS threshold; 15 (default) is the triage threshold of the reference
        paper (ISS >= 15).

    Returns
    -------
    float
        Probability in [0, 1], computed by exact enumeration (no sampling);
        regions are assumed independent.
    """
    t = float(threshold)
    if not math.isfinite(t):
        raise ValueError("`threshold` must be finite.")
    return _p_iss_at_least(iss_distribution(region_probabilities), t)


def _p_iss_at_least(dist: Mapping[int, float], threshold: float) -> float:
    """P(ISS >= threshold) of an ISS distribution (:func:`iss_distribution`)."""
    total = math.fsum(q for s, q in dist.items() if s >= threshold)
    return min(max(total, 0.0), 1.0)


def ais_distribution_from_cumulative(
    cumulative: Sequence[float] | npt.ArrayLike,
) -> tuple[float, ...]:
    """P(AIS = 0..6) from P(AIS >= 1..6).

    Parameters
    ----------
    cumulative : sequence of float, shape (6,)
        P(AIS >= n) for n = 1..6, non-increasing, in [0, 1].

    Returns
    -------
    tuple of float, length 7
        P(AIS = n) = P(>= n) - P(>= n+1), with P(>= 0) = 1 and P(>= 7) = 0.
    """
    c = np.asarray(cumulative, dtype=np.float64)
    if c.shape != (MAX_AIS,):
        raise ValueError(f"`cumulative` must have 6 entries P(AIS >= 1..6), got shape {c.shape}.")
    if not np.all(np.isfinite(c)) or np.any(c < 0.0) or np.any(c > 1.0):
        raise ValueError("`cumulative` must be finite and in [0, 1].")
    if np.any(np.diff(c) > 1e-12):
        raise ValueError("`cumulative` must be non-increasing in n.")
    return _distribution_from_cumulative(c)


#: P(AIS = 0..6) of a region without risk (every P(AIS >= n) zero): what
#: :func:`_distribution_from_cumulative` gives for it, exactly.
_NO_RISK: Final[tuple[float, ...]] = (1.0,) + (0.0,) * MAX_AIS


def _distribution_from_cumulative(c: npt.NDArray[np.float64]) -> tuple[float, ...]:
    """:func:`ais_distribution_from_cumulative` of a checked shape (6,) array."""
    if not c.any():
        return _NO_RISK
    full = np.concatenate(([1.0], c, [0.0]))
    p = np.maximum(full[:-1] - full[1:], 0.0)
    p = p / p.sum()
    return tuple(float(v) for v in p)


def ais_level(
    distribution: Sequence[float] | npt.ArrayLike, threshold: float = AIS_LEVEL_THRESHOLD
) -> int:
    """One AIS level from a distribution: the highest n with P(AIS >= n) >= threshold.

    With the default threshold 0.5 this is the median level (see
    :data:`AIS_LEVEL_THRESHOLD`).

    Parameters
    ----------
    distribution : sequence of float, shape (7,)
        P(AIS = 0..6).
    threshold : float, optional
        In (0, 1].

    Returns
    -------
    int
        0..6.
    """
    if not 0.0 < threshold <= 1.0:
        raise ValueError("`threshold` must be in (0, 1].")
    return _ais_level(_as_distribution("<distribution>", distribution), threshold)


def _ais_level(p: npt.NDArray[np.float64], threshold: float) -> int:
    """:func:`ais_level` of a checked distribution."""
    # P(AIS >= n) for n = 0..6; a small tolerance absorbs rounding at exactly 0.5.
    tail = np.cumsum(p[::-1])[::-1]
    hits = np.nonzero(tail >= threshold - 1e-12)[0]
    return int(hits[-1])
