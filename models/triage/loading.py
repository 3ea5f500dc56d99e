"""Loading: every model the engine answers with, verified and warmed once at start,
and the checksum of the orchestration code itself (``triage_code``)."""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from dataclasses import field as dataclass_field
from functools import lru_cache
from pathlib import Path

from threadpoolctl import threadpool_limits  # type: ignore[import-untyped]

from models import ENGINE_VERSION
from models.baseline.logistic import BaselineModel, load_default
from models.constants import DEFAULT_POSTURE_SD_DEG, DEFAULT_SEAT_TRACK_SD_MM
from models.field.boosted import warm_up as _warm_up_forest
from models.field.risk_model import load_default as load_field_model
from models.field.versions import AnyFieldModel, load_field_artifact
from models.injury.batch_compiled import warm_up as _warm_up_p_iss
from models.lpm.fingerprint import lpm_code_sha256, sources_sha256
from models.lpm.params import ParameterSet, available_parameter_sets, load_parameter_set
from models.lpm.simulate import warm_up as _warm_up_lpm
from models.pulse import warm_up as _warm_up_pulse
from models.risk_calibration import (
    CALIBRATION_NAME,
    CALIBRATION_VERSION,
    calibration_sha256,
)
from models.surrogate.evaluate import (
    EVALUATION_NAME,
    EVALUATION_VERSION,
    SurrogateLibrary,
    default_artifact_dir,
    evaluation_sha256,
)
from models.surrogate.kernels import warm_up as _warm_up_surrogates
from models.tiers import HIGH_RISK_THRESHOLD, check_threshold_order
from models.triage.result import ModelInfo

__all__ = [
    "TRIAGE_SOURCES",
    "default_occupant_threads",
    "triage_code_sha256",
    "EngineModels",
    "operating_thresholds",
    "load_surrogates",
    "warm_up",
    "load_engine_models",
]


#: Sources (under models/) of the orchestration itself: how a notification becomes
#: model inputs and how the answers become a decision. Their checksum is recorded
#: with every case (``triage_code``), beside those of the models they call. The
#: package ``models/triage/`` counts whole: every module of it but its face
#: (``__init__``, re-exports only) and ``simulation.py`` (not on the answer's path),
#: in this fixed order (tests/models/triage/test_triage.py checks that none is left out).
#: A stored case keeps the checksum of the code that answered it. The field risk
#: model's evaluators (``field/risk_model.py``, ``field/boosted.py``) count: its
#: artifact names the model, this the code that evaluates it; so do the integration
#: over unknown inputs and the delta-V measurement model.
TRIAGE_SOURCES = (
    "triage/result.py",
    "triage/loading.py",
    "triage/decision.py",
    "triage/occupant_model.py",
    "triage/field_evidence.py",
    "triage/run.py",
    "tiers.py",
    "pulse.py",
    "pulse_plausibility.py",
    "impact_mode.py",
    "notification.py",
    "sensor_evidence.py",
    "lpm/domain.py",
    "field/risk_model.py",
    "field/boosted.py",
    "field/unknowns.py",
    "field/measurement.py",
)


@lru_cache(maxsize=1)
def measurement_code_sha256() -> str:
    """SHA-256 of the delta-V measurement model's code (``field/measurement.py``), computed
    once (at load: parsing source is not safe in many request threads at once)."""
    return sources_sha256(("field/measurement.py",))


@lru_cache(maxsize=1)
def triage_code_sha256() -> str:
    """SHA-256 over :data:`TRIAGE_SOURCES` (as :func:`models.lpm.fingerprint.sources_sha256`)."""
    return sources_sha256(TRIAGE_SOURCES)


#: Most occupants of one notification computed at once by default. [R] Much of
#: one occupant's occupant-model work (the LPM kernel, the surrogates' BLAS
#: products and compiled order statistics) releases the GIL: with two, a
#: two-occupant triage took 0.86 of one thread's wall time and 1.2 times its CPU
#: on this 2-core box when a core was free (``benchmarks/bench_occupant_threads.py``,
#: ``benchmarks/RESULTS.md``, "Speed (issue 51): where the time goes").
MAX_DEFAULT_OCCUPANT_THREADS = 2


def default_occupant_threads() -> int:
    """``min(2, CPU count)``: the occupants of a notification computed at once by default."""
    return min(MAX_DEFAULT_OCCUPANT_THREADS, os.cpu_count() or 1)


