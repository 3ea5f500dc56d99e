"""Trends over delta-V, restraints, occupants and posture (issue 4, "Done when")."""

from __future__ import annotations

import pytest

from models.impact_mode import ImpactMode
from models.injury.assessment import InjuryMeasures
from models.lpm.domain import SEAT_TRACK_RANGE_MM
from models.lpm.params import ParameterSet
from models.lpm.pulses import haversine_pulse, ncap_frontal_pulse, side_pulse
from models.lpm.simulate import LpmResult, head_clearance_mm, simulate
from models.notification import Body, Occupant
from tests.models.lpm.helpers import occupant

#: Relative tolerance of the monotonicity checks. Restraint interactions make
#: some measures flat over part of the grid (the airbag's constant-force
#: plateau, a load-limited belt); 5 % absorbs those plateaus, not real drops.
MONO_RTOL = 0.05
#: Absolute floors below which a measure is considered zero (HIC, Nij, mm, m/s, g, -, m/s).
FLOORS = {
    "hic15": 20.0,
    "nij": 0.05,
    "chest_deflection_mm": 2.0,
    "chest_vc_m_s": 0.05,
    "chest_a3ms_g": 2.0,
    "chest_cti": 0.05,
    "abdomen_vc_m_s": 0.05,
}


def _values(m: InjuryMeasures) -> dict[str, float]:
    return {k: v for k, v in vars(m).items() if v is not None}


def _check_monotone(rows: list[dict[str, float]], label: str) -> list[str]:
    bad = []
    for a, b in zip(rows, rows[1:], strict=False):
        for k, va in a.items():
            vb = b[k]
            if va > FLOORS[k] and vb < va * (1.0 - MONO_RTOL):
                bad.append(f"{label} {k}: {va:.3f} -> {vb:.3f}")
    return bad


def _known(reason: str) -> pytest.MarkDecorator:
    """A documented model deficiency (open item in docs/lpm/notes.md)."""
    return pytest.mark.xfail(strict=True, reason=reason)


#: Forward-lean cases whose HIC15 or ISS point estimate is lower than neutral
#: although P(ISS >= 15) rises, with the reason.
LEAN_REASONS = {
    (Body.MALE_50TH, False, True): (
        "open item: the unbelted 50M leaning forward meets the airbag earlier, at a lower"
        " relative speed (HIC15 522 -> 447, ISS 10 -> 9), while Nij (1.18 -> 1.95), his"
        " head/neck AIS (1 -> 3) and P(ISS >= 15) (0.40 -> 0.55) rise; the ISS falls"
        " because his chest P(AIS >= 3) falls from 0.56 to 0.44 (deflection 49.2 -> 47.6"
        " mm), across the 0.5 at which the AIS point estimate is taken (3 -> 0). Static"
        " out-of-position deployments of a depowered driver bag on the Hybrid III 5F"
        " likewise predicted neck, not head, injury (wbldb.lievers.net/10046761); the"
        " punch-out itself is crudely modelled"
    ),
}

#: Every frontal restraint configuration of both bodies. Until the interior was
#: closed (2026-12-01: the glass down to the panel, crush strokes, the thighs)
#: the two unrestrained ones were strict xfails: HIC15 fell 2997 -> 1071 (50M)
#: and 4002 -> 1932 (5F) over 60-120 km/h as the head slid off the wheel and
#: left the modelled interior over the panel top or under the wheel.
FRONTAL_GRID = [
    (b, belt, bag)
    for b in Body
    for belt, bag in ((True, True), (True, False), (False, True), (False, False))
]


@pytest.mark.parametrize(("body", "belted", "airbag"), FRONTAL_GRID)
def test_frontal_measures_do_not_decrease_with_delta_v(
    params: ParameterSet, body: Body, belted: bool, airbag: bool
) -> None:
    """20-120 km/h in 10 km/h steps, every restraint configuration."""
    # firing times fixed so that only delta-V changes ("other inputs fixed")
    occ = occupant(body, belted=belted, airbag=airbag, fire_ms=20.0, pretensioner=True)
    rows = [
        _values(simulate(*haversine_pulse(dv, 0.09), ImpactMode.FRONTAL, occ, params).measures)
        for dv in range(20, 130, 10)
    ]
    assert _check_monotone(rows, f"{body} belt={belted} bag={airbag}") == []


