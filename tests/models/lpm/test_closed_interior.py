"""The frontal occupant stays inside the modelled interior (issue 4, "no segment
passes through a rigid surface").

Before the glass was run down to the panel face, the crushable structures got a
stroke limit and the thighs became a surface, the head of an unrestrained 50M
at 120 km/h passed over the panel top below the windshield's lower edge and
ended 1.77 m forward of the H-point, and heads of unbelted occupants with an
airbag (and of belted ones seated rearward) went under the wheel into the
footwell, 0.64 m below the H-point, through the thighs.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from models.impact_mode import ImpactMode
from models.lpm.params import ParameterSet
from models.lpm.pulses import haversine_pulse
from models.lpm.simulate import simulate
from models.notification import Body
from tests.models.lpm.helpers import bottoming_margin_m, occupant

RESTRAINTS = ((True, True), (True, False), (False, True), (False, False))
TRACKS_MM = (-120.0, 0.0, 120.0)
LEANS_DEG = (5.8, 25.0)
DELTA_V_KMH = (40.0, 80.0, 120.0)


@pytest.mark.parametrize("body", list(Body))
def test_head_centre_stays_inside_the_interior(params: ParameterSet, body: Body) -> None:
    """Every restraint, seat track, posture, 40-120 km/h: the head centre stays
    above the H-point's height (the seat and thighs are below it), and it
    does not pass the panel face (where the glass meets it) by more than the
    panel's give and crush stroke plus the 40 mm a 40 kN load travels into
    the bottoming spring (as in test_physics), less the head radius."""
    reach = (
        params["frontal.dash.give"]
        + params["frontal.dash.crush_stroke"]
        + bottoming_margin_m(params)
        - params[f"body.{body.value}.head_radius"]
    )
    panel_x = max(params["frontal.dash.x0"], params["frontal.dash.x1"]) + reach
    bad = []
    for (belted, bag), track, lean, dv in itertools.product(
        RESTRAINTS, TRACKS_MM, LEANS_DEG, DELTA_V_KMH
    ):
        occ = occupant(body, belted=belted, airbag=bag, lean_deg=lean, track_mm=track)
        r = simulate(*haversine_pulse(dv, 0.09), ImpactMode.FRONTAL, occ, params)
        assert r.status == 0
        z_min = float(np.min(r.histories["head_z_m"]))
        x_max = float(np.max(r.histories["head_x_m"])) + track / 1000.0  # seat -> vehicle
        if z_min < 0.0 or x_max > panel_x:
            bad.append(
                f"belt={belted} bag={bag} track={track} lean={lean} dv={dv}: "
                f"head centre down to {z_min:.2f} m, forward to {x_max:.2f} m"
            )
    assert bad == []