@dataclass(frozen=True)
class EngineModels:
    """Every model the engine answers with, loaded once at start.

    Attributes
    ----------
    baseline : BaselineModel
        The statistical baseline (always present).
    parameter_sets : Mapping[str, ParameterSet]
        Occupant-model parameter sets by vehicle model name.
    surrogates : SurrogateLibrary or None
        PCE surrogates for the confidence intervals; None: the interim interval
        from direct occupant-model runs over the sensor-uncertainty box.
    field : RiskModel or FieldModel or None
        The field model the decision is made with (the shipped ISS 15+
        :class:`models.field.risk_model.RiskModel`, or a MAIS 3+
        :class:`models.field.model.FieldModel` for recalls); None only for offline
        tools that compute the occupant models' answers alone
        (:func:`occupant_model_answers`): :func:`triage` needs it.
    operating_point : str or None
        Named operating point of the field model (None: the artifact's default).
    threshold_override : float or None
        Replaces the operating point's thresholds when set.
    high_threshold : float
        The high-risk tier's threshold on the field model's probability
        (:mod:`models.tiers`); never below an operating threshold in use.
    posture_sd_deg, seat_track_sd_mm : float
        Sensor standard deviations used when a notification gives none.
    occupant_threads : int
        Most occupants of one notification whose occupant models run at once
        (the calling thread and a process-wide pool of ``occupant_threads - 1``
        helpers, :func:`models.triage.run._evidences`); 1: one after the other.
        The answer is the same bits either way.
    """

    baseline: BaselineModel
    parameter_sets: Mapping[str, ParameterSet]
    surrogates: SurrogateLibrary | None = None
    field: AnyFieldModel | None = None
    operating_point: str | None = None
    threshold_override: float | None = None
    high_threshold: float = HIGH_RISK_THRESHOLD
    posture_sd_deg: float = DEFAULT_POSTURE_SD_DEG
    seat_track_sd_mm: float = DEFAULT_SEAT_TRACK_SD_MM
    occupant_threads: int = dataclass_field(default_factory=default_occupant_threads)

    def __post_init__(self) -> None:
        if self.occupant_threads < 1:
            raise ValueError(f"occupant_threads must be at least 1, not {self.occupant_threads}")

    @property
    def vehicle_models(self) -> frozenset[str]:
        """Vehicle parameter-set names a notification may name."""
        return frozenset(self.parameter_sets)

    def model_infos(self, vehicle_model: str | None = None) -> dict[str, ModelInfo]:
        """Versions and checksums: the baseline, and the occupant models of `vehicle_model`.

        With `vehicle_model` None, every loaded model.
        """
        b = self.baseline
        infos = {"baseline": ModelInfo(name=b.name, version=b.version, sha256=b.sha256)}
        if self.field is not None:
            f = self.field
            infos["field_model"] = ModelInfo(name=f.name, version=f.version, sha256=f.sha256)
            measurement = getattr(f, "measurement", None)
            if measurement is not None:  # the delta-V measurement model it reads through
                infos["delta_v_measurement"] = ModelInfo(
                    name=measurement.name,
                    version=measurement.version,
                    sha256=measurement_code_sha256(),
                )
        names = sorted(self.parameter_sets) if vehicle_model is None else [vehicle_model]
        for name in names:
            ps = self.parameter_sets[name]
            infos[f"lpm_parameters:{name}"] = ModelInfo(
                name=ps.name, version=name, sha256=ps.sha256
            )
        infos["lpm_code"] = ModelInfo(
            name="occupant LPMs and injury criteria",
            version=ENGINE_VERSION,
            sha256=lpm_code_sha256(),
        )
        infos["triage_code"] = _triage_code_info()
        infos["risk_calibration"] = ModelInfo(
            name=CALIBRATION_NAME, version=CALIBRATION_VERSION, sha256=calibration_sha256()
        )
        if self.surrogates is not None:
            infos["surrogates"] = ModelInfo(
                name="pce_surrogates",
                version=self.surrogates.version,
                sha256=self.surrogates.sha256,
            )
            infos["surrogate_evaluation"] = ModelInfo(
                name=EVALUATION_NAME, version=EVALUATION_VERSION, sha256=evaluation_sha256()
            )
        return infos


def operating_thresholds(
    field_model: AnyFieldModel, operating_point: str | None, threshold_override: float | None
) -> dict[str, float]:
    """The operating thresholds a field model decides with, by name (and crash mode where
    they differ by mode): the override alone when one is set."""
    if threshold_override is not None:
        return {"AACN_TRIAGE_THRESHOLD": threshold_override}
    name = operating_point or field_model.default_operating_point
    point = field_model.operating_points[name]
    if isinstance(point, float):  # the ISS 15+ risk model: one threshold per point
        by_knowledge = getattr(field_model, "knowledge_thresholds", {}).get(name, {})
        return {name: point} | {f"{name} ({k})": t for k, t in by_knowledge.items()}
    return {f"{name} ({mode.value})": t for mode, t in point.thresholds.items()}


