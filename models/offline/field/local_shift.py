"""Real crashes as a site's local outcomes, with and without a known shift (issue 50, item 5).

The NASS-CDS crashes of 2011-2014 (the fitted population's rows,
:func:`models.offline.field.occupants.fit_population`) stand for the linked outcomes
of a site: each occupant's decided probability is the served model's for its row
(every input known, the delta-V reconstructed:
:meth:`models.field.risk_model.RiskModel.decision_probability` of the rows'
design, :func:`models.offline.field.risk_data.risk_arrays`), its outcome ISS 15+
(ISS >= 16) and its weight the survey's national weight ``ratwgt``.

:func:`halve_odds` injects a known shift: each ISS 15+ occupant is kept with
probability 1/2 (seeded), the others all kept. At any inputs ``x`` the kept
occupants have ``P'(y=1|x) = (p/2) / (p/2 + 1 - p)``, i.e. the odds exactly halved.
:func:`crash_halves` splits the crashes in two (seeded), whole crashes together.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np

from models.arrays import FloatArray
from models.field.risk_children import CHILD_MAX_AGE_YEARS, design_columns_3
from models.field.risk_model import RiskModel, load_default
from models.offline.field.occupants import ISS15_PLUS, crash_keys, fit_population, load_occupants
from models.offline.field.risk_data import risk_arrays
from models.tiers import HIGH_RISK_THRESHOLD

__all__ = [
    "LOCAL_YEARS",
    "LocalOutcomes",
    "crash_halves",
    "decisions",
    "halve_odds",
    "nass_local_outcomes",
]

#: The accident years used as local outcomes (the model card's temporal check's years).
LOCAL_YEARS: Final[tuple[int, int]] = (2011, 2014)


@dataclass(frozen=True)
class LocalOutcomes:
    """Linked occupants as arrays of one length ``n``.

    Attributes
    ----------
    probability : ndarray, shape (n,)
        The served model's decided P(ISS 15+).
    serious : ndarray, shape (n,)
        1 ISS 15+, else 0.
    weight : ndarray, shape (n,)
        National weight (``ratwgt``).
    crash : ndarray of str, shape (n,)
        Crash id ``year:psu:caseno``.
    age_years : ndarray, shape (n,)
        Age, years (the threshold of a child is a child's).
    """

    probability: FloatArray
    serious: FloatArray
    weight: FloatArray
    crash: np.ndarray
    age_years: FloatArray

    def __len__(self) -> int:
        return int(self.probability.size)

    def subset(self, mask: np.ndarray) -> LocalOutcomes:
        """The occupants where `mask` holds."""
        return LocalOutcomes(
            self.probability[mask],
            self.serious[mask],
            self.weight[mask],
            self.crash[mask],
            self.age_years[mask],
        )

    def unweighted(self) -> LocalOutcomes:
        """The same occupants with unit weights (a registry's, which has no survey weights)."""
        return LocalOutcomes(
            self.probability, self.serious, np.ones(len(self)), self.crash, self.age_years
        )


def nass_local_outcomes(
    years: tuple[int, int] = LOCAL_YEARS, model: RiskModel | None = None
) -> LocalOutcomes:
    """The fitted population's occupants of `years` (inclusive) as local outcomes of `model`
    (default: the served artifact)."""
    m = load_default() if model is None else model
    rows = fit_population(load_occupants()).rows
    rows = rows[(rows["year"] >= years[0]) & (rows["year"] <= years[1])].reset_index(drop=True)
    x = design_columns_3(risk_arrays(rows, m.imputation))  # type: ignore[arg-type]
    crash = (
        rows["year"].astype(str) + ":" + rows["psu"].astype(str) + ":" + rows["caseno"].astype(str)
    ).to_numpy(dtype=str)
    assert np.unique(crash).size == np.unique(crash_keys(rows)).size
    return LocalOutcomes(
        probability=m.decision_probability(x),
        serious=(rows["iss"] >= ISS15_PLUS).to_numpy(dtype=np.float64),
        weight=rows["ratwgt"].to_numpy(dtype=np.float64),
        crash=crash,
        age_years=rows["age_years"].to_numpy(dtype=np.float64),
    )


def halve_odds(data: LocalOutcomes, seed: int) -> LocalOutcomes:
    """Each ISS 15+ occupant kept with probability 1/2: the odds halved at every input."""
    keep = (data.serious == 0) | (np.random.default_rng(seed).random(len(data)) < 0.5)
    return data.subset(keep)


def crash_halves(data: LocalOutcomes, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Masks of two halves of the crashes (each crash wholly in one), seeded."""
    crashes = np.unique(data.crash)
    first = crashes[np.random.default_rng(seed).random(crashes.size) < 0.5]
    a = np.isin(data.crash, first)
    return a, ~a


def decisions(
    data: LocalOutcomes, model: RiskModel, operating_point: str | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Flagged (at or above the operating point's threshold for an adult or a child, as
    known) and high tier (flagged and at or above the high tier's 20 %), each shape (n,)."""
    child = data.age_years < CHILD_MAX_AGE_YEARS
    threshold = np.where(
        child, model.threshold(operating_point, "child"), model.threshold(operating_point, "adult")
    )
    flagged = data.probability >= threshold
    return flagged, flagged & (data.probability >= HIGH_RISK_THRESHOLD)
