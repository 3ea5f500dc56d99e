"""The field risk models (ISS 15+, regions, vehicle) as served, against the fit that made them.

The artifact loads and refuses tampering; answers are deterministic; risk rises
with delta-V and is lower when belted; every region answers; the served
probability equals the offline fit's (scikit-learn) prediction on the same
occupants, built once from the data file and once as a notification would be.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from models.field.risk_children import (
    ALL_COLUMNS_3,
    ChildRiskInputs,
    Restraint,
    design_columns_3,
)
from models.field.risk_features import (
    AirbagCode,
    RiskInputs,
    SeatSide,
    rcs_basis,
)
from models.field.risk_model import (
    OUTCOME,
    REGION_NAMES,
    RiskModel,
    canonical_content_sha256,
    default_artifact_path,
    load_default,
)
from models.offline.field.occupants import pdof_from_components_deg
from models.offline.field.risk_data import risk_arrays
from models.offline.field.risk_fit import RiskConfig, Spec, fit_spec, load_risk_data


@pytest.fixture(scope="module")
def model() -> RiskModel:
    return load_default()


def _driver(dv: float, **kw: object) -> RiskInputs:
    base: dict[str, object] = {
        "delta_v_kmh": dv,
        "pdof_deg": 0.0,
        "seat_row": 1,
        "seat_side": SeatSide.LEFT,
        "driver": True,
        "belted": True,
        "frontal_airbag": AirbagCode.DEPLOYED,
        "rollover": False,
        "multiple_impacts": False,
        "age_years": 40.0,
    }
    base.update(kw)
    return RiskInputs(**base)  # type: ignore[arg-type]


def test_the_shipped_artifact_loads_with_every_outcome(model: RiskModel) -> None:
    assert model.outcome == OUTCOME == "ISS15+"
    assert model.name == "field_iss15"
    assert model.version == "3.4.0"
    assert model.candidate_columns == ALL_COLUMNS_3
    assert set(model.regions) == set(REGION_NAMES)
    assert model.default_operating_point == "sens85"
    assert set(model.thresholds) == {"sens85", "acs_cot"}
    # ACS-COT finds more, so it flags at a lower probability
    assert model.threshold("acs_cot") < model.threshold("sens85")
    for r in model.regions.values():
        assert r.ais_level in (2, 3)
        assert r.n_bootstrap >= 2
    assert model.vehicle_bootstrap_calibration.shape == (model.decision.n_bootstrap, 2)


def test_a_tampered_or_stale_artifact_is_refused(tmp_path: Path) -> None:
    doc = json.loads(default_artifact_path().read_text(encoding="utf-8"))
    doc["outcomes"]["iss15"]["calibration"][1] += 0.1
    bad = tmp_path / "tampered.json"
    bad.write_text(json.dumps(doc), encoding="utf-8")
    with pytest.raises(ValueError, match="checksum"):
        RiskModel.from_artifact(bad)
    doc["feature_code_sha256"] = "0" * 64
    doc["content_sha256"] = canonical_content_sha256(doc)
    bad.write_text(json.dumps(doc), encoding="utf-8")
    with pytest.raises(ValueError, match="stale"):
        RiskModel.from_artifact(bad)


def test_answers_are_deterministic_bit_for_bit(model: RiskModel) -> None:
    again = RiskModel.from_artifact(default_artifact_path())
    a = model.predict(_driver(47.0, age_years=None))
    b = again.predict(_driver(47.0, age_years=None))
    assert a.probability == b.probability
    assert a.ci95 == b.ci95
    assert {k: v.probability for k, v in a.regions.items()} == {
        k: v.probability for k, v in b.regions.items()
    }
    assert model.vehicle([a, a]) == again.vehicle([b, b])


def test_risk_rises_with_delta_v_and_is_lower_belted(model: RiskModel) -> None:
    dvs = np.arange(5.0, 121.0, 5.0)
    for pdof, side in ((0.0, SeatSide.LEFT), (270.0, SeatSide.LEFT), (90.0, SeatSide.LEFT)):
        for belted in (True, False):
            ps = [
                p.probability
                for p in model.predict_many(
                    [_driver(float(v), pdof_deg=pdof, seat_side=side, belted=belted) for v in dvs]
                )
            ]
            assert np.all(np.diff(ps) >= 0.0), (pdof, belted)
    for dv in (20.0, 40.0, 60.0):
        assert (
            model.predict(_driver(dv, belted=True)).probability
            < model.predict(_driver(dv, belted=False)).probability
        )
    # older occupants are at higher risk at the same crash
    assert (
        model.predict(_driver(40.0, age_years=80.0)).probability
        > model.predict(_driver(40.0, age_years=25.0)).probability
    )


def test_every_region_answers_with_an_interval_holding_it(model: RiskModel) -> None:
    p = model.predict(_driver(55.0, pdof_deg=270.0, belted=False))
    assert set(p.regions) == set(REGION_NAMES)
    for name, r in p.regions.items():
        assert 0.0 < r.ci95[0] <= r.probability <= r.ci95[1] < 1.0, name
        assert r.ais_level == model.regions[name].ais_level
    assert p.ci95[0] <= p.probability <= p.ci95[1]
    # a near-side crash: the head risk above that of a frontal one at the same delta-V
    frontal = model.predict(_driver(55.0, belted=False))
    assert p.regions["head"].probability > frontal.regions["head"].probability


def test_unknown_inputs_are_integrated_or_imputed_and_named(model: RiskModel) -> None:
    """The occupant's unknown inputs are integrated over (feature set 3); the vehicle's
    (quarter turns of a rollover, model year) take the data's values, each named."""
    p = model.predict(
        _driver(30.0, age_years=None, rollover=True, model_year=None, stature_cm=None)
    )
    assert set(p.imputed) == {"quarter_turns", "model_year"} & model.used_inputs
    assert set(p.integrated) == {"age_years", "female", "stature_cm", "mass_kg"}
    assert {"age_years", "model_year"} <= model.used_inputs
    known = model.predict(
        _driver(
            30.0,
            age_years=40.0,
            rollover=True,
            quarter_turns=int(model.imputation.quarter_turns),
            model_year=int(model.imputation.model_year),
            female=False,
            stature_cm=175.0,
            mass_kg=80.0,
        )
    )
    assert known.imputed == ()
    assert known.integrated == ()
    assert known.unknown_inputs_range95 is None


