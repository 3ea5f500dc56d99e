"""The run: one notification in, one triage result out (see :mod:`models.triage`)."""

from __future__ import annotations

import dataclasses
import os
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor

from models import ENGINE_VERSION
from models.assumptions import Assumption, AssumptionCode
from models.field.features import FieldMode
from models.field.risk_model import RiskModel, RiskPrediction
from models.notification import (
    CrashNotification,
    Occupant,
)
from models.pulse import ProcessedPulse, process_pulse
from models.tiers import child_recommendation, tier_of
from models.triage.decision import (
    _field_decision,
    _risk_decision,
    _risk_threshold,
    _worst,
    flagged_for_corrupt_record,
)
from models.triage.field_evidence import (
    OccupantEvidence,
    _field_assumptions,
    _occupant_evidence,
    _risk_assumptions,
    delta_v_source,
    risk_inputs,
)
from models.triage.loading import EngineModels
from models.triage.result import (
    Method,
    ModelInfo,
    OccupantTriage,
    TriageDecision,
    TriageResult,
    UnknownVehicleModel,
    VehicleRiskAnswer,
)

__all__ = ["triage"]


#: The helper threads the occupants of a notification share (with the calling
#: thread), by size, in this process; made on first use. Keyed by the process id
#: as well: a forked child (the batch's worker processes) inherits a pool object
#: whose threads it does not have, and makes its own.
_POOLS: dict[tuple[int, int], ThreadPoolExecutor] = {}
_POOLS_LOCK = threading.Lock()


def _helper_pool(helpers: int) -> ThreadPoolExecutor:
    """The process's pool of `helpers` threads (one per size, shared by every request)."""
    key = (os.getpid(), helpers)
    with _POOLS_LOCK:
        pool = _POOLS.get(key)
        if pool is None:
            pool = ThreadPoolExecutor(max_workers=helpers, thread_name_prefix="aacn-occupant")
            _POOLS[key] = pool
    return pool


def _after_fork_in_child() -> None:
    global _POOLS_LOCK
    _POOLS_LOCK = threading.Lock()  # a parent's thread may have held it at the fork


os.register_at_fork(after_in_child=_after_fork_in_child)


def _evidences(
    notification: CrashNotification,
    pulse: ProcessedPulse,
    models: EngineModels,
    occupant_models: bool,
) -> tuple[list[OccupantEvidence], list[Assumption]]:
    """Every occupant's evidence and the assumptions it noted, in occupant order.

    The occupants are independent of one another (their occupant-model runs and
    surrogate propagations read only the notification and the loaded, immutable
    models), so up to ``models.occupant_threads`` of them are computed at once: the
    calling thread and helper threads take the next occupant in turn, each noting
    its assumptions in a list of its own, and the lists are joined in occupant
    order. Each occupant's arithmetic is the same on any thread (the compiled
    kernels release the GIL and keep no state; BLAS runs one thread per call), so
    the result is that of one thread, bit for bit. A helper task never waits on
    the pool; one still queued behind other requests' when the calling thread has
    taken every occupant is cancelled, not waited for.
    """
    occupants = notification.occupants
    n = len(occupants)
    noted: list[list[Assumption]] = [[] for _ in range(n)]
    done: list[OccupantEvidence | None] = [None] * n
    failed: list[BaseException | None] = [None] * n
    next_index = iter(range(n))
    take = threading.Lock()

    def work() -> None:
        while True:
            with take:
                i = None if any(failed) else next(next_index, None)
            if i is None:
                return
            try:
                done[i] = _occupant_evidence(
                    i, occupants[i], notification, pulse, models, noted[i], occupant_models
                )
            except BaseException as exc:  # raised below in occupant order, as one thread would
                with take:
                    failed[i] = exc

    helpers = min(models.occupant_threads, n) - 1 if occupant_models else 0
    tasks: list[Future[None]] = []
    if helpers > 0:
        pool = _helper_pool(models.occupant_threads - 1)
        tasks = [pool.submit(work) for _ in range(helpers)]
    work()
    for task in tasks:
        if not task.cancel():
            task.result()
    for exc in failed:
        if exc is not None:
            raise exc
    evidences = [e for e in done if e is not None]
    return evidences, [a for occupant in noted for a in occupant]


def _used_models(models: EngineModels, vehicle_model: str, used_lpm: bool) -> dict[str, ModelInfo]:
    infos = models.model_infos(vehicle_model)
    if not used_lpm:
        keep = ("baseline", "field_model", "delta_v_measurement", "triage_code")
        return {k: infos[k] for k in keep if k in infos}
    return infos


def _occupant_triage(
    occupant: Occupant, evidence: OccupantEvidence, decision: TriageDecision, mode: FieldMode
) -> OccupantTriage:
    decided = OccupantTriage(
        seat=occupant.seat,
        body=occupant.body,
        impact=evidence.impact,
        method=Method.FIELD,
        triage=decision,
        baseline=evidence.baseline,
        field_mode=mode,
    )
    answer = evidence.occupant_model
    if answer is None:
        return decided
    return dataclasses.replace(
        decided,
        method=Method.LPM,
        occupant_model=answer.decision,
        iss=answer.iss,
        region_ais=answer.region_ais,
        measures=answer.measures,
        measures_ci95=answer.measures_ci95,
        interval_method=answer.interval_method,
        point_outside_interval=answer.point_outside_interval,
        probability_uncorrected=answer.probability_uncorrected,
        probability_zero_load=answer.probability_zero_load,
        sensor_inputs=answer.sensor_inputs,
    )


