"""What every job process shares: its engine models, loaded once, and a typed line.

A batch on the local pool and a batch on a Dask cluster both triage in worker
processes that load the engine models once and keep them (:func:`models_for`,
keyed by the settings they were loaded for, so one process can hold the models of
two settings, e.g. a recall's). An answer line is a :class:`BatchLine`: its JSON
text and whether the line was refused, so no one reads the text to count.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from models.triage import EngineModels
    from service.settings import Settings

__all__ = ["BatchLine", "models_for"]


@dataclass(frozen=True, slots=True)
class BatchLine:
    """One output line of a batch.

    Attributes
    ----------
    text : str
        The line's JSON text (no newline): ``{"line": n, "result": ...}`` or
        ``{"line": n, "error": problem}``.
    refused : bool
        Whether it is an error (the notification was refused).
    """

    text: str
    refused: bool


#: The engine models of this process, by the settings they were loaded for (and
#: whether with the occupant models' surrogates).
_MODELS: dict[tuple[str, bool], EngineModels] = {}
_MODELS_LOCK = threading.Lock()


def _key(settings: Settings) -> str:
    return settings.model_dump_json()


def models_for(settings: Settings, *, occupant_models: bool = True) -> EngineModels:
    """The engine models for `settings`, loaded on the first call in this process.

    Without `occupant_models`: the models of a decision-only batch, loaded without
    the surrogates (``service.context.engine_models_for``); the occupant models must
    then not be run with them (``models.triage.triage(occupant_models=False)``).
    """
    from service.context import engine_models_for

    key = (_key(settings), occupant_models)
    with _MODELS_LOCK:
        if key not in _MODELS:
            _MODELS[key] = engine_models_for(settings, occupant_models=occupant_models)
        return _MODELS[key]
