"""The delta-V a vehicle measures, read on the scale of the delta-V the field data reconstructed.

The field risk models learned from NASS-CDS delta-V, which investigators
reconstructed after the crash from the vehicle's crush (WinSMASH). A
notification carries the delta-V the vehicle's own sensors measured (the
airbag control module's EDR record, the telematics unit's accelerometer). The
two differ, and this module is the relation between them: the measurement
model, versioned (:data:`MEASUREMENT_MODEL`), every coefficient with its
source.

Reconstructed given measured, for an occupant of a crash reconstructed in era
``e`` (the WinSMASH version of the data's accident year)::

    reconstructed = f_e * measured + eps,     eps ~ Normal(0, SD_KMH)

The served reading takes the reconstruction a measurement stands for,
``f_e * measured``, over the two eras and the measurement's own tolerance
(below), not over ``eps``: ``eps`` is the reconstruction's own noise, which the
field risk curves already carry (they were fitted on reconstructions).

- ``f_e``, the mean ratio reconstructed / measured:

  * accident years up to 2006 (WinSMASH with generic stiffness categories):
    0.77. [V] Niehoff & Gabler 2006 (Annu Proc AAAM 50; PMC3217484): on 121
    NASS-CDS 2000-2003 cases with an EDR readout WinSMASH underestimated
    delta-V by 23 % on average (``../shared/reference/crash-data-and-triage.md``).
  * accident years from 2007 (WinSMASH 2007/2008 with vehicle-specific
    stiffness, revised again in 2010, NHTSA DOT HS 811 546): 0.81. [V]
    ``crash-data-and-triage.md``: NASS reconstructed delta-V averages about
    19 % below EDR-measured delta-V (n = 228). Niehoff & Gabler found that
    vehicle-specific stiffness improved the estimate, so the smaller
    underestimate is taken for the revised code. [R] The years of those 228
    cases are not in the reference; later comparisons of the revised
    WinSMASH with EDRs (Hampton & Gabler; Johnson & Gabler) were not at
    hand, so the era split rests on these two figures.

- ``SD_KMH`` = 8.6 km/h: the standard deviation of the difference between the
  two (n = 228, ``crash-data-and-triage.md``). [R] Taken for both eras (the
  2006 study's scatter is not in the reference).

- The era of a served answer is unknown (the model answers as of its latest
  year, but its delta-V terms were learned from every year): the relation is
  the mixture of the two eras with the fitted population's shares
  (:data:`EARLY_ERA_SHARE`).

- By crash mode and vehicle class: Niehoff & Gabler report pickups off by
  3 % and front-wheel-drive cars by 31 %, but a notification carries no body
  class, and no comparison by crash mode of NASS's own reconstruction is in
  the reference (the 1 % of frontal crashes is with restitution added, which
  NASS-CDS did not do): the mean over the studies' mix is used for every mode
  and class. [R]

**Which reading is the noisier decides the direction.** Part 563 requires the
EDR's delta-V within +/-10 % (49 CFR 563 Table III, ``crash-data-and-triage.md``
2.5), while the reconstruction scatters by 8.6 km/h around it (a third of a
typical 25 km/h): the reconstruction is the noisier reading. A risk curve
fitted on it is therefore flatter than the curve of the measured delta-V would
be (regression dilution). Integrating that curve once more over ``eps`` would
flatten it further and, the curve being convex where most crashes lie, raise
the average probability of every measured delta-V: on held-out crashes with
measurements drawn from this model, it over-predicted the weighted observed
rate 1.7 times (the first fit of 3.3.0, 2026-12-07). The served reading
integrates over what the measurement itself leaves open: the era's ratio (two
values) and the measurement's tolerance (:data:`MEASURED_TOLERANCE_SD`), by a
Gauss-Hermite rule of :data:`QUADRATURE_POINTS` points per era. For a measured
delta-V the answer has the right mean shift (a measured value reads ~1.25
times the reconstruction it stands for) and is, if anything, still too flat in
delta-V. Its spread over these points is the answer's ``unknown_inputs_range95``.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Final

import numpy as np
import numpy.typing as npt

from models.arrays import FloatArray
from models.field.risk_children import ChildRiskInputs
from models.field.risk_features import RiskInputs

__all__ = [
    "DeltaVSource",
    "EARLY_ERA_SHARE",
    "ERA_RATIOS",
    "LATE_ERA_FIRST_YEAR",
    "MEASURED_TOLERANCE_SD",
    "MEASUREMENT_MODEL",
    "QUADRATURE_POINTS",
    "SD_KMH",
    "MeasurementModel",
    "SourcedRiskInputs",
    "delta_v_source_of",
    "over_reconstructed_nodes",
    "reconstructed_nodes",
]


class DeltaVSource(StrEnum):
    """Where a notification's delta-V comes from."""

    MEASURED = "measured"  # the vehicle's sensors: EDR or telematics accelerometer
    RECONSTRUCTED = "reconstructed"  # from crush, as NASS-CDS (WinSMASH)