@pytest.mark.parametrize(
    ("body", "mode"),
    [
        pytest.param(
            b,
            m,
            marks=(),
        )
        for b in Body
        for m in (ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE, ImpactMode.REAR)
    ],
)
def test_side_and_rear_measures_do_not_decrease_with_delta_v(
    params: ParameterSet, body: Body, mode: ImpactMode
) -> None:
    occ = occupant(body)
    rows = []
    for dv in (20.0, 30.0, 40.0, 50.0):
        if mode is ImpactMode.REAR:
            pulse = haversine_pulse(dv, 0.09, angle_deg=180.0)
        else:
            pulse = side_pulse(dv * 1500.0 / 2600.0, 0.06)  # barrier speed -> car delta-V
        rows.append(_values(simulate(*pulse, mode, occ, params).measures))
    assert _check_monotone(rows, f"{body} {mode}") == []


def _frontal(params: ParameterSet, occ: Occupant) -> InjuryMeasures:
    return simulate(*ncap_frontal_pulse(), ImpactMode.FRONTAL, occ, params).measures


#: The frontal head and chest measures (models.lpm.simulate frontal measures).
FRONTAL_HEAD_AND_CHEST = ("hic15", "nij", "chest_deflection_mm", "chest_vc_m_s", "chest_a3ms_g")


@pytest.mark.parametrize("body", list(Body))
@pytest.mark.parametrize("lean_deg", [5.8, 25.0])
def test_belt_lowers_head_and_chest_measures_at_56_kmh(
    params: ParameterSet, body: Body, lean_deg: float
) -> None:
    """With the airbag, the belt lowers every frontal head and chest measure, in the
    neutral and in the forward-leaning posture."""
    with_belt = _frontal(params, occupant(body, belted=True, airbag=True, lean_deg=lean_deg))
    without = _frontal(params, occupant(body, belted=False, airbag=True, lean_deg=lean_deg))
    for k in FRONTAL_HEAD_AND_CHEST:
        assert getattr(with_belt, k) < getattr(without, k), k


@pytest.mark.parametrize("body", list(Body))
def test_airbag_lowers_every_head_and_chest_measure_leaning_forward(
    params: ParameterSet, body: Body
) -> None:
    """Leaning forward 25 deg, the belted driver of either size meets the wheel
    without the bag, and the bag lowers every frontal head and chest measure,
    3 ms chest acceleration included (the neutral 5F: the open items below)."""
    with_bag = _frontal(params, occupant(body, belted=True, airbag=True, lean_deg=25.0))
    no_bag = simulate(
        *ncap_frontal_pulse(),
        ImpactMode.FRONTAL,
        occupant(body, belted=True, airbag=False, lean_deg=25.0),
        params,
    )
    assert head_clearance_mm(no_bag) < 0.0, "without the bag the head reaches the interior"
    for k in FRONTAL_HEAD_AND_CHEST:
        assert getattr(with_bag, k) < getattr(no_bag.measures, k), k


#: Seat track of each dummy in the regulatory 56 km/h full-frontal test, mm forward
#: of mid track: the 50th male at mid track (NCAP), the 5th female with the seat
#: moved to its full-forward position (FMVSS 208 S16.2.10, 49 CFR 571.208; NHTSA
#: interpretation 06-002617as on positioning her "while moving the seat
#: forward"), the front end of the default set's track
#: (models.lpm.domain.SEAT_TRACK_RANGE_MM).
REGULATORY_TRACK_MM = {Body.MALE_50TH: 0.0, Body.FEMALE_5TH: SEAT_TRACK_RANGE_MM[1]}


