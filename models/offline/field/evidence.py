"""The engine's evidence for field rows: the field model's inputs and the occupant models' answers.

Each row is sent through the engine as the service would see it
(:func:`models.triage.occupant_evidence`: the pulse processed, the impact
classified, the occupant model and its surrogate run). The results are cached
in a JSON-lines file keyed by the code and models that make them, so a fit or a
check resumes where it stopped and reruns nothing that cannot have changed.
Work is spread over a process pool with a progress bar.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tqdm import tqdm

from models import ENGINE_VERSION
from models.field.features import FieldInputs, FieldMode
from models.field.model import feature_code_sha256
from models.lpm.fingerprint import lpm_code_sha256
from models.notification import CrashNotification, Sex
from models.triage import (
    EngineModels,
    load_engine_models,
    occupant_evidence,
    triage_code_sha256,
)

__all__ = ["RowEvidence", "default_cache_dir", "evidence_for", "evidence_key"]


@dataclass(frozen=True)
class RowEvidence:
    """What the engine makes of a one-occupant notification.

    Attributes
    ----------
    event_id : str
    inputs : FieldInputs
        The field model's inputs.
    impact_mode : str
        The occupant's impact mode (from the PDOF and seat).
    in_lpm : bool
        An occupant model answered.
    p_lpm : float or None
        The occupant models' P(ISS >= 15) after the zero-load correction (the
        probability the service decided on before the field model).
    p_lpm_uncorrected : float or None
    point_outside_interval : bool or None
    p_baseline : float
        The statistical baseline's probability.
    measures : dict of str to float or None
        The occupant model's nominal injury measures (names with units, as
        :class:`models.injury.measures.InjuryMeasures`; None where no occupant
        model answered).
    """

    event_id: str
    inputs: FieldInputs
    impact_mode: str
    in_lpm: bool
    p_lpm: float | None
    p_lpm_uncorrected: float | None
    point_outside_interval: bool | None
    p_baseline: float
    measures: dict[str, float] | None = None

    @property
    def p_previous_decision(self) -> float:
        """The probability the service decided on before the field model.

        The occupant models' corrected P where one ran, else the baseline's.
        """
        return self.p_lpm if self.p_lpm is not None else self.p_baseline

    def to_json(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["inputs"]["mode"] = self.inputs.mode.value
        d["inputs"]["sex"] = None if self.inputs.sex is None else self.inputs.sex.value
        return d

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> RowEvidence:
        inputs = dict(d["inputs"])
        inputs["mode"] = FieldMode(inputs["mode"])
        inputs["sex"] = None if inputs["sex"] is None else Sex(inputs["sex"])
        return cls(**{**d, "inputs": FieldInputs(**inputs)})


def evidence_key(models: EngineModels, label: str) -> str:
    """Cache key: the data label and every checksum that can change the evidence."""
    parts = [
        label,
        ENGINE_VERSION,
        lpm_code_sha256(),
        triage_code_sha256(),
        feature_code_sha256(),
        models.baseline.sha256,
        models.surrogates.sha256 if models.surrogates is not None else "no-surrogates",
        *(ps.sha256 for ps in models.parameter_sets.values()),
    ]
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()[:16]


def default_cache_dir() -> Path:
    """``$AACN_CACHE_DIR`` or ``~/.cache/aacn-triage``."""
    env = os.environ.get("AACN_CACHE_DIR")
    return Path(env) if env else Path.home() / ".cache" / "aacn-triage"


_MODELS: EngineModels | None = None


def _init() -> None:
    global _MODELS
    _MODELS = load_engine_models(use_field=False)


def _one(notification: CrashNotification) -> dict[str, Any]:
    assert _MODELS is not None
    (ev,), _ = occupant_evidence(notification, _MODELS)
    lpm = ev.occupant_model
    return RowEvidence(
        event_id=notification.event_id,
        inputs=ev.field_inputs,
        impact_mode=ev.impact.mode.value,
        in_lpm=lpm is not None,
        p_lpm=None if lpm is None else lpm.decision.probability,
        p_lpm_uncorrected=None if lpm is None else lpm.probability_uncorrected,
        point_outside_interval=None if lpm is None else lpm.point_outside_interval,
        p_baseline=ev.baseline.probability,
        measures=None if lpm is None else dict(lpm.measures),
    ).to_json()


def evidence_for(
    notifications: Sequence[CrashNotification],
    label: str,
    *,
    cache_dir: Path | None = None,
    workers: int | None = None,
    progress: bool = True,
    key: Callable[[EngineModels, str], str] = evidence_key,
) -> list[RowEvidence]:
    """The engine's evidence for one-occupant notifications, cached and resumable.

    Parameters
    ----------
    notifications : sequence of CrashNotification
        Each with one occupant and a unique ``event_id``.
    label : str
        Names the data set in the cache key (e.g. the data file's checksum).
    cache_dir : Path, optional
        Default :func:`default_cache_dir`.
    workers : int, optional
        Processes; default the CPU count.
    progress : bool
        Show a progress bar on stderr.

    Returns
    -------
    list of RowEvidence
        In the order of `notifications`.
    """
    models = load_engine_models(use_field=False, warm=False)
    root = cache_dir or default_cache_dir()
    root.mkdir(parents=True, exist_ok=True)
    path = root / f"evidence-{key(models, label)}.jsonl"
    done: dict[str, RowEvidence] = {}
    if path.is_file():
        for line in path.read_text(encoding="utf-8").splitlines():
            try:
                ev = RowEvidence.from_json(json.loads(line))
            except (ValueError, KeyError, TypeError):
                continue  # a line cut short by an interrupted run
            done[ev.event_id] = ev
    todo = [n for n in notifications if n.event_id not in done]
    if todo:
        n_workers = workers or os.cpu_count() or 1
        with (
            path.open("a", encoding="utf-8") as out,
            tqdm(total=len(todo), desc=f"engine runs ({label})", disable=not progress) as bar,
            ProcessPoolExecutor(n_workers, initializer=_init) as pool,
        ):
            for record in pool.map(_one, todo, chunksize=32):
                out.write(json.dumps(record) + "\n")
                out.flush()
                ev = RowEvidence.from_json(record)
                done[ev.event_id] = ev
                bar.update(1)
    return [done[n.event_id] for n in notifications]
