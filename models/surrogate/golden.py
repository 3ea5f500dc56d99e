"""What the surrogates depend on, checked by running it: golden occupant-model cases.

A surrogate family is a fit of direct occupant-model runs. It stays valid as
long as the occupant models give the same answers and read the same parameter
values, however the code is written. So the library records, when it is built,
the parameter set's values checksum and the outputs of a few *golden cases* (a
direct run per family at fixed inputs, :func:`golden_inputs`); at start the
service reruns those cases and compares (:func:`golden_mismatch`). A docstring,
a reformat, a file move or a refactor that keeps the numbers leaves the
artifacts current; a change of physics that moves a golden output, or of any
parameter value, makes them stale and the service not ready, with the reason.

The direct run of a family at a design point (:func:`family_run`: a haversine
pulse along the PDOF, as the build sampled it) is the one the offline build
uses too, so the golden cases are the build's own runs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any, Final

import numpy as np

from models.impact_mode import ImpactMode
from models.lpm.params import ParameterSet
from models.lpm.simulate import LpmResult, simulate
from models.notification import AirbagState, Occupant, Seat
from models.pulse import haversine, haversine_amplitude_g
from models.surrogate.spec import INPUT_NAMES, FamilySpec

__all__ = [
    "GOLDEN_DELTA_V_KMH",
    "GOLDEN_REL_TOL",
    "PULSE_RATE_HZ",
    "SIMULATED_S",
    "family_outputs",
    "family_run",
    "golden_inputs",
    "golden_mismatch",
    "golden_record",
    "parameter_values_sha256",
]


#: Sampling rate of the haversine pulses fed to the LPM, Hz (the service's
#: models.pulse.DEFAULT_OUTPUT_RATE_HZ).
PULSE_RATE_HZ: Final[float] = 10_000.0
#: Simulated duration, s (models.lpm.simulate default).
SIMULATED_S: Final[float] = 0.2
#: Mode axis (deg clockwise) for an occupant on the right (models.impact_mode).
_AXIS_DEG: Final[Mapping[str, float]] = {
    "frontal": 0.0,
    "near_side": 90.0,
    "rear": 180.0,
    "far_side": 270.0,
}

#: Delta-V of the golden cases, km/h: mid-severity, inside every family's range.
GOLDEN_DELTA_V_KMH: Final[float] = 35.0
#: Relative tolerance of a golden output (absolute for P(ISS >= 15) and ISS).
#: The same code on another CPU (other SIMD, FMA and libm code paths) moved
#: held-out LPM outputs by up to 5.7e-4 relative (tests/tolerance.py); a change
#: of physics smaller than this on every golden case goes unnoticed, a change of
#: any parameter value does not (its checksum).
GOLDEN_REL_TOL: Final[float] = 2e-3


def parameter_values_sha256(params: ParameterSet) -> str:
    """SHA-256 of the parameter set's values (:attr:`ParameterSet.values_sha256`)."""
    return params.values_sha256


def family_run(spec: FamilySpec, x: Sequence[float], params: ParameterSet) -> LpmResult:
    """The direct occupant-model run of a family at one design point.

    Parameters
    ----------
    spec : FamilySpec
    x : sequence of float, length 5
        Inputs per :data:`models.surrogate.spec.INPUT_NAMES`: delta-V (km/h),
        angle from the mode's axis (deg), lumbar flexion (deg), seat track (mm),
        haversine duration (ms).
    params : ParameterSet

    Returns
    -------
    LpmResult
    """
    dv, ang, posture, seat, dur = (float(v) for v in x)
    occupant = Occupant(
        seat=Seat.DRIVER,
        body=spec.body,
        belted=spec.belted,
        frontal_airbag=(
            AirbagState.DEPLOYED
            if spec.mode is ImpactMode.FRONTAL and spec.airbag_deployed
            else AirbagState.NOT_DEPLOYED
        ),
        side_airbag=(
            AirbagState.DEPLOYED
            if spec.mode is ImpactMode.NEAR_SIDE and spec.airbag_deployed
            else AirbagState.ABSENT
        ),
    )
    t = np.arange(int(round(SIMULATED_S * PULSE_RATE_HZ)) + 1) / PULSE_RATE_HZ
    tsec = dur / 1000.0
    h = haversine(t, haversine_amplitude_g(dv, tsec), tsec)
    pdof = np.radians(_AXIS_DEG[spec.mode.value] + ang)
    occ = replace(occupant, posture_lumbar_flexion_deg=posture, seat_track_mm=seat)
    return simulate(
        t,
        -np.cos(pdof) * h,
        -np.sin(pdof) * h,
        spec.mode,
        occ,
        params,
        angle_deg=ang,
        duration_s=SIMULATED_S,
    )


