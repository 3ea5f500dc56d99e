"""The delta-V a vehicle measures, read on the scale of the delta-V the field data reconstructed.

The field risk models learned from NASS-CDS delta-V, which investigators
reconstructed after the crash from the vehicle's crush (WinSMASH). A
notification carries the delta-V the vehicle's own sensors measured (the
airbag control module's EDR record, the telematics unit's accelerometer). The
two differ, and this module is the relation between them: the measurement
model, versioned (:data:`MEASUREMENT_MODELS`; an artifact names the version it
was checked with, and answers and stored cases name it), every coefficient
with its source.

Reconstructed given measured, for a crash of direction ``d`` (longitudinal:
frontal or rear; side)::

    reconstructed = f_d * measured + eps,     eps ~ Normal(0, SD_KMH)

The served reading takes the reconstruction a measurement stands for,
``f_d * measured``, over the measurement's own tolerance (below), not over
``eps``: ``eps`` is the reconstruction's own noise, which the field risk curves
already carry (they were fitted on reconstructions).

Version 1.2.0 (served):

- ``f`` for a longitudinal (frontal or rear) crash: 0.796, the mean of the two
  NASS-CDS comparisons with EDRs weighted by their cases. [V] Niehoff & Gabler
  2006 (Annu Proc AAAM 50; PMC3217484): 121 NASS-CDS 2000-2003 cases, WinSMASH
  23 % under the EDR. [V] Funk, Cormier & Gabler 2008 (Annu Proc AAAM 52:
  155-164): 228 NASS-CDS single-event frontal crashes, NASS delta-V 19 % under
  the EDR, SD of the difference 8.6 km/h (the figure
  ``../shared/reference/crash-data-and-triage.md`` cites). [R] Rear crashes
  take the frontal ratio: no comparison of rear crashes was found.
- ``f`` for a side crash (the delta-V's direction within 45 degrees of either
  side, the sectors :func:`models.field.risk_features.crash_mode_codes` calls
  side): 0.979. [V] Johnson & Gabler (Traffic Injury Prevention; N. Johnson,
  MS thesis, Virginia Tech 2011, "Assessment of Crash Energy-Based Side Impact
  Reconstruction Accuracy"): in single-event NASS-CDS side crashes with biaxial
  EDR data, WinSMASH over-estimates the EDR's delta-V at common velocity (the
  EDR's divided by 1.10, an assumed restitution of 10 %) by 12.9 % for cars
  struck by cars and 2.4 % for cars struck by light trucks and vans. On the
  EDR's own scale that is 1.129 / 1.10 = 1.026 and 1.024 / 1.10 = 0.931. [R]
  Their mean, the two striking kinds taken as equally common (the case counts
  were not at hand).
- The reconstruction era. The two longitudinal comparisons are of the early
  code (categorical stiffness, accident years up to 2006). WinSMASH 2007/2008
  and 2010 (vehicle-specific stiffness, NHTSA DOT HS 811 546) reconstruct the
  later years; Niehoff & Gabler found vehicle-specific stiffness improved the
  longitudinal estimate, but no comparison of the revised code with EDRs was
  found, so one ratio is used for every year. [R]
- By vehicle class: Niehoff & Gabler report pickups 3 % under and
  front-wheel-drive cars 31 % under with categorical stiffness, but a
  notification carries no body class or drive layout: the ratio is the mean
  over the studies' mix. [R]
- ``SD_KMH`` = 8.6 km/h (Funk et al. 2008, frontal). [R] Taken for side crashes
  too (their scatter was not at hand). The served reading does not integrate
  over it (below); the offline consistency check uses it.

Version 1.1.0 (field model 3.3.0, kept so that it still loads): the era's
ratio (0.77 up to 2006, 0.81 from 2007, mixed 67.7/32.3 by the population's
years) for every direction; it read a measured side crash 20 % low against
Johnson & Gabler.

**Which reading is the noisier decides the direction.** Part 563 requires the
EDR's delta-V within +/-10 % (49 CFR 563 Table III, ``crash-data-and-triage.md``
2.5), while the reconstruction scatters by 8.6 km/h around it (a third of a
typical 25 km/h): the reconstruction is the noisier reading. Funk et al.
treated it so: correcting NASS risk curves for the bias moved them to higher
delta-V, and for the scatter (a deconvolution) moved them back part of the way.
A risk curve fitted on the reconstruction is therefore flatter than the curve
of the measured delta-V would be (regression dilution). Integrating that curve
once more over ``eps`` would flatten it further and, the curve being convex
where most crashes lie, raise the average probability of every measured
delta-V: on held-out crashes with measurements drawn from this model, it
over-predicted the weighted observed rate 1.7 times (the first fit of field
model 3.3.0, 2026-12-07). The served reading integrates over what the
measurement itself leaves open: its tolerance (:data:`MEASURED_TOLERANCE_SD`),
by a Gauss-Hermite rule of :data:`QUADRATURE_POINTS` points (per era, for
1.1.0). For a measured delta-V the answer has the right mean shift and is, if
anything, still too flat in delta-V (Funk et al.'s scatter correction). Its
spread over these points is part of the answer's ``unknown_inputs_range95``.
"""

