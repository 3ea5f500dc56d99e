"""The vehicle interior is data of the parameter set: the contacts come from its table."""

from __future__ import annotations

import json

import numpy as np
import pytest

from models.impact_mode import ImpactMode
from models.lpm.assemble import Restraints, build_model
from models.lpm.interior import CONDITIONS, interior_plane
from models.lpm.params import ParameterError, ParameterSet, parse_parameter_set
from models.notification import AirbagState, Body, Occupant, Seat

PLANES = {"sagittal": ImpactMode.FRONTAL, "near_side": ImpactMode.NEAR_SIDE}
RESTRAINTS = Restraints(
    airbag=True,
    airbag_fire_s=0.015,
    belted=True,
    pretensioner_fire_s=0.012,
    airbag_equipped=True,
    side_airbag=True,
    side_airbag_fire_s=0.01,
)


def _driver(body: Body = Body.MALE_50TH) -> Occupant:
    return Occupant(seat=Seat.DRIVER, body=body, belted=True, frontal_airbag=AirbagState.DEPLOYED)


def _with(params: ParameterSet, edit: object) -> ParameterSet:
    doc = params.to_document()
    assert callable(edit)
    edit(doc)
    return parse_parameter_set(json.dumps(doc).encode())


@pytest.mark.parametrize("plane", ["sagittal", "near_side", "far_side"])
def test_every_contact_of_the_kernel_is_a_row_of_the_table(
    params: ParameterSet, plane: str
) -> None:
    table = params.interior[plane]
    mode = {
        "sagittal": ImpactMode.FRONTAL,
        "near_side": ImpactMode.NEAR_SIDE,
        "far_side": ImpactMode.FAR_SIDE,
    }[plane]
    model = build_model(mode, _driver(), params, RESTRAINTS)
    assert model.contact_names == tuple(c["name"] for c in table["contacts"])
    for c in table["contacts"]:
        assert c["point"] in table["points"]
        assert c.get("when") is None or c["when"] in CONDITIONS


def test_a_contact_law_is_read_from_the_table(params: ParameterSet) -> None:
    """Point the windshield contact at another stiffness: the kernel row follows."""

    def edit(doc: dict[str, object]) -> None:
        interior = doc["interior"]
        assert isinstance(interior, dict)
        for c in interior["sagittal"]["contacts"]:
            if c["name"] == "windshield_head":
                c["stiff"] = "frontal.dash.stiffness"

    edited = _with(params, edit)
    before = build_model(ImpactMode.FRONTAL, _driver(), params, RESTRAINTS)
    after = build_model(ImpactMode.FRONTAL, _driver(), edited, RESTRAINTS)
    i = before.contact_names.index("windshield_head")
    from models.lpm import kernel as K

    assert after.ct[i, K.C_K] == params["frontal.dash.stiffness"]
    assert before.ct[i, K.C_K] == params["frontal.windshield.stiffness"]
    rest = np.delete(np.arange(len(before.contact_names)), i)
    assert np.array_equal(before.ct[rest], after.ct[rest])
    assert edited.values_sha256 != params.values_sha256, "the interior is physics"


def test_a_table_naming_an_unknown_parameter_or_point_is_refused(params: ParameterSet) -> None:
    def unknown_key(doc: dict[str, object]) -> None:
        interior = doc["interior"]
        assert isinstance(interior, dict)
        interior["sagittal"]["contacts"][0]["stiff"] = "frontal.no_such_thing"

    with pytest.raises(ParameterError, match="unknown parameter"):
        interior_plane(_with(params, unknown_key), "sagittal", "male_50th", lambda k: 0.3, [])

    def unknown_point(doc: dict[str, object]) -> None:
        interior = doc["interior"]
        assert isinstance(interior, dict)
        interior["near_side"]["contacts"][0]["point"] = "elbow"

    with pytest.raises(ParameterError, match="unknown point"):
        interior_plane(_with(params, unknown_point), "near_side", "male_50th", lambda k: 0.3, [])


def test_conditions_switch_contacts_on_and_off(params: ParameterSet) -> None:
    """The wheel is the driver's; with side airbags the bags replace the door-rib and
    window-head contacts (which stay in the table, switched off)."""
    passenger = Occupant(
        seat=Seat.FRONT_PASSENGER,
        body=Body.MALE_50TH,
        belted=True,
        frontal_airbag=AirbagState.DEPLOYED,
    )
    from models.lpm import kernel as K

    m = build_model(ImpactMode.FRONTAL, passenger, params, RESTRAINTS)
    enabled = dict(zip(m.contact_names, m.ct[:, K.C_EN], strict=True))
    assert enabled["wheel_head"] == 0.0
    assert enabled["airbag_head"] == 1.0
    near = build_model(ImpactMode.NEAR_SIDE, _driver(), params, RESTRAINTS)
    enabled = dict(zip(near.contact_names, near.ct[:, K.C_EN], strict=True))
    assert enabled["door_rib"] == 0.0
    assert enabled["side_airbag_thorax"] == 1.0