#: First accident year of the revised reconstruction code (WinSMASH 2007/2008,
#: vehicle-specific stiffness). [V] crash-data-and-triage.md.
LATE_ERA_FIRST_YEAR: Final[int] = 2007

#: Mean ratio reconstructed / measured by era: (up to 2006, from 2007). [V]
#: Niehoff & Gabler 2006 (23 % under), crash-data-and-triage.md (19 % under).
ERA_RATIOS: Final[tuple[float, float]] = (0.77, 0.81)

#: Standard deviation of reconstructed around its mean given measured, km/h. [V]
#: crash-data-and-triage.md (SD of the difference 8.6 km/h, n = 228).
SD_KMH: Final[float] = 8.6

#: Share of the fitted population's occupants (NASS-CDS 1997-2014, every
#: occupant with a known age, delta-V and ISS) in accident years before
#: :data:`LATE_ERA_FIRST_YEAR`: 35,960 of 53,113. [R] Counted from the data
#: (tests/models/offline/test_occupant_data.py holds it to the file).
EARLY_ERA_SHARE: Final[float] = 0.6770

#: Standard deviation of a measured delta-V around the vehicle's true delta-V, as a
#: share of it. [R] 49 CFR 563 Table III: delta-V accurate to +/-10 %, taken as two
#: standard deviations.
MEASURED_TOLERANCE_SD: Final[float] = 0.05

#: Gauss-Hermite points per era. [R] Three points integrate a polynomial of degree 5
#: exactly; over +/-1.7 SD (+/-9 %) the risk curve in delta-V is smooth, and each
#: point costs a row through the trees (32 donors x 6 nodes for an occupant of
#: unknown age with a measured delta-V).
QUADRATURE_POINTS: Final[int] = 3

#: Smallest reconstructed delta-V a node may take, km/h (the field models'
#: delta-V clamp: below it a notification is not a crash).
_MIN_KMH: Final[float] = 1.0


@dataclass(frozen=True)
class SourcedRiskInputs(ChildRiskInputs):
    """An occupant's field inputs with the source of the delta-V.

    Attributes
    ----------
    delta_v_source : DeltaVSource
        Measured by the vehicle (integrated over the reconstructions it allows,
        where the artifact has a measurement model) or reconstructed (taken as is).
    """

    delta_v_source: DeltaVSource = DeltaVSource.RECONSTRUCTED


def delta_v_source_of(inputs: RiskInputs) -> DeltaVSource:
    """The source of an occupant's delta-V (plain inputs: reconstructed, as fitted)."""
    if isinstance(inputs, SourcedRiskInputs):
        return inputs.delta_v_source
    return DeltaVSource.RECONSTRUCTED


