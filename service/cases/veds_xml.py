"""The safe XML reader of VEDS documents: one UTF-8, well-formed, bounded XML tree,
and the XML Schema lexical forms of its numbers (:func:`is_xsd_decimal`, :func:`xsd_integer`).

Reading is hardened (``defusedxml`` over the standard library's expat): a
document type declaration is refused outright, so there are no entities,
internal (entity expansion, "billion laughs") or external (XXE), and nothing is
fetched; nesting deeper than :data:`MAX_DEPTH` or more than :data:`MAX_ELEMENTS`
elements are refused while parsing. Every refusal is a 400 problem naming where.
"""

from __future__ import annotations

import io
import re
from collections.abc import Iterator
from typing import Final
from xml.etree.ElementTree import Element, ParseError

from defusedxml import DefusedXmlException
from defusedxml.ElementTree import iterparse

from service.problems import FieldError, MalformedXml

__all__ = [
    "MAX_DEPTH",
    "MAX_ELEMENTS",
    "MAX_NUMBER_CHARS",
    "VEDS_NAMESPACES",
    "is_xsd_decimal",
    "parse_xml",
    "xsd_integer",
]


#: VEDS namespaces read, with the version they stand for.
VEDS_NAMESPACES: Final[dict[str, str]] = {
    "http://www.veds.org/acn/3.1": "3.1",
    "http://www.veds.org/acn/1.0": "1.0",
}


#: NIEM 2.0 core and justice (jxdm 4.1) namespaces of the elements VEDS borrows.
NC_NAMESPACE: Final = "http://niem.gov/niem/niem-core/2.0"


J_NAMESPACE: Final = "http://niem.gov/niem/domains/jxdm/4.1"


#: Deepest element nesting accepted. [R] A VEDS 3.1 document nests 7 levels
#: (root, Crash, CrashVehicle, VehicleCrashPulse, measure, value); 32 leaves room
#: for extensions and refuses crafted nesting long before it costs anything.
MAX_DEPTH: Final = 32


#: Most elements accepted. [R] The full VEDS 3.1 example has about 130; 5,000 is
#: room for many seats, airbags and pulses, and bounds the work on a crafted body.
MAX_ELEMENTS: Final = 5_000


#: Longest number text, characters. [R] Far beyond any sensor's precision (an MPH
#: value with 12 decimals is 22 characters as KPH); bounds the decimal arithmetic.
MAX_NUMBER_CHARS: Final = 64


#: xsd:decimal's lexical form (no exponent, no underscores, no NaN), ASCII digits only
#: (``\d`` would take any Unicode digit, ``٤٠`` or ``４０``). Any number of digits, leading
#: zeros and decimals (an exact KPH twin of an MPH value has six more decimals than it),
#: as XML Schema allows: the length is capped, the value checked against the limits.
_DECIMAL = re.compile(r"[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)")


#: xsd:integer's lexical form, ASCII digits only (leading zeros allowed).
_INTEGER = re.compile(r"[+-]?[0-9]+")


def is_xsd_decimal(text: str) -> bool:
    """An xsd:decimal in ASCII digits, no longer than :data:`MAX_NUMBER_CHARS`."""
    return len(text) <= MAX_NUMBER_CHARS and _DECIMAL.fullmatch(text) is not None


def xsd_integer(text: str) -> int | None:
    """The value of an xsd:integer in ASCII digits no longer than :data:`MAX_NUMBER_CHARS`,
    else None."""
    if len(text) > MAX_NUMBER_CHARS or _INTEGER.fullmatch(text) is None:
        return None
    return int(text)


_PREFIX_OF: Final = {NC_NAMESPACE: "nc", J_NAMESPACE: "j", **dict.fromkeys(VEDS_NAMESPACES, "veds")}


_ENCODING = re.compile(rb"^<\?xml[^>]*?encoding\s*=\s*[\"']([A-Za-z0-9._-]+)[\"']")


def _refuse_xml(reason: str, *, field: str = "body", kind: str = "xml_malformed") -> MalformedXml:
    return MalformedXml(
        f"The VEDS document was refused: {reason}",
        errors=[FieldError(field=field, reason=reason, type=kind)],
    )


def _qualified(tag: str) -> str:
    """``{namespace}Local`` as ``prefix:Local`` (the namespace itself when unknown)."""
    if tag.startswith("{"):
        ns, _, local = tag[1:].partition("}")
        prefix = _PREFIX_OF.get(ns)
        return f"{prefix}:{local}" if prefix else tag
    return tag


def _check_encoding(raw: bytes) -> None:
    if raw.startswith((b"\xff\xfe", b"\xfe\xff", b"\x00", b"\x4c\x6f\xa7\x94")):
        raise _refuse_xml("the document must be encoded in UTF-8", kind="xml_encoding")
    body = raw[3:] if raw.startswith(b"\xef\xbb\xbf") else raw
    declared = _ENCODING.match(body.lstrip())
    if declared and declared.group(1).decode("ascii").lower() not in ("utf-8", "utf8", "us-ascii"):
        raise _refuse_xml(
            f"the declared encoding {declared.group(1).decode('ascii')!r} is not accepted; "
            "send UTF-8",
            kind="xml_encoding",
        )
    try:
        body.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise _refuse_xml(f"invalid UTF-8 at byte {exc.start}", kind="xml_encoding") from exc


def parse_xml(raw: bytes) -> Element:
    """Parse one XML document safely; returns its root element.

    Raises
    ------
    MalformedXml
        Not UTF-8; a document type declaration (and so any entity); not well-formed;
        nesting deeper than `MAX_DEPTH`; more than `MAX_ELEMENTS` elements.
    """
    if not raw.strip():
        raise _refuse_xml("the body is empty", kind="xml_empty")
    _check_encoding(raw)
    root: Element | None = None
    depth = count = 0
    path: list[str] = []
    events: Iterator[tuple[str, Element]] = iterparse(
        io.BytesIO(raw),
        events=("start", "end"),
        forbid_dtd=True,
        forbid_entities=True,
        forbid_external=True,
    )
    try:
        for event, element in events:
            if event == "end":
                depth -= 1
                path.pop()
                continue
            depth += 1
            count += 1
            path.append(_qualified(element.tag))
            if root is None:
                root = element
            if depth > MAX_DEPTH:
                raise _refuse_xml(
                    f"elements nest deeper than {MAX_DEPTH} levels",
                    field="/".join(path[1 : MAX_DEPTH + 2]),
                    kind="xml_too_deep",
                )
            if count > MAX_ELEMENTS:
                raise _refuse_xml(
                    f"more than {MAX_ELEMENTS} elements",
                    field="/".join(path[1:]),
                    kind="xml_too_many_elements",
                )
    except DefusedXmlException as exc:
        raise _refuse_xml(
            "a document type declaration (DOCTYPE) is not accepted: VEDS needs none, and "
            f"it would carry entities ({type(exc).__name__})",
            kind="xml_dtd_forbidden",
        ) from exc
    except ParseError as exc:
        raise _refuse_xml(f"not well-formed XML: {exc}") from exc
    if root is None:  # pragma: no cover - expat refuses a document without an element
        raise _refuse_xml("no root element")
    return root