def family_outputs(spec: FamilySpec, result: LpmResult) -> dict[str, float]:
    """The family's outputs of a run (NaN where the run failed or a measure is absent)."""
    out = {}
    for name in spec.outputs:
        if result.status < 0 or result.assessment is None:
            out[name] = math.nan
        elif name == "p_iss15":
            out[name] = float(result.assessment.p_iss15)
        elif name == "iss":
            out[name] = float(result.assessment.iss)
        else:
            v = getattr(result.measures, name)
            out[name] = math.nan if v is None else float(v)
    return out


def golden_inputs(spec: FamilySpec) -> tuple[float, ...]:
    """The golden point of a family: :data:`GOLDEN_DELTA_V_KMH`, the other inputs mid-range."""
    mid = [0.5 * (lo + hi) for lo, hi in spec.ranges]
    mid[INPUT_NAMES.index("delta_v_kmh")] = GOLDEN_DELTA_V_KMH
    return tuple(mid)


def golden_record(specs: Sequence[FamilySpec], params: ParameterSet) -> dict[str, Any]:
    """The golden cases of `specs` run now: what a manifest records at build time."""
    cases = {}
    for spec in specs:
        x = golden_inputs(spec)
        cases[spec.name] = {
            "inputs": list(x),
            "outputs": family_outputs(spec, family_run(spec, x, params)),
        }
    return {
        "rel_tol": GOLDEN_REL_TOL,
        "parameter_values_sha256": parameter_values_sha256(params),
        "cases": cases,
    }


def _differs(name: str, recorded: float, now: float, tol: float) -> bool:
    if math.isnan(recorded) or math.isnan(now):
        return math.isnan(recorded) != math.isnan(now)
    if name in ("p_iss15", "iss"):
        return abs(now - recorded) > tol * (1.0 if name == "p_iss15" else 10.0)
    return abs(now - recorded) > tol * max(abs(recorded), 1e-9)


def golden_mismatch(
    record: Mapping[str, Any], specs: Mapping[str, FamilySpec], params: ParameterSet
) -> str | None:
    """Why the occupant models no longer give the recorded golden answers, or None.

    Parameters
    ----------
    record : Mapping
        :func:`golden_record` as stored in the manifest.
    specs : Mapping[str, FamilySpec]
        The families by name.
    params : ParameterSet
        The parameter set the service runs.

    Returns
    -------
    str or None
        The first difference (parameter values, or a golden output with its
        recorded and current value).
    """
    if record.get("parameter_values_sha256") != parameter_values_sha256(params):
        return "the LPM parameter values differ from those the surrogates were built with"
    tol = float(record.get("rel_tol", GOLDEN_REL_TOL))
    for name, case in sorted(record["cases"].items()):
        spec = specs.get(name)
        if spec is None:
            return f"golden case {name}: no such family"
        now = family_outputs(spec, family_run(spec, case["inputs"], params))
        for out, value in case["outputs"].items():
            if _differs(out, float(value), now.get(out, math.nan), tol):
                return (
                    f"the occupant models' physics changed: golden case {name}, {out} "
                    f"{now.get(out, math.nan):.6g} now against {float(value):.6g} when built"
                )
    return None