@dataclass(frozen=True)
class MeasurementModel:
    """The measurement model's identity, as answers and stored cases name it."""

    name: str
    version: str

    @property
    def label(self) -> str:
        """``name@version``."""
        return f"{self.name}@{self.version}"


#: The measurement model served.
MEASUREMENT_MODEL: Final[MeasurementModel] = MeasurementModel("delta_v_measurement", "1.1.0")


def _gauss_hermite() -> tuple[FloatArray, FloatArray]:
    """Nodes and weights of E[g(Z)], Z ~ Normal(0, 1)."""
    x, w = np.polynomial.hermite.hermgauss(QUADRATURE_POINTS)
    return np.sqrt(2.0) * x, w / np.sqrt(np.pi)


def reconstructed_nodes(measured_kmh: float) -> tuple[FloatArray, FloatArray]:
    """Reconstructed delta-V values and their weights given a measured delta-V.

    Parameters
    ----------
    measured_kmh : float
        The vehicle's measured resultant delta-V, km/h.

    Returns
    -------
    values_kmh : ndarray, shape (2 * QUADRATURE_POINTS,)
        The reconstructed delta-V the measurement stands for, km/h (at least 1
        km/h), the early era's nodes first.
    weights : ndarray, shape (2 * QUADRATURE_POINTS,)
        Sum to 1.
    """
    z, w = _gauss_hermite()
    values, weights = [], []
    for ratio, share in zip(ERA_RATIOS, (EARLY_ERA_SHARE, 1.0 - EARLY_ERA_SHARE), strict=True):
        at = ratio * float(measured_kmh) * (1.0 + MEASURED_TOLERANCE_SD * z)
        values.append(np.maximum(at, _MIN_KMH))
        weights.append(share * w)
    return np.concatenate(values), np.concatenate(weights)


def over_reconstructed_nodes(
    arrays: dict[str, FloatArray | list[str]],
    owner: npt.NDArray[np.int64],
    weight: FloatArray,
    measured_kmh: dict[int, float],
) -> tuple[dict[str, FloatArray | list[str]], npt.NDArray[np.int64], FloatArray]:
    """Raw input rows with each measured occupant's rows expanded over the reconstructions.

    Parameters
    ----------
    arrays : dict of arrays, each shape (N,)
        Raw inputs (``delta_v_kmh`` among them), as :func:`models.field.unknowns.substitute`
        returns them.
    owner : ndarray of int, shape (N,)
        The occupant of each row.
    weight : ndarray, shape (N,)
        Each row's weight within its occupant (summing to 1 per occupant).
    measured_kmh : dict of int to float
        Occupant -> its measured delta-V, km/h (occupants not in it are taken as
        they are).

    Returns
    -------
    arrays, owner, weight
        Expanded: a measured occupant's row becomes ``2 * QUADRATURE_POINTS``
        rows, its delta-V the nodes of :func:`reconstructed_nodes` and its weight
        multiplied by theirs.
    """
    nodes = {i: reconstructed_nodes(v) for i, v in measured_kmh.items()}
    take: list[int] = []
    dv: list[float] = []
    w: list[float] = []
    for r, (o, wr) in enumerate(zip(owner.tolist(), weight.tolist(), strict=True)):
        if o in nodes:
            values, weights = nodes[o]
            take.extend([r] * values.size)
            dv.extend(values.tolist())
            w.extend((wr * weights).tolist())
        else:
            take.append(r)
            dv.append(float(np.asarray(arrays["delta_v_kmh"])[r]))
            w.append(wr)
    ix = np.asarray(take, dtype=np.int64)
    out: dict[str, FloatArray | list[str]] = {}
    for name, value in arrays.items():
        if isinstance(value, np.ndarray):
            out[name] = value[ix]
        else:
            out[name] = [value[i] for i in take]
    out["delta_v_kmh"] = np.asarray(dv, dtype=np.float64)
    return out, owner[ix], np.asarray(w, dtype=np.float64)
