"""What the occupant models may report as a region's AIS level: never AIS 6 from a dummy measure.

:func:`models.injury.assessment.assess` turns the measures into each region's
AIS distribution with the published curves and reports its median level. The
head/neck level reaches AIS 6 ("maximal", unsurvivable) wherever the
Prasad/Mertz AIS 6 curve passes 0.5, at HIC15 of about 2,200. That level is
not something a dummy measure can represent:

- AIS 6 is defined by specific lesions (for the head, a crushed skull or
  brain stem; AIS 2005 dictionary), not by an acceleration; the Prasad/Mertz
  AIS 5 and AIS 6 curves extrapolate skull-fracture data of cadavers and
  cross the lower curves above HIC 3,250 (:mod:`models.injury.risk`);
- the occupant models reach HIC15 in the thousands only beyond the crash
  severities their parameters were checked at (side: the IIHS side test,
  struck-car delta-V 18-31 km/h, wbldb.lievers.net/01377; the reference
  near-side car delta-V 28.8 km/h, docs/lpm/notes.md), where nothing bounds the
  head load (no glass fracture, no yielding of the intruding structure);
- on the real crashes of NASS-CDS 1997-2014, of the occupants to whom the
  occupant models gave head/neck AIS 6 a minority had any AIS 5+ injury and
  most survived (``python -m models.offline.regions.report``,
  docs/occupant-models.md, "The body map against real injuries").

So the level the service reports for a region is at most :data:`MAX_REPORTED_AIS`,
and a capped region is named, so that the answer can flag it. The region's
AIS distribution, the ISS distribution and P(ISS >= 15) are left as the
curves give them (AIS 5 and AIS 6 both give ISS 15+, so the cap cannot move
P(ISS >= 15)); the surrogates, fitted on the uncapped outputs, are untouched.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

from models.injury.scores import iss

__all__ = ["MAX_REPORTED_AIS", "SIDE_TESTED_MAX_DELTA_V_KMH", "ReportedLevels", "reported_levels"]

#: Highest AIS level reported for a region from the occupant models' measures
#: (AIS 5, "critical"). [R] The module docstring gives the reasons.
MAX_REPORTED_AIS: Final[int] = 5
#: Highest struck-car (lateral) delta-V of the side tests the side occupant models
#: were checked against, km/h: the IIHS side test (1500 kg barrier at 50 km/h), whose
#: delta-V by SMASH ranged 18-31 km/h over 49 tests (mean 24). [V]
#: wbldb.lievers.net/01377 (IIHS side test severity against NASS-CDS side crashes).
#: Above it the answer says that the side models extrapolate.
SIDE_TESTED_MAX_DELTA_V_KMH: Final[float] = 31.0


@dataclass(frozen=True)
class ReportedLevels:
    """Region AIS levels as reported, and which regions were capped.

    Attributes
    ----------
    region_ais : dict of str to int
        Each region's level, at most :data:`MAX_REPORTED_AIS`.
    iss : int
        Baker ISS of `region_ais`.
    capped : tuple of str
        Regions whose model level was above :data:`MAX_REPORTED_AIS`.
    """

    region_ais: dict[str, int]
    iss: int
    capped: tuple[str, ...]


def reported_levels(region_ais: Mapping[str, int]) -> ReportedLevels:
    """The levels the service reports for the occupant models' region AIS.

    Parameters
    ----------
    region_ais : mapping of str to int
        The assessment's level per ISS region (0..6).

    Returns
    -------
    ReportedLevels

    Examples
    --------
    >>> r = reported_levels({"head_neck": 6, "chest": 3})
    >>> r.region_ais["head_neck"], r.iss, r.capped
    (5, 34, ('head_neck',))
    """
    levels = {k: min(int(v), MAX_REPORTED_AIS) for k, v in region_ais.items()}
    capped = tuple(k for k, v in region_ais.items() if int(v) > MAX_REPORTED_AIS)
    return ReportedLevels(region_ais=levels, iss=iss(levels), capped=capped)
