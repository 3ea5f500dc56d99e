"""Request-path evaluation of the PCE surrogates (numpy only, no chaospy).

:meth:`SurrogateLibrary.load` reads and verifies the artifacts once;
:meth:`SurrogateFamily.propagate` turns the occupant sensor uncertainty into
95% intervals in a few milliseconds, with all bootstrap replicates.

Propagation (reference paper section 2.5)
----------------------------------------------------
* Sensor errors: posture and seat track readings are Gaussian with the given
  standard deviations (service default: 5 deg and 50 mm at 95%, i.e.
  ``5 / 1.96``), clipped to the model domain. A FIXED sample set of
  :data:`N_SENSOR_SAMPLES` standard-normal pairs (a Fibonacci lattice through
  the Box-Muller map: deterministic, low discrepancy) is used, so the same
  call always gives bit-identical output.
* A delta-V piece in which the head strikes the rigid interior in part of
  the design holds two sets of PCEs, one per side of the strike onset, and a
  gate PCE of the head's least clearance (mm) that picks the side at every
  point, blended over a few millimetres (:class:`_SplitPiece`).
* Each piece carries the Kriging of its point-PCE residuals on its design
  runs (PC-Kriging, :mod:`models.surrogate.kriging`): one kernel matrix of the
  sensor samples against the design and one matrix product, added on the
  fitted scale to the point PCE and every replicate (:class:`_KrigedPiece`).
* Delta-V, |angle from the mode axis| and pulse duration are taken as given
  (clamped to the design ranges; :attr:`UncertaintyResult.clamped_inputs`).
* P(ISS >= 15) is not read from its own PCE: at every sensor sample of every
  replicate it is computed from the surrogate measures by the assessment's
  risk curves and the exact ISS sum (:func:`models.injury.batch.p_iss15_batch`,
  with the occupant's age when known), so it is the same function of the
  measures as in a direct LPM case. [R] The P(ISS >= 15) PCE of the artifacts
  smooths the thresholds of a composite function: with it the held-out ISS15+
  agreement was 94.7-97.3 % in six families; from the measures it is 96.7 % in
  two and 98-100 % in the others, and the median |P error| is lower in 13
  families and equal (below 1e-4) in the rest (2026-12-01, same artifacts,
  REPORT.md Table B). The point value is the mean over
  the sensor distribution with the point PCEs; its 95% interval the 2.5 and
  97.5 percentiles of the same mean over the bootstrap replicates
  (model-adequacy uncertainty of the surrogate; each replicate's mean taken
  on a 24-sample subset as its deviation from the point PCEs there,
  :data:`_P_SUBSET`), widened by a held-out factor.
* Measures and ISS: the point value is the point PCE at the (clamped) readings;
  the 95% interval the 2.5 and 97.5 percentiles (order statistics, "inverted
  CDF") over all sensor samples and all bootstrap replicates (sensor and
  surrogate uncertainty together), widened on the fitted scale by the
  polynomial's own error, which the replicates do not see: a bound calibrated
  on the family's held-out LPM runs, added in quadrature on each side of the
  point value (:meth:`SurrogateFamily._interval_factors`).
* The evaluation is versioned (:data:`EVALUATION_VERSION`, with this module's
  checksum) and recorded with every case beside the artifacts' checksum.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path
from typing import Final

import models.injury.batch as _batch_module
from models.codehash import source_tree_sha256
from models.surrogate.family import SurrogateFamily
from models.surrogate.family_constants import (
    _NORMALS,
    DEFAULT_POSTURE_SD_DEG,
    DEFAULT_SEAT_TRACK_SD_MM,
    N_SENSOR_SAMPLES,
    UncertaintyResult,
)
from models.surrogate.library import SurrogateLibrary, default_artifact_dir

__all__ = [
    "_NORMALS",
    "EVALUATION_NAME",
    "EVALUATION_VERSION",
    "DEFAULT_POSTURE_SD_DEG",
    "DEFAULT_SEAT_TRACK_SD_MM",
    "N_SENSOR_SAMPLES",
    "SurrogateFamily",
    "SurrogateLibrary",
    "UncertaintyResult",
    "default_artifact_dir",
    "evaluation_sha256",
]


#: What turns the shipped artifacts into an answer (recorded with every case
#: beside the artifacts' manifest checksum, so that a change of the
#: propagation or of the interval calibration shows in the audit record).
EVALUATION_NAME: Final[str] = "PCE sensor-uncertainty propagation and interval calibration"
#: 1: bootstrap percentiles, P(ISS >= 15) interval widened by the held-out factor;
#: 2: the measure and ISS intervals extended by their held-out calibrated margins;
#: 3: P(ISS >= 15) from the surrogate measures through the risk curves (age-aware);
#: 4: delta-V pieces split at the head-strike onset, chosen by a gate PCE (format 4);
#: 5: the sensor-sample sums by a sparse product and one sensor basis per split
#: piece (summation order only: served values within 4e-12 relative of version
#: 4 at 480 random readings over the 24 families);
#: 6: the Kriging of each piece's residuals added to its PCEs (format 5,
#: models.surrogate.kriging);
#: 7: the gate of a split piece is a point PCE, evaluated alone (format 6).
EVALUATION_VERSION: Final[str] = "7"


#: Sources of the evaluation (the library, its families and pieces, their compiled
#: loops, and the batch risk they call).
_EVALUATION_SOURCES: Final[tuple[Path, ...]] = (
    Path(__file__),
    Path(__file__).with_name("family_constants.py"),
    Path(__file__).with_name("pieces.py"),
    Path(__file__).with_name("family.py"),
    Path(__file__).with_name("library.py"),
    Path(_batch_module.__file__),
    Path(_batch_module.__file__).with_name("batch_compiled.py"),
    Path(__file__).with_name("kriging.py"),
    Path(__file__).with_name("kernels.py"),
)


@lru_cache(maxsize=1)
def evaluation_sha256() -> str:
    """SHA-256 over the evaluation's sources (its checksum in a case record).

    Of the normalised syntax trees (:mod:`models.codehash`): docstrings and layout aside.
    """
    return source_tree_sha256(_EVALUATION_SOURCES)
