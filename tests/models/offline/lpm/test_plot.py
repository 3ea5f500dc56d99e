"""The simulation plot (`aacn-triage simulate --plot`) shows what the measures are."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from models.impact_mode import ImpactMode
from models.lpm.params import ParameterSet
from models.lpm.pulses import ncap_frontal_pulse, side_pulse
from models.lpm.simulate import simulate
from models.notification import Body
from models.offline.lpm.plot import _nij_terms, plot_simulation
from tests.models.lpm.helpers import occupant


@pytest.mark.parametrize(
    ("mode", "pulse"),
    [(ImpactMode.FRONTAL, ncap_frontal_pulse()), (ImpactMode.NEAR_SIDE, side_pulse())],
)
@pytest.mark.parametrize("body", list(Body))
def test_the_plotted_nij_terms_peak_at_the_reported_nij(
    params: ParameterSet, mode: ImpactMode, pulse: tuple[np.ndarray, ...], body: Body
) -> None:
    """Each term over its own-sign intercept, at the occipital condyle, filtered
    at CFC 600: their sum peaks at the Nij the result reports."""
    r = simulate(*pulse, mode, occupant(body), params)
    t_ms = 1000.0 * (np.arange(r.histories["neck_fz_n"].size) * 1e-4)
    n_force, n_moment = _nij_terms(r.histories, t_ms, body)
    assert np.all(n_force >= 0.0)
    assert np.all(n_moment >= 0.0)
    assert float(np.max(n_force + n_moment)) == pytest.approx(r.measures.nij, rel=1e-12)


def test_the_plot_is_drawn(params: ParameterSet, tmp_path: Path) -> None:
    r = simulate(*side_pulse(), ImpactMode.NEAR_SIDE, occupant(Body.FEMALE_5TH), params)
    out = plot_simulation(r, tmp_path / "sim.png", body=Body.FEMALE_5TH)
    assert out.stat().st_size > 10_000
