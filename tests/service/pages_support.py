"""Support for the case page tests: notifications, an HTML element reader, sign-in."""

from __future__ import annotations

import re
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from html.parser import HTMLParser
from typing import Any

from tests.support import example, summary

_VOID = frozenset({"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta"})


@dataclass(frozen=True)
class Element:
    """One start tag: its attributes, the ids of its ancestors and its own text."""

    tag: str
    attrs: dict[str, str]
    within: tuple[str, ...]
    index: int


class _Reader(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[tuple[str, dict[str, str], int]] = []
        self.elements: list[Element] = []
        self.texts: dict[int, list[str]] = {}

    def _record(self, tag: str, attrs: list[tuple[str, str | None]]) -> int:
        a = {k: v or "" for k, v in attrs}
        within = tuple(x[1]["id"] for x in self.stack if "id" in x[1])
        index = len(self.elements)
        self.elements.append(Element(tag, a, within, index))
        return index

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        index = self._record(tag, attrs)
        if tag not in _VOID:
            self.stack.append((tag, self.elements[index].attrs, index))

    def handle_startendtag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self._record(tag, attrs)

    def handle_endtag(self, tag: str) -> None:
        if tag in _VOID:
            return
        while self.stack:
            open_tag, _, _ = self.stack.pop()
            if open_tag == tag:
                break

    def handle_data(self, data: str) -> None:
        for _, _, index in self.stack:
            self.texts.setdefault(index, []).append(data)


class Page:
    """The elements of an HTML page, queryable by tag, attributes and ancestor id."""

    def __init__(self, html: str) -> None:
        reader = _Reader()
        reader.feed(html)
        reader.close()
        self.html = html
        self.elements = reader.elements
        self._texts = reader.texts

    def text(self, element: Element) -> str:
        """The element's text content, whitespace collapsed."""
        return re.sub(r"\s+", " ", " ".join(self._texts.get(element.index, []))).strip()

    def all(
        self, tag: str | None = None, *, within: str | None = None, **attrs: str
    ) -> list[Element]:
        """Elements matching; attribute names with `_` for `-` (data_region=...)."""
        wanted = {k.replace("_", "-"): v for k, v in attrs.items()}
        out = []
        for e in self.elements:
            if tag is not None and e.tag != tag:
                continue
            if within is not None and within not in e.within:
                continue
            if all((k in e.attrs) if v == "*" else e.attrs.get(k) == v for k, v in wanted.items()):
                out.append(e)
        return out

    def one(self, tag: str | None = None, *, within: str | None = None, **attrs: str) -> Element:
        found = self.all(tag, within=within, **attrs)
        assert len(found) == 1, f"{len(found)} elements {tag} {attrs} within {within}"
        return found[0]

    def by_class(self, css: str, *, within: str | None = None) -> list[Element]:
        return [e for e in self.all(within=within) if css in e.attrs.get("class", "").split()]


def recent(minutes: float = 7.0) -> str:
    """An occurred_at some minutes ago (RFC 3339)."""
    return (datetime.now(UTC) - timedelta(minutes=minutes)).isoformat()


def head_injury() -> dict[str, Any]:
    """An unbelted driver without an airbag at 40 km/h frontal: the occupant model gives
    head/neck AIS 3 (checked by the tests on the stored result)."""
    body = summary(40.0, 0.0, belted=False, airbag="not_deployed")
    body["occurred_at"] = recent()
    return body


def near_side_56() -> dict[str, Any]:
    """The body map's case: a 56 km/h near-side crash, the driver's side and curtain airbags
    deployed (the occupant models' curves put the head/neck at AIS 6)."""
    body = summary(56.0, 270.0)
    body["occupants"][0]["side_airbag"] = "deployed"
    body["occurred_at"] = recent(5)
    return body


def minor() -> dict[str, Any]:
    """8 km/h frontal, belted with airbag: no trauma-center indication."""
    body = summary(8.0, 0.0)
    body["occurred_at"] = recent(3)
    return body


def rear_seat_rollover() -> dict[str, Any]:
    """A driver and a child in the rear (field model only), with rollover and multiple impacts."""
    body = summary(30.0, 0.0)
    body["occupants"].append(
        {
            "seat": "rear_left",
            "body": "female_5th",
            "age_years": 8,
            "belted": True,
            "frontal_airbag": "not_deployed",
        }
    )
    body["crash"]["rollover"] = True
    body["crash"]["multiple_impacts"] = True
    body["occurred_at"] = recent(12)
    return body


def side_edr() -> dict[str, Any]:
    """The documented EDR example: near-side driver, far-side passenger."""
    body = example("delta_v")
    body["occurred_at"] = recent(20)
    return body


def acceleration() -> dict[str, Any]:
    """The documented acceleration example (samples drawn on the pulse plot)."""
    body = example("acceleration")
    body["occurred_at"] = recent(30)
    return body


def mixed_tiers() -> dict[str, Any]:
    """The body map's near-side crash with a belted far-side passenger: the driver in the high
    tier (P about 0.40), the passenger in the moderate one (about 0.09)."""
    body = near_side_56()
    body["occupants"].append(
        {
            "seat": "front_passenger",
            "body": "male_50th",
            "age_years": 30,
            "sex": "male",
            "belted": True,
            "frontal_airbag": "deployed",
            "side_airbag": "not_deployed",
        }
    )
    body["occurred_at"] = recent(4)
    return body


#: The case page's banner words of each risk tier (written out here, not imported: the
#: tests hold the page to them).
TIER_VERDICTS = {
    "high": "HIGH RISK: HIGHEST-LEVEL TRAUMA CENTER",
    "moderate": "MODERATE RISK: CONSIDER A TRAUMA CENTER",
    "none": "NO TELEMETRY INDICATION",
}

#: The notification of each tier the page tests use (checked on the stored answer).
TIER_CASES = {"high": near_side_56, "moderate": head_injury, "none": minor}


def csrf_token(html: str) -> str:
    match = re.search(r'name="csrf_token" value="([^"]+)"', html)
    assert match, "no csrf_token in the form"
    return match.group(1)


def set_cookies(response: Any) -> dict[str, str]:
    """name -> the full Set-Cookie header of each cookie a response sets."""
    out = {}
    for header in response.headers.get_list("set-cookie"):
        name = header.split("=", 1)[0]
        out[name] = header
    return out


def cookie_value(set_cookie: str) -> str:
    return set_cookie.split(";", 1)[0].split("=", 1)[1]