from __future__ import annotations

import functools
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
    "LONGITUDINAL_RATIO",
    "MEASUREMENT_MODEL",
    "MEASUREMENT_MODELS",
    "QUADRATURE_POINTS",
    "SD_KMH",
    "SIDE_RATIO",
    "SIDE_SECTORS_DEG",
    "MeasurementModel",
    "SourcedRiskInputs",
    "delta_v_source_of",
    "is_side",
    "over_reconstructed_nodes",
    "reconstructed_nodes",
]


class DeltaVSource(StrEnum):
    """Where a notification's delta-V comes from."""

    MEASURED = "measured"  # the vehicle's sensors: EDR or telematics accelerometer
    RECONSTRUCTED = "reconstructed"  # from crush, as NASS-CDS (WinSMASH)


#: First accident year of the revised reconstruction code (WinSMASH 2007/2008,
#: vehicle-specific stiffness). [V] crash-data-and-triage.md. (Version 1.1.0.)
LATE_ERA_FIRST_YEAR: Final[int] = 2007

#: Mean ratio reconstructed / measured by era: (up to 2006, from 2007). [V]
#: Niehoff & Gabler 2006 (23 % under), crash-data-and-triage.md (19 % under).
#: (Version 1.1.0, every direction.)
ERA_RATIOS: Final[tuple[float, float]] = (0.77, 0.81)

#: Cases of the two longitudinal comparisons: Niehoff & Gabler 2006 (121, all
#: directions, mostly frontal) and Funk, Cormier & Gabler 2008 (228, frontal). [V]
_LONGITUDINAL_CASES: Final[tuple[int, int]] = (121, 228)

#: Mean ratio reconstructed / measured of a longitudinal (frontal or rear) crash:
#: the two comparisons' ratios (0.77, 0.81) weighted by their cases, 0.796. [V]
#: (module docstring; version 1.2.0).
LONGITUDINAL_RATIO: Final[float] = round(
    (_LONGITUDINAL_CASES[0] * ERA_RATIOS[0] + _LONGITUDINAL_CASES[1] * ERA_RATIOS[1])
    / sum(_LONGITUDINAL_CASES),
    3,
)

#: Restitution Johnson & Gabler assumed to put the EDR's delta-V at common
#: velocity (the EDR's divided by 1 + 0.10). [V]
_SIDE_STUDY_RESTITUTION: Final[float] = 0.10

#: WinSMASH over the EDR's common-velocity delta-V in side crashes: cars struck by
#: cars 1.129, by light trucks and vans 1.024. [V] Johnson & Gabler.
_SIDE_STUDY_RATIOS: Final[tuple[float, float]] = (1.129, 1.024)

#: Mean ratio reconstructed / measured of a side crash, on the EDR's own scale:
#: the mean of 1.129 / 1.10 and 1.024 / 1.10, 0.979. [V] figures, [R] the mean
#: (module docstring; version 1.2.0).
SIDE_RATIO: Final[float] = round(
    sum(_SIDE_STUDY_RATIOS) / len(_SIDE_STUDY_RATIOS) / (1.0 + _SIDE_STUDY_RESTITUTION), 3
)

#: Side sectors of the delta-V's direction, deg clockwise from ahead: the right
#: side [45, 135) and the left [225, 315), as
#: :func:`models.field.risk_features.crash_mode_codes` has them.
SIDE_SECTORS_DEG: Final[tuple[tuple[float, float], ...]] = ((45.0, 135.0), (225.0, 315.0))

#: Standard deviation of reconstructed around its mean given measured, km/h. [V]
#: Funk, Cormier & Gabler 2008 (SD of the difference 8.6 km/h, n = 228, frontal).
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
    """A version of the measurement model: its identity and its ratios.

    Attributes
    ----------
    name, version : str
        As answers and stored cases name it.
    longitudinal, side : tuple of (ratio, share)
        The ratios reconstructed / measured of a longitudinal and of a side crash,
        each with its share (summing to 1): one pair, or one per reconstruction era.
    tolerance_sd : float
        The measurement's own SD, a share of it.
    quadrature_points : int
        Gauss-Hermite points per ratio.
    """

    name: str
    version: str
    longitudinal: tuple[tuple[float, float], ...]
    side: tuple[tuple[float, float], ...]
    tolerance_sd: float = MEASURED_TOLERANCE_SD
    quadrature_points: int = QUADRATURE_POINTS

    @property
    def label(self) -> str:
        """``name@version``."""
        return f"{self.name}@{self.version}"

    def ratios(self, pdof_deg: float) -> tuple[tuple[float, float], ...]:
        """The (ratio, share) pairs of a crash whose delta-V points along `pdof_deg`."""
        return self.side if is_side(pdof_deg) else self.longitudinal

    def mean_ratio(self, pdof_deg: float) -> float:
        """The mean ratio reconstructed / measured of a crash along `pdof_deg`."""
        return float(sum(r * w for r, w in self.ratios(pdof_deg)))

    def document(self) -> dict[str, object]:
        """The artifact's ``measurement_model`` block."""
        return {
            "name": self.name,
            "version": self.version,
            "longitudinal": [list(p) for p in self.longitudinal],
            "side": [list(p) for p in self.side],
            "side_sectors_deg": [list(s) for s in SIDE_SECTORS_DEG],
            "sd_kmh": SD_KMH,
            "measured_tolerance_sd": self.tolerance_sd,
            "quadrature_points": self.quadrature_points,
        }


