"""The Injury Severity Score's possible values, and its agreement with MAIS.

ISS (Baker et al., J Trauma 1974) is the sum of the squares of the highest AIS
severity in each of the three most severely injured of six ISS body regions, AIS
1-5; any AIS 6 (unsurvivable) injury sets ISS to 75 by convention. So ISS takes
only the values ``a^2 + b^2 + c^2`` with ``a, b, c`` in 0-5 (75 among them): 45 of the 76
integers 0-75 (7, 15, 23, 28, ... cannot occur). MAIS is the highest AIS of all
injuries, so an ISS also bounds the MAIS it can come with: the largest of ``a, b,
c`` is the MAIS (1-5), and MAIS 6 comes only with ISS 75.
"""

from __future__ import annotations

from itertools import combinations_with_replacement
from typing import Final

__all__ = [
    "ISS_MAX",
    "MAIS_MAX",
    "POSSIBLE_ISS",
    "iss_mais_agree",
    "possible_iss_for_mais",
]

#: Highest ISS (any AIS 6 injury, or three regions at AIS 5).
ISS_MAX: Final[int] = 75
#: Highest AIS severity (6: unsurvivable, "maximal").
MAIS_MAX: Final[int] = 6
#: Highest AIS that enters the ISS sum (AIS 6 sets ISS to 75 instead).
_AIS_SUMMED_MAX: Final[int] = 5


def possible_iss_for_mais(mais: int) -> frozenset[int]:
    """Every ISS that can occur with this MAIS (0-6).

    Parameters
    ----------
    mais : int
        The highest AIS severity of all injuries, 0 (uninjured) to 6.

    Returns
    -------
    frozenset of int
        ``{a^2 + b^2 + c^2 : 0 <= a, b, c <= mais, max(a, b, c) == mais}``; ``{75}``
        for MAIS 6; ``{0}`` for MAIS 0.
    """
    if not 0 <= mais <= MAIS_MAX:
        raise ValueError(f"MAIS must be 0-{MAIS_MAX}, got {mais}")
    if mais == MAIS_MAX:
        return frozenset({ISS_MAX})
    return frozenset(
        a * a + b * b + c * c
        for a, b, c in combinations_with_replacement(range(mais + 1), 3)
        if max(a, b, c) == mais
    )


#: Every ISS that can occur (45 values of 0-75; ISS 15 is not one, so ISS 15+ is ISS 16+).
POSSIBLE_ISS: Final[frozenset[int]] = frozenset().union(
    *(possible_iss_for_mais(m) for m in range(_AIS_SUMMED_MAX + 1))
)


def iss_mais_agree(iss: int, mais: int) -> bool:
    """True when an ISS can come with this MAIS (both assumed in range)."""
    return iss in possible_iss_for_mais(mais)