def test_out_of_range_inputs_name_the_field(model: RiskModel) -> None:
    with pytest.raises(ValueError, match="delta_v_kmh"):
        model.predict(_driver(250.0))
    with pytest.raises(ValueError, match="age_years"):
        model.predict(_driver(30.0, age_years=-3.0))


def test_the_vehicle_answer_is_at_least_its_riskiest_occupants_rank(model: RiskModel) -> None:
    one = model.predict(_driver(50.0, belted=False))
    low = model.predict(_driver(50.0, seat_side=SeatSide.RIGHT, driver=False))
    v1 = model.vehicle([one])
    v2 = model.vehicle([one, low])
    assert v2.probability >= v1.probability
    assert v1.probability >= one.probability, "anyone is at least as likely as any one"
    assert v2.ci95[0] <= v2.probability <= v2.ci95[1]
    with pytest.raises(ValueError, match="at least one"):
        model.vehicle([])


def test_the_spline_is_linear_beyond_its_outer_knots() -> None:
    knots = (10.0, 18.0, 27.0, 52.0)
    x = np.array([60.0, 70.0, 80.0, 90.0])
    b = rcs_basis(x, knots)
    assert np.allclose(np.diff(b, n=2, axis=0), 0.0, atol=1e-12)
    assert np.all(rcs_basis(np.array([0.0, 5.0, 10.0]), knots) == 0.0)


# ------------------------------------------------------------- against the fit


@pytest.fixture(scope="module")
def data():  # type: ignore[no-untyped-def]
    return load_risk_data()


def _as_inputs(rows: pd.DataFrame) -> list[RiskInputs]:
    """The occupant file's rows as a notification would carry them (unknowns None)."""
    pdof = pdof_from_components_deg(
        rows["delta_v_long_kmh"].to_numpy(), rows["delta_v_lat_kmh"].to_numpy()
    )
    out = []
    for i, (_, r) in enumerate(rows.iterrows()):
        qt = r["rollover_quarter_turns"]

        def opt(v: float) -> float | None:
            return None if pd.isna(v) else float(v)

        out.append(
            ChildRiskInputs(
                delta_v_kmh=float(r["delta_v_kmh"]),
                pdof_deg=float(pdof[i]),
                seat_row=int(r["seat_row"]),
                seat_side=SeatSide(r["seat_side"]),
                driver=r["role"] == "driver",
                belted=r["belt"] == "belted",
                frontal_airbag=AirbagCode(r["frontal_airbag"]),
                rollover=bool(not pd.isna(qt) and qt > 0),
                multiple_impacts=bool(r["n_events"] >= 2),
                quarter_turns=None if pd.isna(qt) else int(qt),
                age_years=opt(r["age_years"]),
                female=None if pd.isna(r["female"]) else bool(r["female"]),
                stature_cm=opt(r["stature_cm"]),
                mass_kg=opt(r["mass_kg"]),
                model_year=None if pd.isna(r["model_year"]) else int(r["model_year"]),
                impact_count=int(r["n_events"]),
                restraint=Restraint(r["belt"]),
            )
        )
    return out