def is_side(pdof_deg: float) -> bool:
    """Whether a delta-V along `pdof_deg` (deg clockwise from ahead) is a side crash's."""
    p = float(pdof_deg) % 360.0
    return any(lo <= p < hi for lo, hi in SIDE_SECTORS_DEG)


_ERAS_1_1: Final[tuple[tuple[float, float], ...]] = (
    (ERA_RATIOS[0], EARLY_ERA_SHARE),
    (ERA_RATIOS[1], 1.0 - EARLY_ERA_SHARE),
)

#: Every version an artifact may name, by version.
MEASUREMENT_MODELS: Final[dict[str, MeasurementModel]] = {
    "1.1.0": MeasurementModel("delta_v_measurement", "1.1.0", _ERAS_1_1, _ERAS_1_1),
    "1.2.0": MeasurementModel(
        "delta_v_measurement", "1.2.0", ((LONGITUDINAL_RATIO, 1.0),), ((SIDE_RATIO, 1.0),)
    ),
}

#: The measurement model new fits are checked with (the served artifact names it).
MEASUREMENT_MODEL: Final[MeasurementModel] = MEASUREMENT_MODELS["1.2.0"]


@functools.cache
def _gauss_hermite(points: int) -> tuple[FloatArray, FloatArray]:
    """Nodes and weights of E[g(Z)], Z ~ Normal(0, 1) (read-only; computed once per size:
    numpy's eigenvalue solution cost about 0.3 ms per occupant whose delta-V was measured)."""
    x, w = np.polynomial.hermite.hermgauss(points)
    nodes, weights = np.sqrt(2.0) * x, w / np.sqrt(np.pi)
    nodes.flags.writeable = False
    weights.flags.writeable = False
    return nodes, weights


def reconstructed_nodes(
    measured_kmh: float, pdof_deg: float = 0.0, model: MeasurementModel = MEASUREMENT_MODEL
) -> tuple[FloatArray, FloatArray]:
    """Reconstructed delta-V values and their weights given a measured delta-V.

    Parameters
    ----------
    measured_kmh : float
        The vehicle's measured resultant delta-V, km/h.
    pdof_deg : float
        Its direction, deg clockwise from ahead (side or longitudinal).
    model : MeasurementModel
        The version the artifact names.

    Returns
    -------
    values_kmh : ndarray, shape (n_ratios * quadrature_points,)
        The reconstructed delta-V the measurement stands for, km/h (at least 1
        km/h), ratio by ratio.
    weights : ndarray, shape (n_ratios * quadrature_points,)
        Sum to 1.
    """
    z, w = _gauss_hermite(model.quadrature_points)
    values, weights = [], []
    for ratio, share in model.ratios(pdof_deg):
        at = ratio * float(measured_kmh) * (1.0 + model.tolerance_sd * z)
        values.append(np.maximum(at, _MIN_KMH))
        weights.append(share * w)
    return np.concatenate(values), np.concatenate(weights)


def over_reconstructed_nodes(
    arrays: dict[str, FloatArray | list[str]],
    owner: npt.NDArray[np.int64],
    weight: FloatArray,
    measured_kmh: dict[int, float],
    model: MeasurementModel = MEASUREMENT_MODEL,
) -> tuple[dict[str, FloatArray | list[str]], npt.NDArray[np.int64], FloatArray]:
    """Raw input rows with each measured occupant's rows expanded over the reconstructions.

    Parameters
    ----------
    arrays : dict of arrays, each shape (N,)
        Raw inputs (``delta_v_kmh`` and ``pdof_deg`` among them), as
        :func:`models.field.unknowns.substitute` returns them.
    owner : ndarray of int, shape (N,)
        The occupant of each row.
    weight : ndarray, shape (N,)
        Each row's weight within its occupant (summing to 1 per occupant).
    measured_kmh : dict of int to float
        Occupant -> its measured delta-V, km/h (occupants not in it are taken as
        they are).
    model : MeasurementModel
        The version the artifact names.

    Returns
    -------
    arrays, owner, weight
        Expanded: a measured occupant's row becomes the nodes of
        :func:`reconstructed_nodes` (of its own direction), its weight multiplied by
        theirs.
    """
    pdof = np.asarray(arrays["pdof_deg"], dtype=np.float64)
    nodes: dict[tuple[int, float], tuple[FloatArray, FloatArray]] = {}
    take: list[int] = []
    dv: list[float] = []
    w: list[float] = []
    for r, (o, wr) in enumerate(zip(owner.tolist(), weight.tolist(), strict=True)):
        if o in measured_kmh:
            key = (o, float(pdof[r]))
            if key not in nodes:
                nodes[key] = reconstructed_nodes(measured_kmh[o], key[1], model)
            values, weights = nodes[key]
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
