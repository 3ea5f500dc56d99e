"""Parameter sets: every value has a unit and a source, validation rejects bad files."""

from __future__ import annotations

import hashlib
import json

import pytest

from models.lpm.params import (
    DATA_DIR,
    ParameterError,
    ParameterSet,
    available_parameter_sets,
    load_parameter_set,
    parse_parameter_set,
)


def _raw() -> bytes:
    return (DATA_DIR / "compact_sedan.json").read_bytes()


def test_default_set_is_available_and_checksummed(params: ParameterSet) -> None:
    assert "compact_sedan" in available_parameter_sets()
    assert params.name == "compact_sedan"
    assert params.sha256 == hashlib.sha256(_raw()).hexdigest()


def test_every_value_has_unit_and_source(params: ParameterSet) -> None:
    assert len(params.entries) > 200
    for key, entry in params.entries.items():
        assert entry.unit, key
        assert entry.source.strip(), key
        if entry.minimum is not None:
            assert entry.value >= entry.minimum, key
        if entry.maximum is not None:
            assert entry.value <= entry.maximum, key


def test_seat_friction_is_the_papers(params: ParameterSet) -> None:
    assert params["seat.friction"] == 0.5
    assert params["posture.neutral_lumbar_flexion"] == 5.8


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda e: e.pop("unit"), "missing unit"),
        (lambda e: e.update(source=" "), "missing source"),
        (lambda e: e.update(value="3"), "must be a number"),
        (lambda e: e.update(value=float("nan")), "finite"),
        (lambda e: e.update(value=-1.0), "below its minimum"),
    ],
)
def test_bad_entries_are_rejected(mutate, message: str) -> None:  # type: ignore[no-untyped-def]
    doc = json.loads(_raw())
    mutate(doc["parameters"]["seat.friction"])
    raw = json.dumps(doc, allow_nan=True).encode()
    with pytest.raises(ParameterError, match=message):
        parse_parameter_set(raw)


def test_missing_and_unknown_keys_are_rejected(params: ParameterSet) -> None:
    doc = json.loads(_raw())
    del doc["parameters"]["seat.friction"]
    with pytest.raises(ParameterError, match="lacks"):
        parse_parameter_set(json.dumps(doc).encode(), expected_keys=set(params.entries))
    doc = json.loads(_raw())
    doc["parameters"]["seat.extra"] = {"value": 1.0, "unit": "-", "source": "x"}
    with pytest.raises(ParameterError, match="unknown"):
        parse_parameter_set(json.dumps(doc).encode(), expected_keys=set(params.entries))


def test_not_json_and_unknown_name() -> None:
    with pytest.raises(ParameterError, match="JSON"):
        parse_parameter_set(b"{nope")
    with pytest.raises(ParameterError, match="unknown parameter set"):
        load_parameter_set("no_such_car")


def test_with_values_changes_value_source_and_checksum(params: ParameterSet) -> None:
    new = params.with_values({"seat.friction": 0.4}, note="test")
    assert new["seat.friction"] == 0.4
    assert new.entries["seat.friction"].source.endswith("test")
    assert new.sha256 != params.sha256
    with pytest.raises(ParameterError):
        params.with_values({"seat.friction": 5.0})