def _known(data) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Rows whose occupant inputs are all known (the others are integrated over when served,
    while the fit's rows take the age band's medians)."""
    rows = data.rows
    return np.flatnonzero(
        (rows[["age_years", "female", "stature_cm", "mass_kg"]].notna().all(axis=1)).to_numpy()
    )


def test_the_served_probability_is_the_fits_prediction(model: RiskModel, data) -> None:  # type: ignore[no-untyped-def]
    """On 300 occupants, the service's path (RiskInputs -> numpy) gives the probability of
    every outcome model evaluated on the fit's own design rows at the served accident year;
    each regression refitted as the artifact records it reproduces its coefficients and
    its scikit-learn prediction. (A boosted bag's evaluation against scikit-learn and its
    refit's reproducibility are tests of their own: ``test_boosted.py``.)"""
    doc = model.document
    cfg = RiskConfig(
        **{k: tuple(v) if isinstance(v, list) else v for k, v in doc["config"].items()}
    )
    if cfg.subsample < 1.0:
        pytest.skip("a reduced artifact: the data differ")
    rng = np.random.default_rng(3)
    pick = rng.choice(_known(data), 300, replace=False)
    served = model.predict_many(_as_inputs(data.rows.iloc[pick]))
    x = data.x[pick].copy()
    x[:, ALL_COLUMNS_3.index("accident_year")] = model.imputation.accident_year
    refitted = 0
    for name in ("iss15", *(f"region_{r}" for r in REGION_NAMES)):
        om = model.decision if name == "iss15" else model.regions[name.removeprefix("region_")]
        got = (
            [p.probability for p in served]
            if name == "iss15"
            else [p.regions[name.removeprefix("region_")].probability for p in served]
        )
        eta, boot = om.logits(x)
        if name == "iss15" and model.children is not None:  # the children's calibration
            eta, _ = model.children.apply(eta, boot, x)
        assert np.allclose(got, 1.0 / (1.0 + np.exp(-eta)), rtol=1e-9, atol=1e-12), name
        od = doc["outcomes"][name]
        carried = "regions_from" in doc and name != "iss15"  # fitted on that artifact's data
        if od["kind"] == "boosted" or refitted >= 2 or carried:
            continue
        o = next(o for o in data.outcomes if o.name == name)
        spec = Spec(
            tuple(od["groups"]),
            od["penalty_c"],
            doc["drift"]["chosen"],
            tree_groups=tuple(od.get("tree_groups", ())),
        )
        # a blend's regression part refits as a regression (its bag: test_boosted.py)
        f = fit_spec(data, o.y, np.arange(o.y.size), spec, cfg)
        lr = od if od["kind"] == "logistic" else od["logistic"]
        assert np.allclose(f.beta, lr["coefficients"], rtol=1e-6, atol=1e-9)  # type: ignore[union-attr]
        if od["kind"] == "logistic":
            assert np.allclose(got, f.probability(x), rtol=1e-7, atol=1e-10)
        else:
            part = om.logistic  # type: ignore[union-attr]
            assert np.allclose(part.logits(x)[0], f.logit(x), rtol=1e-7, atol=1e-9)
        refitted += 1
    assert refitted >= 1 or "regions_from" in doc


def test_data_and_notification_paths_build_the_same_design(model: RiskModel, data) -> None:  # type: ignore[no-untyped-def]
    rows = data.rows.iloc[_known(data)[:500]]
    from_data = design_columns_3(risk_arrays(rows, model.imputation))  # type: ignore[arg-type]
    from_inputs, _ = model.design(_as_inputs(rows))
    year = ALL_COLUMNS_3.index("accident_year")
    keep = [i for i in range(len(ALL_COLUMNS_3)) if i != year]
    assert np.allclose(from_data[:, keep], from_inputs[:, keep])
    assert np.all(from_inputs[:, year] == model.imputation.accident_year)
