"""Direct LPM runs of the surrogate families and how surrogates are scored against them.

Shared by the build (:mod:`.build`), its report (:mod:`.report`) and the fresh
validation (:mod:`.validate`), which import this module and not each other's
helpers: the offline surrogate tools form no import cycle.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from models.arrays import FloatArray
from models.impact_mode import ImpactMode
from models.surrogate.golden import PULSE_RATE_HZ, SIMULATED_S, family_outputs, family_run
from models.surrogate.spec import FamilySpec

__all__ = [
    "ISS15_DECISION_PROBABILITY",
    "PULSE_RATE_HZ",
    "SIMULATED_S",
    "LpmRuns",
    "heldout_scores",
    "lpm_outputs",
    "lpm_runs",
    "relative_error",
    "service_raw_threshold",
]


#: An ISS15+ decision from a probability: P(ISS >= 15) >= 0.5 (the more likely class).
ISS15_DECISION_PROBABILITY = 0.5


@dataclass(frozen=True)
class LpmRuns:
    """Direct LPM runs at the points of a design.

    Attributes
    ----------
    y : ndarray, shape (n, n_outputs)
        Physical values of the family's outputs (NaN where the run failed).
    status : ndarray of int64, shape (n,)
    head_clearance_mm : ndarray, shape (n,)
        :func:`models.lpm.simulate.head_clearance_mm` of each run (NaN where it failed).
    """

    y: FloatArray
    status: npt.NDArray[np.int64]
    head_clearance_mm: FloatArray


def lpm_outputs(
    spec: FamilySpec, x: npt.ArrayLike, params: Any = None
) -> tuple[FloatArray, npt.NDArray[np.int64]]:
    """Direct LPM runs at raw input points of a family (outputs and status).

    See :func:`lpm_runs`.
    """
    runs = lpm_runs(spec, x, params)
    return runs.y, runs.status


def lpm_runs(spec: FamilySpec, x: npt.ArrayLike, params: Any = None) -> LpmRuns:
    """Direct LPM runs at raw input points of a family.

    Each run is :func:`models.surrogate.golden.family_run` (the haversine pulse
    along the PDOF that the service's golden cases use too).

    Parameters
    ----------
    spec : FamilySpec
    x : array_like, shape (n, 5)
        Columns of :data:`models.surrogate.spec.INPUT_NAMES` (km/h, deg, deg, mm, ms).
    params : ParameterSet, optional
        Default: ``load_parameter_set()``.

    Returns
    -------
    LpmRuns
    """
    from models.lpm.params import load_parameter_set
    from models.lpm.simulate import head_clearance_mm

    ps = load_parameter_set() if params is None else params
    xv = np.atleast_2d(np.asarray(x, dtype=np.float64))
    y = np.full((xv.shape[0], len(spec.outputs)), np.nan)
    status = np.zeros(xv.shape[0], dtype=np.int64)
    clearance = np.full(xv.shape[0], np.nan)
    for i, point in enumerate(xv):
        r = family_run(spec, point, ps)
        status[i] = r.status
        if r.status < 0 or r.assessment is None:
            continue
        clearance[i] = head_clearance_mm(r)
        outputs = family_outputs(spec, r)
        y[i] = [outputs[name] for name in spec.outputs]
    return LpmRuns(y, status, clearance)


def relative_error(y_pred: npt.ArrayLike, y_true: npt.ArrayLike) -> FloatArray:
    """|y_pred - y_true| / |y_true| elementwise (a zero true value divides by 1e-12)."""
    a = np.asarray(y_true, dtype=np.float64)
    b = np.asarray(y_pred, dtype=np.float64)
    return np.asarray(np.abs(b - a) / np.maximum(np.abs(a), 1e-12), dtype=np.float64)


def heldout_scores(spec: FamilySpec, y_true: FloatArray, y_pred: FloatArray) -> dict[str, Any]:
    """Surrogate against direct LPM values on held-out points (REPORT.md Table B).

    Parameters
    ----------
    spec : FamilySpec
    y_true, y_pred : ndarray, shape (n, n_outputs)
        Direct LPM and surrogate values of ``spec.outputs`` (rows with a NaN
        LPM value are skipped).

    Returns
    -------
    dict
        ``n``; per measure the median and 90th percentile relative error and
        R^2; per score (P(ISS >= 15), ISS) the median absolute error and R^2;
        the ISS15+ decision agreement from P (>= 0.5) and from the ISS (>= 15);
        the LPM's ISS15+ share.
    """
    ok = np.all(np.isfinite(y_true), axis=1)
    yt, yp = y_true[ok], y_pred[ok]
    out: dict[str, Any] = {"n": int(ok.sum())}
    for j, name in enumerate(spec.outputs):
        a, b = yt[:, j], yp[:, j]
        if name in ("p_iss15", "iss"):
            err = np.abs(b - a)
            out[name] = {"median_abs_error": float(np.median(err))}
        else:
            rel = relative_error(b, a)
            out[name] = {
                "median_rel_error": float(np.median(rel)),
                "p90_rel_error": float(np.quantile(rel, 0.9)),
            }
        ss = float(np.sum((a - a.mean()) ** 2))
        out[name]["r2"] = float(1.0 - np.sum((b - a) ** 2) / ss) if ss > 0 else 1.0
    jp = spec.outputs.index("p_iss15")
    ji = spec.outputs.index("iss")
    thr = ISS15_DECISION_PROBABILITY
    out["decision_agreement_p"] = float(np.mean((yt[:, jp] >= thr) == (yp[:, jp] >= thr)))
    out["decision_agreement_iss"] = float(np.mean((yt[:, ji] >= 15) == (yp[:, ji] >= 15)))
    out["iss15_share_lpm"] = float(np.mean(yt[:, ji] >= 15))
    return out


def service_raw_threshold(family_name: str, outputs: Sequence[str]) -> float:
    """The service's decision threshold for a family, on the uncorrected P(ISS >= 15).

    The service decides on (P - P0) / (1 - P0) >= t (``models.risk_calibration``,
    ``models.triage.LPM_THRESHOLDS``), i.e. on P >= P0 + t (1 - P0), with P0 the
    zero-load probability of the family's body, mode and measures (default age,
    as the surrogates are built).
    """
    from models.injury.assessment import InjuryMeasures
    from models.notification import Body
    from models.risk_calibration import zero_load_probability
    from models.triage import LPM_THRESHOLDS  # the service's decision thresholds

    mode_name, body_name = family_name.split("__")[:2]
    mode = ImpactMode(mode_name)
    fields = {f.name for f in dataclasses.fields(InjuryMeasures)}
    present = InjuryMeasures(**dict.fromkeys((o for o in outputs if o in fields), 0.0))
    p0 = zero_load_probability(present, Body(body_name), None, mode)
    t = LPM_THRESHOLDS[mode]
    return p0 + t * (1.0 - p0)
