"""LPM parameter sets: data files with a unit and a source for every value.

A parameter set is a JSON file ``models/lpm/data/<name>.json``::

    {"name": "...", "description": "...", "labels": "...",
     "parameters": {"dotted.key": {"value": 1.0, "unit": "N/m",
                                   "source": "...", "min": 0.0, "max": 2.0}}}

It is loaded and validated at start (:func:`load_parameter_set`); its SHA-256
(of the file bytes) identifies it in every stored case. The default set,
``compact_sedan``, describes a 2010 Toyota Yaris-class car and is also the
schema: every other set must define the same keys.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

__all__ = [
    "DATA_DIR",
    "DEFAULT_SET",
    "ParameterEntry",
    "ParameterError",
    "ParameterSet",
    "available_parameter_sets",
    "load_parameter_set",
    "parse_parameter_set",
]

#: Folder of the parameter-set files.
DATA_DIR = Path(__file__).resolve().parent / "data"
#: Name of the default (schema) parameter set.
DEFAULT_SET = "compact_sedan"


class ParameterError(ValueError):
    """A parameter file is missing, malformed or out of bounds."""


@dataclass(frozen=True)
class ParameterEntry:
    """One parameter value.

    Attributes
    ----------
    value : float
    unit : str
    source : str
        Where the value comes from, or how it was calibrated.
    minimum, maximum : float or None
        Validation bounds (inclusive), in ``unit``.
    """

    value: float
    unit: str
    source: str
    minimum: float | None = None
    maximum: float | None = None


@dataclass(frozen=True)
class ParameterSet:
    """A validated, immutable LPM parameter set.

    Attributes
    ----------
    name : str
    description : str
    sha256 : str
        Hex SHA-256 of the file bytes (or of the canonical JSON for a set
        derived in memory with :meth:`with_values`).
    entries : Mapping[str, ParameterEntry]
    """

    name: str
    description: str
    sha256: str
    entries: Mapping[str, ParameterEntry] = field(repr=False)
    #: the vehicle interior: per model plane its body points and contacts
    #: (:mod:`models.lpm.interior`), as read from the file's ``interior`` object
    interior: Mapping[str, Any] = field(default_factory=dict, repr=False, compare=False, hash=False)

    def __getitem__(self, key: str) -> float:
        """Value of ``key`` in its unit."""
        try:
            return self.entries[key].value
        except KeyError:
            raise KeyError(f"parameter set {self.name!r} has no parameter {key!r}") from None

    def value(self, key: str) -> float:
        """Value of ``key`` in its unit (same as ``self[key]``)."""
        return self[key]

    def keys(self) -> list[str]:
        """Parameter names, sorted."""
        return sorted(self.entries)

    @property
    def values_sha256(self) -> str:
        """SHA-256 of the values alone (canonical JSON of name -> value).

        What the physics reads: units, sources, bounds, descriptions and the
        file's layout do not enter it, so editing a source or reformatting the
        file leaves it unchanged, and changing any value changes it.
        """
        values = {k: e.value for k, e in sorted(self.entries.items())}
        # the interior table is physics too: which point meets which surface, by which law
        doc = {"values": values, "interior": dict(self.interior)}
        text = json.dumps(doc, sort_keys=True, separators=(",", ":"), allow_nan=False)
        return hashlib.sha256(text.encode()).hexdigest()

    def to_document(self) -> dict[str, Any]:
        """The set as a JSON-ready document (the file format)."""
        params: dict[str, dict[str, Any]] = {}
        for key, e in self.entries.items():
            d: dict[str, Any] = {"value": e.value, "unit": e.unit, "source": e.source}
            if e.minimum is not None:
                d["min"] = e.minimum
            if e.maximum is not None:
                d["max"] = e.maximum
            params[key] = d
        doc: dict[str, Any] = {
            "name": self.name,
            "description": self.description,
            "parameters": params,
        }
        if self.interior:
            doc["interior"] = json.loads(json.dumps(dict(self.interior)))
        return doc

    def with_values(
        self, values: Mapping[str, float], *, name: str | None = None, note: str = "calibrated"
    ) -> ParameterSet:
        """A copy with some values replaced (validated; the source records ``note``).

        Parameters
        ----------
        values : Mapping[str, float]
            New values by key; every key must exist.
        name : str, optional
            Name of the new set (default: the same name).
        note : str
            Appended to the source of each changed value.
        """
        doc = self.to_document()
        for key, val in values.items():
            if key not in doc["parameters"]:
                raise ParameterError(f"unknown parameter {key!r}")
            entry = doc["parameters"][key]
            entry["value"] = float(val)
            entry["source"] = f"{entry['source']}; {note}"
        if name is not None:
            doc["name"] = name
        raw = json.dumps(doc, indent=1).encode()
        return parse_parameter_set(raw, expected_keys=set(self.entries))


def _number(key: str, raw: object) -> float:
    if isinstance(raw, bool) or not isinstance(raw, int | float):
        raise ParameterError(f"{key}: value must be a number, got {raw!r}")
    val = float(raw)
    if not math.isfinite(val):
        raise ParameterError(f"{key}: value must be finite")
    return val


def parse_parameter_set(raw: bytes, *, expected_keys: set[str] | None = None) -> ParameterSet:
    """Parse and validate the bytes of a parameter-set file.

    Parameters
    ----------
    raw : bytes
        File contents (UTF-8 JSON).
    expected_keys : set of str, optional
        Keys that must be present (the schema); extra keys are rejected too.

    Raises
    ------
    ParameterError
        On malformed JSON, a missing unit or source, a non-finite value, a
        value outside its bounds, or a missing/unknown key.
    """
    try:
        doc = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ParameterError(f"parameter file is not valid JSON: {exc}") from exc
    if not isinstance(doc, dict) or not isinstance(doc.get("parameters"), dict):
        raise ParameterError("parameter file needs an object with a 'parameters' object")
    name = doc.get("name")
    if not isinstance(name, str) or not name:
        raise ParameterError("parameter file needs a non-empty 'name'")
    entries: dict[str, ParameterEntry] = {}
    for key, e in doc["parameters"].items():
        if not isinstance(e, dict):
            raise ParameterError(f"{key}: entry must be an object")
        val = _number(key, e.get("value"))
        unit = e.get("unit")
        source = e.get("source")
        if not isinstance(unit, str) or not unit:
            raise ParameterError(f"{key}: missing unit")
        if not isinstance(source, str) or not source.strip():
            raise ParameterError(f"{key}: missing source")
        lo = _number(key + ".min", e["min"]) if "min" in e else None
        hi = _number(key + ".max", e["max"]) if "max" in e else None
        if lo is not None and val < lo:
            raise ParameterError(f"{key}: {val} {unit} below its minimum {lo}")
        if hi is not None and val > hi:
            raise ParameterError(f"{key}: {val} {unit} above its maximum {hi}")
        entries[key] = ParameterEntry(val, unit, source, lo, hi)
    if expected_keys is not None:
        missing = sorted(expected_keys - set(entries))
        extra = sorted(set(entries) - expected_keys)
        if missing:
            raise ParameterError(f"parameter set {name!r} lacks {missing[:5]} ...")
        if extra:
            raise ParameterError(f"parameter set {name!r} has unknown keys {extra[:5]} ...")
    interior = doc.get("interior", {})
    if not isinstance(interior, dict):
        raise ParameterError("'interior' must be an object")
    return ParameterSet(
        name=name,
        description=str(doc.get("description", "")),
        sha256=hashlib.sha256(raw).hexdigest(),
        entries=MappingProxyType(entries),
        interior=MappingProxyType(interior),
    )


def available_parameter_sets() -> list[str]:
    """Names of the parameter sets shipped in :data:`DATA_DIR`, sorted."""
    return sorted(p.stem for p in DATA_DIR.glob("*.json"))


_SCHEMA_KEYS: set[str] | None = None


def _schema_keys() -> set[str]:
    global _SCHEMA_KEYS
    if _SCHEMA_KEYS is None:
        raw = (DATA_DIR / f"{DEFAULT_SET}.json").read_bytes()
        _SCHEMA_KEYS = set(parse_parameter_set(raw).entries)
    return _SCHEMA_KEYS


def load_parameter_set(name: str = DEFAULT_SET, *, path: str | Path | None = None) -> ParameterSet:
    """Load and validate a parameter set.

    Parameters
    ----------
    name : str
        Name of a shipped set (see :func:`available_parameter_sets`).
    path : str or Path, optional
        Load this file instead (e.g. a calibrated set); ``name`` is ignored.

    Returns
    -------
    ParameterSet

    Raises
    ------
    ParameterError
        Unknown name, or the file fails validation.
    """
    if path is None:
        if name not in available_parameter_sets():
            raise ParameterError(
                f"unknown parameter set {name!r}; available: {available_parameter_sets()}"
            )
        path = DATA_DIR / f"{name}.json"
    raw = Path(path).read_bytes()
    return parse_parameter_set(raw, expected_keys=_schema_keys())
