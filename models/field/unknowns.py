"""Unknown occupant inputs integrated over the fitted population, not imputed.

A telematics unit senses seats, belts and airbags; it rarely knows an
occupant's age, sex, stature or mass, and many rear belts are not monitored.
Risk is not linear in these inputs, so the risk at the median age is not the
average risk of an occupant of unknown age (it understates the risk of the
old most). For feature set 3 artifacts (:mod:`models.field.risk_children`) the
probability of an occupant with unknown inputs is the expectation over their
distribution in the fitting data, given what is known:

    P = E[P(x_known, X_unknown) | seat group, known inputs]

The distribution is a **donor table** stored in the artifact: per seat group
(:data:`SEAT_GROUPS`), :data:`DONORS_PER_GROUP` occupants of the fitted
population drawn with probability proportional to their national weight
(``ratwgt``, systematic sampling of the rows sorted by age, stature, mass,
sex and restraint; deterministic), so each donor stands for an equal share of
the nation's occupants of that seat. A request takes the donors of its seat
group that match what it knows (age band, sex, restraint) and, of those,
:data:`DONORS_PER_OCCUPANT` evenly spaced in the table's order (a stratified
sample over age); where fewer than :data:`MIN_DONORS` match, the match is
relaxed in a fixed order (seat group, then restraint, then sex), so a rare
combination still gets an answer. The offline fit scores held-out occupants
through the same functions (:func:`pick_donors`, :func:`substitute`).

Why not a library: this is weighted resampling from an empirical table (a
few lines of numpy); what matters is that the service and the fit share it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from models.arrays import FloatArray, IntArray

__all__ = [
    "AGE_BANDS_YEARS",
    "DONORS_PER_GROUP",
    "DONORS_PER_OCCUPANT",
    "INTEGRATED_INPUTS",
    "MIN_DONORS",
    "SEAT_GROUPS",
    "DonorTable",
    "build_donors",
    "pick_donors",
    "seat_group",
    "substitute",
]

#: The inputs integrated over when unknown (raw-array names; ``restraint`` is
#: a :class:`models.field.risk_children.Restraint` value).
INTEGRATED_INPUTS: Final[tuple[str, ...]] = (
    "age_years",
    "female",
    "stature_cm",
    "mass_kg",
    "restraint",
)

#: Seat groups of the donor table (who sits where differs: children ride in
#: the back, drivers are adults).
SEAT_GROUPS: Final[tuple[str, ...]] = (
    "driver",
    "front_passenger",
    "front_middle",
    "row2_outboard",
    "row2_middle",
    "row3",
)

#: Age bands a known age is matched in, years: the child groups of feature set
#: 3 and adult bands of 20 years (the age spline's knots at 18, 33 and 65 fall
#: inside or on their edges).
AGE_BANDS_YEARS: Final[tuple[float, ...]] = (0.0, 5.0, 10.0, 16.0, 25.0, 45.0, 65.0, 200.0)

#: Donors per seat group in the artifact. [R] 400 equal-weight draws give a
#: share (e.g. of the 65+) to within about 2 percentage points (binomial SE
#: at 0.15: 0.018) while the artifact stays small.
DONORS_PER_GROUP: Final[int] = 400

#: Donors an occupant's probability is averaged over. [R] 32 points evenly
#: spaced over the matching donors sorted by age: a stratified sample over age
#: (the input that moves risk most), whose mean has a smaller error than that of
#: 32 independent draws; it bounds the request's cost (32 rows through the trees
#: per occupant with unknown inputs).
DONORS_PER_OCCUPANT: Final[int] = 32

#: Fewest matching donors before the match is relaxed.
MIN_DONORS: Final[int] = 8

#: Raw-array names of the donor values, in the table's column order.
_NUMERIC: Final[tuple[str, ...]] = ("age_years", "female", "stature_cm", "mass_kg")


def seat_group(seat_row: int, seat_side: str, driver: bool) -> str:
    """The donor seat group of a seat (row 1-3, side ``left``/``middle``/``right``)."""
    if seat_row == 1:
        if driver:
            return "driver"
        return "front_middle" if seat_side == "middle" else "front_passenger"
    if seat_row == 2:
        return "row2_middle" if seat_side == "middle" else "row2_outboard"
    return "row3"


def _age_band(age_years: float) -> int:
    return int(np.searchsorted(AGE_BANDS_YEARS, age_years, side="right")) - 1


@dataclass(frozen=True, eq=False)
class DonorTable:
    """Equal-weight draws of the fitted population per seat group.

    Attributes
    ----------
    group : tuple of str, shape (D,)
        Seat group of each donor (:data:`SEAT_GROUPS`).
    age_years, female, stature_cm, mass_kg : ndarray, shape (D,)
    restraint : tuple of str, shape (D,)
    """

    group: tuple[str, ...]
    age_years: FloatArray
    female: FloatArray
    stature_cm: FloatArray
    mass_kg: FloatArray
    restraint: tuple[str, ...]

    def __post_init__(self) -> None:
        n = len(self.group)
        sizes = {len(self.restraint), *(np.shape(getattr(self, k))[0] for k in _NUMERIC)}
        if sizes != {n} or n == 0:
            raise ValueError("donor table: every column must hold the same number of donors")
        if not set(self.group) <= set(SEAT_GROUPS):
            raise ValueError("donor table: unknown seat group")
        for k in _NUMERIC:
            if not np.all(np.isfinite(getattr(self, k))):
                raise ValueError(f"donor table: `{k}` must be finite")

    def to_document(self) -> dict[str, Any]:
        """JSON-ready columns."""
        return {
            "group": list(self.group),
            **{k: [round(float(v), 3) for v in getattr(self, k)] for k in _NUMERIC},
            "restraint": list(self.restraint),
        }

    @classmethod
    def from_document(cls, doc: Mapping[str, Any]) -> DonorTable:
        """The table of :meth:`to_document` (ValueError when malformed)."""
        try:
            arrays = {k: np.array(doc[k], dtype=np.float64) for k in _NUMERIC}
            for a in arrays.values():
                a.setflags(write=False)
            return cls(
                group=tuple(str(g) for g in doc["group"]),
                restraint=tuple(str(r) for r in doc["restraint"]),
                **arrays,
            )
        except (KeyError, TypeError) as exc:
            raise ValueError(f"donor table: malformed ({exc})") from None

    def _groups_index(self) -> dict[str, IntArray]:
        g = np.asarray(self.group, dtype=object)
        return {name: np.flatnonzero(g == name) for name in SEAT_GROUPS}


def pick_donors(
    table: DonorTable,
    group: str,
    *,
    age_years: float | None = None,
    female: float | None = None,
    restraint: str | None = None,
) -> IntArray:
    """Indices of the donors an occupant is averaged over (module docstring).

    Parameters
    ----------
    table : DonorTable
    group : str
        The occupant's seat group.
    age_years, female, restraint : optional
        What is known (None: unknown, integrated over).

    Returns
    -------
    ndarray of int, shape (m,), 1 <= m <= DONORS_PER_OCCUPANT
        In the table's order.
    """
    g = np.asarray(table.group, dtype=object)
    r = np.asarray(table.restraint, dtype=object)
    conditions: list[tuple[str, np.ndarray]] = [("group", g == group)]
    if restraint is not None:
        conditions.append(("restraint", r == restraint))
    if female is not None:
        conditions.append(("female", table.female == float(female)))
    if age_years is not None:  # never relaxed: a known age is the strongest input
        band = _age_band(float(age_years))
        bands = np.searchsorted(AGE_BANDS_YEARS, table.age_years, side="right") - 1
        age_mask = bands == band
    else:
        age_mask = np.ones(len(g), dtype=bool)
    relax_order = ("group", "restraint", "female")
    active = dict(conditions)
    mask = age_mask & np.logical_and.reduce(list(active.values()))
    for name in relax_order:
        if mask.sum() >= MIN_DONORS:
            break
        active.pop(name, None)
        mask = age_mask.copy()
        for m in active.values():
            mask &= m
    cand = np.flatnonzero(mask)
    if cand.size == 0:  # an age band with no donor at all: the nearest ages
        cand = np.argsort(np.abs(table.age_years - float(age_years or 0.0)), kind="stable")[
            :MIN_DONORS
        ]
        cand.sort()
    if cand.size <= DONORS_PER_OCCUPANT:
        return cand
    at = ((np.arange(DONORS_PER_OCCUPANT) + 0.5) * cand.size / DONORS_PER_OCCUPANT).astype(int)
    out: IntArray = cand[at]
    return out


def substitute(
    arrays: Mapping[str, FloatArray | Sequence[str]],
    rows: Sequence[tuple[int, IntArray | None, Sequence[str]]],
    table: DonorTable,
) -> tuple[dict[str, FloatArray | list[str]], IntArray]:
    """Raw input arrays with each listed row expanded over its donors.

    Parameters
    ----------
    arrays : mapping of str to array, each shape (n,)
        Raw inputs (an unknown one holds any value: the donors' replace it).
    rows : sequence of (row, donors, unknown names)
        Per output block: the input row, the donor indices (None: the row
        alone) and the names of :data:`INTEGRATED_INPUTS` to take from them.
    table : DonorTable

    Returns
    -------
    expanded : dict of arrays, each shape (N,)
    owner : ndarray of int, shape (N,)
        The block (index into `rows`) of each expanded row.
    """
    src: list[int] = []
    owner: list[int] = []
    for k, (row, donors, _) in enumerate(rows):
        m = 1 if donors is None else int(donors.size)
        src.extend([row] * m)
        owner.extend([k] * m)
    take = np.asarray(src, dtype=np.int64)
    out: dict[str, FloatArray | list[str]] = {}
    for name, value in arrays.items():
        if isinstance(value, np.ndarray):
            out[name] = value[take].astype(np.float64, copy=True)
        else:
            seq = list(value)
            out[name] = [seq[i] for i in src]
    pos = 0
    for row_donors in rows:
        _, donors, names = row_donors
        m = 1 if donors is None else int(donors.size)
        if donors is not None:
            for name in names:
                if name == "restraint":
                    target = out["restraint"]
                    assert isinstance(target, list)
                    target[pos : pos + m] = [table.restraint[j] for j in donors]
                else:
                    col = out[name]
                    assert isinstance(col, np.ndarray)
                    col[pos : pos + m] = np.asarray(getattr(table, name))[donors]
            if "restraint" in names:
                belted = out["belted"]
                assert isinstance(belted, np.ndarray)
                belted[pos : pos + m] = [float(table.restraint[j] != "none") for j in donors]
        pos += m
    return out, np.asarray(owner, dtype=np.int64)


def build_donors(
    group: Sequence[str],
    values: Mapping[str, FloatArray | Sequence[str]],
    weight: FloatArray,
    per_group: int = DONORS_PER_GROUP,
) -> DonorTable:
    """Draw the donor table from the fitted population (offline; module docstring).

    Parameters
    ----------
    group : sequence of str, shape (n,)
        Each row's seat group.
    values : mapping
        ``age_years``, ``female``, ``stature_cm``, ``mass_kg`` (arrays (n,))
        and ``restraint`` (str (n,)), as the fit sees them.
    weight : ndarray, shape (n,)
        National weights.
    per_group : int
    """
    g = np.asarray(group, dtype=object)
    restr = np.asarray(values["restraint"], dtype=object)
    cols = {k: np.asarray(values[k], dtype=np.float64) for k in _NUMERIC}
    picks: list[int] = []
    out_group: list[str] = []
    for name in SEAT_GROUPS:
        idx = np.flatnonzero(g == name)
        if idx.size == 0:
            continue
        order = np.lexsort(
            (
                restr[idx].astype(str),
                cols["female"][idx],
                cols["mass_kg"][idx],
                cols["stature_cm"][idx],
                cols["age_years"][idx],
            )
        )
        idx = idx[order]
        cum = np.cumsum(np.asarray(weight, dtype=np.float64)[idx])
        points = (np.arange(per_group) + 0.5) * cum[-1] / per_group
        chosen = idx[np.minimum(np.searchsorted(cum, points), idx.size - 1)]
        picks.extend(int(i) for i in chosen)
        out_group.extend([name] * per_group)
    take = np.asarray(picks, dtype=np.int64)
    return DonorTable(
        group=tuple(out_group),
        restraint=tuple(str(r) for r in restr[take]),
        **{k: cols[k][take] for k in _NUMERIC},
    )