#: The measures the airbag must not raise at the regulatory seating (issue 23, item 9).
AIRBAG_CRITERION = ("hic15", "nij", "chest_deflection_mm", "chest_vc_m_s")


def _regulatory(params: ParameterSet, body: Body, airbag: bool) -> LpmResult:
    return simulate(
        *ncap_frontal_pulse(),
        ImpactMode.FRONTAL,
        occupant(body, belted=True, airbag=airbag, track_mm=REGULATORY_TRACK_MM[body]),
        params,
    )


@pytest.mark.parametrize("body", list(Body))
def test_airbag_does_not_raise_any_measure_at_the_regulatory_seating(
    params: ParameterSet, body: Body
) -> None:
    """The airbag check of the occupant models: each dummy at its regulatory seating
    (Hybrid III 50th male at mid track, 5th female full forward), belted, in the 56 km/h
    NCAP pulse; belt + airbag against belt alone must not raise HIC15, Nij, chest
    deflection, chest VC or P(ISS >= 15). Measured: 50M HIC15 824 -> 173, Nij 0.90 ->
    0.38, deflection 29.2 -> 27.9 mm, VC 0.13 -> 0.09 m/s, P 0.19 -> 0.09; 5F HIC15 444 ->
    371, Nij 0.98 -> 0.63, deflection 29.3 -> 27.3 mm, VC 0.19 -> 0.15 m/s, P 0.20 -> 0.13."""
    with_bag = _regulatory(params, body, airbag=True)
    without = _regulatory(params, body, airbag=False)
    for k in AIRBAG_CRITERION:
        assert getattr(with_bag.measures, k) <= getattr(without.measures, k), k
    assert with_bag.assessment is not None
    assert without.assessment is not None
    assert with_bag.assessment.p_iss15 <= without.assessment.p_iss15


@pytest.mark.parametrize("body", list(Body))
def test_chest_acceleration_with_the_airbag_is_reported_not_required_to_fall(
    params: ParameterSet, body: Body, record_property: pytest.RecordProperty
) -> None:
    """The 3 ms chest acceleration at the regulatory seating, with and without the bag,
    is reported (JUnit properties), not required to fall: published belt + bag tests show
    it does not (adding a bag to the belt did not lower the dummy's chest g, SAE 851247,
    1985; NHTSA's 1984 35 mph test of a Mercedes 300SD measured 63 g for the belted
    driver with the bag against 44 g for the belt-only passenger). Measured: 50M 45.8 ->
    45.5 g; 5F 49.6 -> 53.7 g (the bag's chest plateau on her lighter thorax, while her
    deflection and VC fall)."""
    with_bag = _regulatory(params, body, airbag=True).measures.chest_a3ms_g
    without = _regulatory(params, body, airbag=False).measures.chest_a3ms_g
    assert with_bag is not None
    assert without is not None
    record_property(f"chest_a3ms_g_{body.value}_belt_only", round(without, 2))
    record_property(f"chest_a3ms_g_{body.value}_belt_and_bag", round(with_bag, 2))
    assert 0.0 < with_bag < 80.0, "within the range of belted 56 km/h tests"
    assert 0.0 < without < 80.0


@pytest.mark.parametrize("body", list(Body))
def test_airbag_lowers_chest_deflection_and_vc_at_56_kmh(params: ParameterSet, body: Body) -> None:
    """With the bag the belt load limit is the airbag car's (4 kN instead of 5 kN)
    and the bag spreads its chest load over the thorax and shoulders
    (``frontal.airbag.chest_sternum_share``), so the sternum deflects less
    than with the belt alone, and more slowly (VC)."""
    with_bag = _frontal(params, occupant(body, belted=True, airbag=True))
    without = _frontal(params, occupant(body, belted=True, airbag=False))
    assert with_bag.chest_deflection_mm is not None
    assert without.chest_deflection_mm is not None
    assert with_bag.chest_deflection_mm < without.chest_deflection_mm
    assert with_bag.chest_vc_m_s is not None
    assert without.chest_vc_m_s is not None
    assert with_bag.chest_vc_m_s < without.chest_vc_m_s


