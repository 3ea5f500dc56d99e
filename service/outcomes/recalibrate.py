"""Recalibrate the served field model on the linked local outcomes, and write it.

``aacn-triage outcomes recalibrate --site NAME`` (:mod:`service.cli.outcomes`):

1. read every stored occupant decided by the served artifact (its checksum recorded
   with the case) that has a current outcome: its decided probability, ISS 15+
   (``iss >= 15``; an EMS outcome without an ISS counts as ISS < 15, as in the quality
   figures) and weight; the case is the crash (one notification, one vehicle);
2. decide the form from the precision required, or refuse
   (:func:`models.field.recalibration.precision_plan`);
3. fit it, check it by cross-validation by crash, and write a new versioned,
   checksummed artifact into the site's model directory
   (:func:`models.field.recalibrated.recalibrated_document`), loaded back to verify it.

The math is the engine's (:mod:`models.field.recalibration`); this module reads the
store and writes the file.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from sqlalchemy.orm import Session, sessionmaker

from models.field.recalibrated import local_version, recalibrated_document
from models.field.recalibration import (
    CrossValidation,
    PrecisionPlan,
    Recalibration,
    TooFewOutcomes,
    cross_validate,
    fit_recalibration,
    precision_plan,
)
from models.field.risk_model import RiskModel
from models.field.versions import artifact_versions
from models.tiers import HIGH_RISK_THRESHOLD, check_threshold_order
from models.triage.loading import operating_thresholds
from service.db import repository
from service.outcomes.quality import SERIOUS_ISS

__all__ = ["LinkedOutcomes", "RecalibrationResult", "linked_outcomes", "recalibrate"]

#: The key under which a case records its field model (``models.triage.loading``).
FIELD_MODEL_KEY = "field_model"


@dataclass(frozen=True)
class LinkedOutcomes:
    """The linked occupants a recalibration learns from (arrays of one length).

    Attributes
    ----------
    occupants : tuple of str
        ``case_id:seat``.
    crash : tuple of str
        The case id of each (the crash: the unit of the folds and of the robust SEs).
    probability, serious, weight : ndarray
        Decided probability, ISS 15+ (0/1), weight.
    """

    occupants: tuple[str, ...]
    crash: tuple[str, ...]
    probability: np.ndarray
    serious: np.ndarray
    weight: np.ndarray

    @property
    def cases(self) -> int:
        return len(set(self.crash))


def linked_outcomes(sessions: sessionmaker[Session], artifact_sha256: str) -> LinkedOutcomes:
    """Every stored occupant decided by the artifact of `artifact_sha256` with an outcome
    (streamed from the store: :func:`service.db.repository.linked_decisions`)."""
    occupants: list[str] = []
    crash: list[str] = []
    p: list[float] = []
    y: list[float] = []
    w: list[float] = []
    with sessions() as session:
        for row in repository.linked_decisions(session):
            if (row.models.get(FIELD_MODEL_KEY) or {}).get("sha256") != artifact_sha256:
                continue
            occupants.append(f"{row.case_id}:{row.seat}")
            crash.append(row.case_id)
            p.append(row.probability)
            y.append(1.0 if row.iss is not None and row.iss >= SERIOUS_ISS else 0.0)
            w.append(row.weight)
    return LinkedOutcomes(tuple(occupants), tuple(crash), np.array(p), np.array(y), np.array(w))


@dataclass(frozen=True)
class RecalibrationResult:
    """What a recalibration found and wrote (`path` None on a dry run)."""

    version: str
    served_version: str
    plan: PrecisionPlan
    recalibration: Recalibration
    cross_validation: CrossValidation
    thresholds: dict[str, tuple[float, float]]
    cases: int
    occupants: int
    path: Path | None


def recalibrate(
    sessions: sessionmaker[Session],
    served: RiskModel,
    *,
    site: str,
    out_dir: Path,
    dry_run: bool = False,
    local_dirs: Sequence[Path] = (),
    high_threshold: float = HIGH_RISK_THRESHOLD,
    operating_point: str | None = None,
) -> RecalibrationResult:
    """Fit, check and write the recalibration of `served` on the linked local outcomes.

    `high_threshold` and `operating_point` are the service's (AACN_HIGH_RISK_THRESHOLD,
    AACN_OPERATING_POINT): a recalibration whose mapped thresholds would rise above the
    high tier's is refused here, not written to be refused by the service at start.

    Raises
    ------
    TooFewOutcomes
        Too few (effective) linked ISS 15+ outcomes (the message says how many are
        needed and why).
    ThresholdOrderError
        (a ValueError) A mapped operating threshold above `high_threshold`.
    ValueError
        A bad site name.
    """
    data = linked_outcomes(sessions, served.sha256)
    plan = precision_plan(data.probability, data.serious, data.weight)
    version = local_version(served.version, site, list(artifact_versions((out_dir, *local_dirs))))
    if plan.method == "refused":
        raise TooFewOutcomes(
            f"{plan.reason} (of {len(data.occupants)} linked occupants decided by "
            f"{served.name} {served.version}); no model written"
        )
    fit = fit_recalibration(data.probability, data.serious, data.weight, data.crash, plan.method)
    cv = cross_validate(data.probability, data.serious, data.weight, data.crash, plan.method)
    doc = recalibrated_document(
        served.document,
        version=version,
        site=site,
        recalibration=fit,
        plan=plan,
        cross_validation=cv,
        occupants=data.occupants,
        cases=data.cases,
    )
    new = RiskModel.from_document(doc)  # verified as the loader will verify the file
    check_threshold_order(high_threshold, operating_thresholds(new, operating_point, None))
    thresholds = {
        name: (served.thresholds[name], new.thresholds[name]) for name in served.thresholds
    }
    path = None
    if not dry_run:
        out_dir.mkdir(parents=True, exist_ok=True)
        path = out_dir / f"field_iss15-{version}.json"
        tmp = path.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n", encoding="utf-8")
        tmp.replace(path)
        RiskModel.from_artifact(path)
    return RecalibrationResult(
        version=version,
        served_version=served.version,
        plan=plan,
        recalibration=fit,
        cross_validation=cv,
        thresholds=thresholds,
        cases=data.cases,
        occupants=len(data.occupants),
        path=path,
    )
