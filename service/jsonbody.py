"""Request-body JSON read strictly: duplicate keys and runaway nesting are refused.

Python's ``json`` (and pydantic's parser) keep the last of two equal keys, so
``{"delta_v_kmh": 500, "delta_v_kmh": 56}`` was triaged at 56 km/h while the
audit copy held only one of the two values (issue 24, a fuzzing finding). The
notification is therefore parsed here first, every object checked for repeated
keys, and refused as malformed (400) before pydantic sees it.
"""

from __future__ import annotations

import json
from typing import Any

__all__ = ["MalformedJson", "loads_strict"]


class MalformedJson(ValueError):
    """The body is not one well-formed JSON document with unique keys."""


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise MalformedJson(f"duplicate key {key!r} in a JSON object")
        out[key] = value
    return out


def loads_strict(raw: bytes | str) -> Any:
    """Parse one JSON document, refusing duplicate keys and excessive nesting.

    Non-finite numbers (``NaN``, ``Infinity``, ``1e999``) are parsed, so that the
    validation that follows refuses them naming the field (422).

    Raises
    ------
    MalformedJson
        On invalid JSON, invalid UTF-8, a duplicate key, or nesting deep enough to
        exhaust the parser's recursion limit.
    """
    try:
        return json.loads(raw, object_pairs_hook=_unique_keys)
    except MalformedJson:
        raise
    except RecursionError as exc:
        raise MalformedJson("the JSON document is nested too deeply") from exc
    except (ValueError, UnicodeDecodeError) as exc:  # JSONDecodeError is a ValueError
        raise MalformedJson(str(exc)) from exc