LEAN_GRID = [
    (b, belt, bag) for b in Body for belt, bag in ((True, True), (True, False), (False, True))
]


def _neutral_and_leaning(
    params: ParameterSet, body: Body, belted: bool, airbag: bool
) -> tuple[LpmResult, LpmResult]:
    return tuple(  # type: ignore[return-value]
        simulate(
            *ncap_frontal_pulse(),
            ImpactMode.FRONTAL,
            occupant(body, belted=belted, airbag=airbag, lean_deg=lean),
            params,
        )
        for lean in (5.8, 25.0)
    )


@pytest.mark.parametrize(("body", "belted", "airbag"), LEAN_GRID)
def test_forward_leaning_is_not_safer_than_neutral(
    params: ParameterSet, body: Body, belted: bool, airbag: bool
) -> None:
    """Safety as the service judges it: the probability of ISS >= 15 (the
    triage decision) and the worst neck load (Nij) do not fall when the
    occupant leans forward 25 deg in the 56 km/h NCAP pulse."""
    neutral, leaning = _neutral_and_leaning(params, body, belted, airbag)
    assert neutral.assessment is not None
    assert leaning.assessment is not None
    assert leaning.assessment.p_iss15 >= neutral.assessment.p_iss15 - 1e-9
    assert leaning.measures.nij is not None
    assert neutral.measures.nij is not None
    assert leaning.measures.nij >= neutral.measures.nij


@pytest.mark.parametrize(("body", "belted", "airbag"), LEAN_GRID)
def test_forward_leaning_does_not_lower_the_head_and_neck_ais(
    params: ParameterSet, body: Body, belted: bool, airbag: bool
) -> None:
    """The head/neck region's AIS point estimate does not fall when the occupant
    leans forward 25 deg (it rises in all six configurations: 0 -> 1, 2 -> 4,
    1 -> 3, 0 -> 1, 0 -> 2, 3 -> 4), the unbelted 50M with the bag included,
    whose HIC15 falls while his Nij rises (the open item below)."""
    neutral, leaning = _neutral_and_leaning(params, body, belted, airbag)
    assert neutral.assessment is not None
    assert leaning.assessment is not None
    assert leaning.assessment.region_ais["head_neck"] >= neutral.assessment.region_ais["head_neck"]


@pytest.mark.parametrize(
    ("body", "belted", "airbag"),
    [
        pytest.param(*c, marks=_known(LEAN_REASONS[c]) if c in LEAN_REASONS else ())
        for c in LEAN_GRID
    ],
)
def test_forward_leaning_does_not_lower_hic_or_iss(
    params: ParameterSet, body: Body, belted: bool, airbag: bool
) -> None:
    """Stricter: no single measure improves either (HIC15 within 5 %, ISS)."""
    neutral, leaning = _neutral_and_leaning(params, body, belted, airbag)
    assert neutral.assessment is not None
    assert leaning.assessment is not None
    assert leaning.assessment.iss >= neutral.assessment.iss
    assert leaning.measures.hic15 is not None
    assert neutral.measures.hic15 is not None
    assert leaning.measures.hic15 >= 0.95 * neutral.measures.hic15


def test_posture_and_seat_track_change_the_gaps(params: ParameterSet) -> None:
    base = simulate(*ncap_frontal_pulse(), ImpactMode.FRONTAL, occupant(), params)
    fwd = simulate(*ncap_frontal_pulse(), ImpactMode.FRONTAL, occupant(track_mm=80.0), params)
    lean = simulate(*ncap_frontal_pulse(), ImpactMode.FRONTAL, occupant(lean_deg=25.0), params)
    # leaning moves the head forward at t = 0; the seat track changes contact timing
    assert lean.histories["head_x_m"][0] > base.histories["head_x_m"][0] + 0.1
    t_knee = [
        float(r.time_s[(r.histories["force_knee_bolster_n"] > 0).argmax()]) for r in (base, fwd)
    ]
    assert t_knee[1] < t_knee[0]
