"""The vehicle interior as data: which body point meets which surface, by which contact law.

The parameter set's ``interior`` object (``data/compact_sedan.json``) holds, per
model plane (``sagittal``, ``near_side``, ``far_side``):

* ``points``: the body points that can touch the interior, each on a body
  ``body`` (kernel numbering: 0 pelvis ... 4 head, 5 sternum or rib, 6 the
  point that follows only a share of the chest deflection), ``p`` along its
  link (or ``p_link_fraction`` of the link length), ``r`` across it, and a
  contact ``radius`` (times ``radius_scale``);
* ``contacts``, in the kernel's order (the order the forces are summed in):
  a ``point``, a ``surface`` (a named piece of the interior whose coordinates
  come from the parameters: :func:`models.lpm.assemble` draws them), an optional
  ``motion`` and ``channel`` (how the surface moves: the door intrusion, the
  airbag's deployment, the pelvis), the contact law's fields
  (:class:`models.lpm.assemble.ContactSpec`), ``when`` it is present
  (:data:`CONDITIONS`), its unloading ``hysteresis``, and ``fills_gap`` for a
  side airbag that fills a gap narrower than its depth;
* ``surfaces`` (top level): the sizes of the surfaces that are not vehicle
  parameters of their own (knee bolster height, seat-back segments ...).

A string value is a parameter key (``{body}`` stands for the occupant's body
class); a number is a value in SI units with its source in the entry's
``note``; a list of keys is their sum.
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Final

from models.lpm.params import ParameterError, ParameterSet

__all__ = [
    "CONDITIONS",
    "CONTACT_LAW_FIELDS",
    "BodyPoint",
    "ContactRow",
    "interior_plane",
    "resolve_value",
    "surface_size",
]

#: When a contact is present (the `when` field): the occupant's seat and restraints.
CONDITIONS: Final[tuple[str, ...]] = ("airbag", "driver", "side_airbag", "no_side_airbag")

#: Contact-law fields a table entry may give (:class:`models.lpm.assemble.ContactSpec`).
CONTACT_LAW_FIELDS: Final[tuple[str, ...]] = (
    "law",
    "stiff",
    "stiff3",
    "damp",
    "fcap",
    "give",
    "k_bottom",
    "ramp",
    "share",
    "bottom_cap",
    "crush_viscosity",
    "crush_limit",
    "hysteresis",
)


def resolve_value(value: Any, ps: ParameterSet, body: str, where: str) -> float:
    """A table value: a number, a parameter key (``{body}`` substituted), or a list of keys (sum).

    Raises
    ------
    ParameterError
        A key the parameter set does not have, or a value of another type.
    """
    if isinstance(value, bool):
        raise ParameterError(f"interior {where}: a boolean is not a value")
    if isinstance(value, int | float):
        return float(value)
    if isinstance(value, str):
        key = value.replace("{body}", body)
        if key not in ps.entries:
            raise ParameterError(f"interior {where}: unknown parameter {key!r}")
        return ps[key]
    if isinstance(value, list) and value:
        total = 0.0
        for i, v in enumerate(value):
            total += resolve_value(v, ps, body, f"{where}[{i}]")
        return total
    raise ParameterError(f"interior {where}: {value!r} is not a number, key or list of keys")


def surface_size(ps: ParameterSet, name: str) -> Any:
    """A surface size of the interior table (``interior.surfaces.<name>.value``)."""
    try:
        return ps.interior["surfaces"][name]["value"]
    except (KeyError, TypeError):
        raise ParameterError(f"interior surfaces: {name!r} is missing") from None


@dataclass(frozen=True)
class BodyPoint:
    """A body point of the table, resolved: kernel body, position on it and radius, m."""

    k: int
    p: float
    r: float
    radius: float


@dataclass(frozen=True)
class ContactRow:
    """A contact of the table, resolved for one occupant.

    Attributes
    ----------
    name, point, surface : str
    motion : str or None
        Named motion of the surface (None: the surface's own).
    channel : int or None
        Kernel channel (None: the surface's own).
    law : Mapping[str, float]
        The contact-law fields given.
    enabled : bool
    hysteresis : float
    fills_gap : bool
    """

    name: str
    point: str
    surface: str
    motion: str | None
    channel: int | None
    law: Mapping[str, float]
    enabled: bool
    hysteresis: float
    fills_gap: bool


def _points(
    table: Mapping[str, Any], ps: ParameterSet, body: str, link_length: Callable[[int], float]
) -> dict[str, BodyPoint]:
    out = {}
    for name, spec in table.items():
        where = f"point {name}"
        k = int(spec["body"])
        if "p_link_fraction" in spec:
            p = float(spec["p_link_fraction"]) * link_length(k)
        else:
            p = resolve_value(spec["p"], ps, body, where + ".p")
        radius = resolve_value(spec["radius"], ps, body, where + ".radius")
        if "radius_scale" in spec:
            radius = float(spec["radius_scale"]) * radius
        out[name] = BodyPoint(k, p, resolve_value(spec["r"], ps, body, where + ".r"), radius)
    return out


#: Resolved planes per parameter-set object: ``id(ps) -> (weak reference, {key: plane})``.
#: The table is resolved once per parameter set, plane, body, link lengths and
#: conditions (a handful of combinations) instead of on every simulation; the
#: weak reference tells a live set from a new one that reuses a freed id.
_RESOLVED: dict[int, tuple[weakref.ref[ParameterSet], dict[Any, Any]]] = {}
_RESOLVED_LOCK = threading.Lock()


def interior_plane(
    ps: ParameterSet,
    plane: str,
    body: str,
    link_length: Callable[[int], float],
    conditions: Sequence[str],
) -> tuple[dict[str, BodyPoint], list[ContactRow]]:
    """The body points and contacts of one model plane, resolved for one occupant.

    Memoised per parameter-set object (:data:`_RESOLVED`); the rows are
    immutable, and the containers returned are fresh copies.

    Parameters
    ----------
    ps : ParameterSet
    plane : str
        ``sagittal``, ``near_side`` or ``far_side``.
    body : str
        The body class (substituted for ``{body}``).
    link_length : callable
        Link length of a body, m (for ``p_link_fraction``).
    conditions : sequence of str
        The :data:`CONDITIONS` that hold for this occupant.

    Returns
    -------
    points : dict of str to BodyPoint
    contacts : list of ContactRow
        In table order.

    Raises
    ------
    ParameterError
        A plane missing from the table, an unknown point, condition or key.
    """
    lengths = tuple(link_length(k) for k in _LINKED_BODIES)
    key = (plane, body, lengths, tuple(conditions))
    with _RESOLVED_LOCK:
        entry = _RESOLVED.get(id(ps))
        if entry is None or entry[0]() is not ps:
            for stale in [k for k, (ref, _) in _RESOLVED.items() if ref() is None]:
                del _RESOLVED[stale]
            entry = (weakref.ref(ps), {})
            _RESOLVED[id(ps)] = entry
        hit = entry[1].get(key)
    if hit is None:
        hit = _resolve_plane(ps, plane, body, lengths, tuple(conditions))
        with _RESOLVED_LOCK:
            entry[1][key] = hit
    return dict(hit[0]), list(hit[1])


#: Bodies whose link length a ``p_link_fraction`` may refer to (kernel numbering:
#: pelvis, lumbar, thorax, neck, head).
_LINKED_BODIES: Final[tuple[int, ...]] = (0, 1, 2, 3, 4)


def _resolve_plane(
    ps: ParameterSet,
    plane: str,
    body: str,
    lengths: tuple[float, ...],
    conditions: tuple[str, ...],
) -> tuple[dict[str, BodyPoint], list[ContactRow]]:
    try:
        table = ps.interior[plane]
    except KeyError:
        raise ParameterError(f"the parameter set has no interior for the {plane} plane") from None
    points = _points(table["points"], ps, body, lambda k: lengths[k])
    rows = []
    for entry in table["contacts"]:
        name = str(entry["name"])
        if entry["point"] not in points:
            raise ParameterError(f"interior contact {name}: unknown point {entry['point']!r}")
        when = entry.get("when")
        if when is not None and when not in CONDITIONS:
            raise ParameterError(f"interior contact {name}: unknown condition {when!r}")
        law = {
            f: resolve_value(entry[f], ps, body, f"contact {name}.{f}")
            for f in CONTACT_LAW_FIELDS
            if f in entry and f != "hysteresis"
        }
        rows.append(
            ContactRow(
                name=name,
                point=str(entry["point"]),
                surface=str(entry["surface"]),
                motion=entry.get("motion"),
                channel=int(entry["channel"]) if "channel" in entry else None,
                law=MappingProxyType(law),
                enabled=when is None or when in conditions,
                hysteresis=(
                    resolve_value(entry["hysteresis"], ps, body, f"contact {name}.hysteresis")
                    if "hysteresis" in entry
                    else 0.0
                ),
                fills_gap=bool(entry.get("fills_gap", False)),
            )
        )
    return points, rows
