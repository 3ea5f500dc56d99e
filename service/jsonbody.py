"""Request-body JSON read strictly: duplicate keys and runaway nesting are refused.

Python's ``json`` (and pydantic's parser) keep the last of two equal keys, so
``{"delta_v_kmh": 500, "delta_v_kmh": 56}`` would be triaged at 56 km/h while the
audit copy would hold only one of the two values (a fuzzing finding). The
notification is therefore parsed here first, every object checked for repeated
keys, and refused as malformed (400) before pydantic sees it.
"""

from __future__ import annotations

import json
import sys
from typing import Any, Final

__all__ = ["MAX_INTEGER_DIGITS", "MalformedJson", "loads_strict"]

#: Most digits of an integer in a JSON document: Python's own bound on turning a
#: digit string into an int (``sys.int_info.default_max_str_digits``, 4300), far
#: beyond any field's range. A longer one is refused in the service's words, not
#: the interpreter's (which name ``sys.set_int_max_str_digits``).
MAX_INTEGER_DIGITS: Final[int] = sys.int_info.default_max_str_digits


class MalformedJson(ValueError):
    """The body is not one well-formed JSON document with unique keys."""


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise MalformedJson(f"duplicate key {key!r} in a JSON object")
        out[key] = value
    return out


def _bounded_int(text: str) -> int:
    """An integer of the document; too many digits is malformed (400), not a crash."""
    digits = len(text) - text.startswith("-")
    if digits > MAX_INTEGER_DIGITS:
        raise MalformedJson(
            f"a number is too long: an integer of {digits} digits (at most {MAX_INTEGER_DIGITS})"
        )
    return int(text)


def loads_strict(raw: bytes | str) -> Any:
    """Parse one JSON document, refusing duplicate keys and excessive nesting.

    Non-finite numbers (``NaN``, ``Infinity``, ``1e999``) are parsed, so that the
    validation that follows refuses them naming the field (422).

    Raises
    ------
    MalformedJson
        On invalid JSON, invalid UTF-8, a duplicate key, an integer of more than
        :data:`MAX_INTEGER_DIGITS` digits, or nesting deep enough to exhaust the
        parser's recursion limit.
    """
    try:
        return json.loads(raw, object_pairs_hook=_unique_keys, parse_int=_bounded_int)
    except MalformedJson:
        raise
    except RecursionError as exc:
        raise MalformedJson("the JSON document is nested too deeply") from exc
    except (ValueError, UnicodeDecodeError) as exc:  # JSONDecodeError is a ValueError
        raise MalformedJson(str(exc)) from exc