def _vehicle_answer(
    model: RiskModel, models: EngineModels, predictions: list[RiskPrediction]
) -> VehicleRiskAnswer:
    """P(anyone ISS 15+) and its own tier, against the occupants' thresholds."""
    v = model.vehicle(predictions)
    threshold = _risk_threshold(model, models)
    return VehicleRiskAnswer(
        probability=v.probability,
        probability_ci95=v.ci95,
        heldout_auc=model.vehicle_heldout_auc,
        model=f"{model.name}@{model.version}",
        tier=tier_of(v.probability, threshold, models.high_threshold),
        threshold=threshold,
        high_threshold=models.high_threshold,
    )


def triage(
    notification: CrashNotification, models: EngineModels, *, occupant_models: bool = True
) -> TriageResult:
    """Triage every occupant of a notification.

    Parameters
    ----------
    notification : CrashNotification
    models : EngineModels
        With a field model.
    occupant_models : bool, optional
        False: the decision only (a fleet's rescoring): the occupant models
        (LPM and surrogates) are not run, so no occupant has an explanation
        (an assumption says so); every decision field is the full run's, bit
        for bit (the field risk model never reads the occupant models).

    Returns
    -------
    TriageResult

    Raises
    ------
    UnknownVehicleModel
        When `notification.vehicle_model` names no loaded parameter set.
    ValueError
        When the pulse cannot be processed (the message names the field), or
        `models` holds no field model.
    """
    if models.field is None:
        raise ValueError("the engine models hold no field model: triage needs one")
    field_model = models.field
    if notification.vehicle_model not in models.vehicle_models:
        raise UnknownVehicleModel(
            f"unknown vehicle model {notification.vehicle_model!r}; known: "
            + ", ".join(sorted(models.vehicle_models))
        )
    t0 = time.perf_counter()
    pulse = process_pulse(notification.pulse)
    t1 = time.perf_counter()

    assumptions: list[Assumption] = []
    if notification.rollover:
        assumptions.append(
            Assumption(
                AssumptionCode.ROLLOVER_REPORTED,
                "rollover reported: the field model's probability is that of a rollover (it is "
                "in its data); the occupant models see only the planar crash pulse",
            )
        )
    if pulse.nonphysical is not None:
        assumptions.append(
            Assumption(
                AssumptionCode.PULSE_LOOKS_CORRUPT,
                f"the crash pulse record looks corrupt ({pulse.nonphysical}): every occupant "
                "is flagged for a trauma center, whatever the probability computed from it",
            )
        )
    if notification.multiple_impacts:
        assumptions.append(
            Assumption(
                AssumptionCode.MULTIPLE_IMPACTS_REPORTED,
                "multiple impacts reported: the field model's probability includes them (they "
                "are in its data); the occupant models run the recorded pulse as one event",
            )
        )

    occupants: list[OccupantTriage] = []
    risk_predictions: list[RiskPrediction] = []
    field_ms = 0.0
    evidences, noted = _evidences(notification, pulse, models, occupant_models)
    assumptions.extend(noted)
    if isinstance(field_model, RiskModel):  # every occupant at once: one walk of the trees
        tf = time.perf_counter()
        all_inputs = [risk_inputs(o, notification, pulse) for o in notification.occupants]
        all_risks = field_model.predict_many(all_inputs)
        field_ms += 1000.0 * (time.perf_counter() - tf)
    for i, occupant in enumerate(notification.occupants):
        evidence = evidences[i]
        tf = time.perf_counter()
        if isinstance(field_model, RiskModel):
            inputs, risk = all_inputs[i], all_risks[i]
            risk_predictions.append(risk)
            decision = _risk_decision(field_model, models, risk)
            if occupant.child and decision.tier is not None:  # the guideline's pediatric words
                decision = dataclasses.replace(
                    decision,
                    recommendation=child_recommendation(
                        decision.tier, occupant.pediatric_crash_criterion
                    ),
                )
            answered = dataclasses.replace(
                _occupant_triage(occupant, evidence, decision, FieldMode(risk.mode)),
                region_risk=risk.regions,
            )
            assumptions.extend(_risk_assumptions(i, occupant, inputs, risk, field_model))
        else:
            prediction = field_model.predict(evidence.field_inputs)
            decision = _field_decision(field_model, models, prediction)
            answered = _occupant_triage(occupant, evidence, decision, prediction.mode)
            assumptions.extend(_field_assumptions(i, occupant, prediction, field_model))
        field_ms += 1000.0 * (time.perf_counter() - tf)
        if pulse.nonphysical is not None:  # decided conservatively (models.pulse_plausibility)
            answered = dataclasses.replace(
                answered, triage=flagged_for_corrupt_record(answered.triage)
            )
        occupants.append(answered)
    vehicle = (
        _vehicle_answer(field_model, models, risk_predictions)
        if isinstance(field_model, RiskModel)
        else None
    )
    used_lpm = any(o.method is Method.LPM for o in occupants)
    t2 = time.perf_counter()

    return TriageResult(
        event_id=notification.event_id,
        triage=_worst([o.triage for o in occupants]),
        occupants=tuple(occupants),
        pulse=pulse,
        assumptions=tuple(assumptions),
        engine_version=ENGINE_VERSION,
        models=_used_models(models, notification.vehicle_model, used_lpm),
        timings_ms={
            "pulse": 1000.0 * (t1 - t0),
            "occupants": 1000.0 * (t2 - t1),
            "field_model": field_ms,
            "engine_total": 1000.0 * (t2 - t0),
        },
        vehicle=vehicle,
        delta_v_source=delta_v_source(notification.pulse).value,
    )