def load_surrogates(directory: Path | None = None) -> SurrogateLibrary | None:
    """Load and verify the PCE surrogates; None when none are shipped.

    Raises
    ------
    ValueError
        When artifacts are present but fail verification (checksum mismatch, a
        file missing) or were built from other occupant-model code or parameters.
    """
    root = default_artifact_dir() if directory is None else directory
    if not (root / "manifest.json").is_file() and not any(root.glob("*.npz")):
        return None
    library = SurrogateLibrary.load(root)
    reason = library.stale_reason()
    if reason is not None:
        raise ValueError(f"surrogates are stale: {reason}; run `aacn-triage build-surrogates`")
    return library


def warm_up() -> None:
    """Compile (or load from the numba cache) every compiled loop of the request path:
    the pulse fit, the LPM kernels and measures, the surrogates' loops and their
    P(ISS >= 15), and the field risk model's forest of boosted trees."""
    _warm_up_pulse()
    _warm_up_lpm()
    _warm_up_surrogates()
    _warm_up_p_iss()
    _warm_up_forest()


def load_engine_models(
    threshold_override: float | None = None,
    *,
    operating_point: str | None = None,
    high_threshold: float = HIGH_RISK_THRESHOLD,
    field_artifact: Path | None = None,
    posture_sd_deg: float = DEFAULT_POSTURE_SD_DEG,
    seat_track_sd_mm: float = DEFAULT_SEAT_TRACK_SD_MM,
    surrogate_dir: Path | None = None,
    use_surrogates: bool = True,
    use_field: bool = True,
    warm: bool = True,
    blas_threads: int | None = 1,
    occupant_threads: int | None = None,
) -> EngineModels:
    """Load and verify the shipped model artifacts, and warm the compiled kernels.

    Also caps this process's BLAS threads at `blas_threads` (None: leaves them as
    they are). The engine's matrix products are small (the surrogate
    propagation's largest is 97 x 57 by 57 x 906, its kriging 97 x 5 by 5 x
    1000): on more than one thread OpenBLAS only adds hand-overs, and on a busy
    machine its spinning threads wait for cores. [R] Issue 51, the two-occupant
    notification of ``benchmarks/bench_speed.py`` on this 2-core box at load
    average 5-8: 134-187 ms per occupant with OpenBLAS's default of one thread
    per core, 16-20 ms with one (the service always capped them:
    ``service.context.limit_blas_threads``, measured there 2026-12-04). One
    thread is also what the service runs, so a triage in any process gives the
    service's bits.

    `occupant_threads` (None: :func:`default_occupant_threads`) is how many
    occupants of one notification run their occupant models at once
    (:attr:`EngineModels.occupant_threads`).

    Raises
    ------
    ValueError
        When an artifact is missing, malformed, altered, or does not match the
        code, or `operating_point` is not one the field model defines.
    ThresholdOrderError
        (a ValueError) When `high_threshold` lies below an operating threshold in use.
    """
    if blas_threads is not None:
        threadpool_limits(limits=blas_threads, user_api="blas")
    field_model: AnyFieldModel | None = None
    if use_field:
        field_model = (
            load_field_model() if field_artifact is None else load_field_artifact(field_artifact)
        )
    if (
        field_model is not None
        and operating_point is not None
        and operating_point not in field_model.operating_points
    ):
        raise ValueError(
            f"unknown operating point {operating_point!r}; the field model defines "
            + ", ".join(sorted(field_model.operating_points))
        )
    if field_model is not None:
        check_threshold_order(
            high_threshold, operating_thresholds(field_model, operating_point, threshold_override)
        )
    surrogates = load_surrogates(surrogate_dir) if use_surrogates else None
    parameter_sets = {name: load_parameter_set(name) for name in available_parameter_sets()}
    # the code checksums recorded with every case are computed here, once (they parse
    # source; CPython 3.11's parser is not safe to run from several threads at once)
    lpm_code_sha256()
    triage_code_sha256()
    measurement_code_sha256()
    evaluation_sha256()
    if warm:
        warm_up()
    if occupant_threads is None:
        occupant_threads = default_occupant_threads()
    return EngineModels(
        baseline=load_default(),
        parameter_sets=parameter_sets,
        surrogates=surrogates,
        field=field_model,
        operating_point=operating_point,
        threshold_override=threshold_override,
        high_threshold=high_threshold,
        posture_sd_deg=posture_sd_deg,
        seat_track_sd_mm=seat_track_sd_mm,
        occupant_threads=occupant_threads,
    )


def _triage_code_info() -> ModelInfo:
    return ModelInfo(
        name="notification-to-answer orchestration (pulse, impact mode, sensor evidence, decision)",
        version=ENGINE_VERSION,
        sha256=triage_code_sha256(),
    )
