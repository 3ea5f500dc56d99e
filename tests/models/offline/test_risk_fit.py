"""The field risk fit's machinery: folds by crash, the recalibration, a reduced fit end to end.

The reduced fit (15 % of the crashes, 3 folds, 3 refits) runs the whole
tool as ``aacn-triage fit-field`` does and checks that the model card, the
README block and the artifact agree: every figure they print is the artifact's.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from models.field.risk_impacts import ALL_COLUMNS_2
from models.field.risk_model import REGION_NAMES, RiskModel
from models.offline.field.risk_core import (
    crash_folds,
    expit,
    penalised_logistic,
    weighted_recalibration,
)
from models.offline.field.risk_fit import RiskConfig, load_risk_data
from models.offline.field.risk_metrics import crash_resamples


def test_folds_never_split_a_crash() -> None:
    d = load_risk_data(subsample=0.2, seed=1)
    folds = crash_folds(d.crash, 5, 7)
    seen = np.zeros(d.crash.size, dtype=int)
    for train, test in folds:
        assert not set(d.crash[train]) & set(d.crash[test])
        seen[test] += 1
    assert np.all(seen == 1)


def test_crash_resamples_take_whole_crashes() -> None:
    crash = np.array([0, 0, 1, 2, 2, 2, 3])
    for ix in crash_resamples(crash, 20, 3):
        ids, counts = np.unique(crash[ix], return_counts=True)
        full = np.bincount(crash)
        assert np.all(counts % full[ids] == 0)


def test_weighted_recalibration_recovers_a_known_shift() -> None:
    """Rows sampled with outcome-dependent weights (as NASS-CDS samples severe crashes):
    the unweighted fit's intercept is off by log(1/sampling ratio); the weighted
    recalibration recovers the population's intercept and slope."""
    rng = np.random.default_rng(5)
    n = 200_000
    x = rng.normal(size=n)
    y = (rng.random(n) < expit(-4.0 + 1.5 * x)).astype(float)
    keep = (y == 1) | (rng.random(n) < 0.1)  # every positive, a tenth of the negatives
    w = np.where(y[keep] == 1, 1.0, 10.0)
    beta = penalised_logistic(np.column_stack([np.ones(keep.sum()), x[keep]]), y[keep], None)
    assert beta[0] == pytest.approx(-4.0 + np.log(10.0), abs=0.1)
    eta = beta[0] + beta[1] * x[keep]
    a, b = weighted_recalibration(eta, y[keep], w)
    assert a + b * beta[0] == pytest.approx(-4.0, abs=0.1)
    assert b * beta[1] == pytest.approx(1.5, abs=0.1)


@pytest.mark.slow
def test_a_reduced_fit_writes_an_artifact_card_and_readme_block_that_agree(
    tmp_path: Path,
) -> None:
    from models.offline.field.readme import readme_block
    from models.offline.field.risk_report import acceptance, write_risk_model_card
    from models.offline.field.risk_run import fit_risk

    cfg = RiskConfig(
        subsample=0.15,
        n_splits=3,
        n_bootstrap=3,
        n_metric_bootstrap=10,
        boost_members=2,
        boost_tree_grid=(40, 80),
    )
    fit = fit_risk(cfg, cache_dir=tmp_path / "cache")
    doc = fit.artifact
    model = RiskModel.from_document(doc)
    assert set(model.regions) == set(REGION_NAMES)
    kinds = {o["kind"] for o in doc["outcomes"].values()}
    assert kinds <= {"logistic", "boosted", "blend"}
    with_trees = doc["outcomes"]["iss15"]["kind"] in ("boosted", "blend")
    assert model.decision.n_bootstrap == (2 if with_trees else 3)
    for o in doc["outcomes"].values():  # each kind was chosen on the lowest held-out log loss
        key = o["kind"] if o["kind"] != "blend" else f"blend_{o['weight_boosted']:g}"
        assert o["selection"]["kind_loss"][key] == min(o["selection"]["kind_loss"].values())
    # resumable: a second run reads every stage from the cache and gives the same document
    again = fit_risk(cfg, cache_dir=tmp_path / "cache")
    assert again.artifact == doc
    card = write_risk_model_card(fit, tmp_path / "card")
    text = card.read_text(encoding="utf-8")
    for item, _, figure in acceptance(doc):
        assert item in text
        assert figure in text
    for png in ("iss15_reliability.png", "iss15_risk_curves.png", "iss15_regions.png"):
        assert (tmp_path / "card" / png).stat().st_size > 1000
    iss = doc["outcomes"]["iss15"]
    assert f"{iss['heldout']['auc']:.3f}" in text
    # the risk tiers' held-out figures: the tiers partition the occupants
    tiers = doc["tiers"]["heldout"]
    assert sum(tiers[t]["n"] for t in ("high", "moderate", "none")) == doc["data"]["rows"]
    assert "## Risk tiers (held out)" in text
    assert "| OnStar ISP (published) | 40.0 % | 98.0 % |" in text
    assert doc["tiers"]["vehicle_at_high_threshold"]["threshold"] == 0.2
    example = {
        "probability": 0.01,
        "probability_ci95": [0.005, 0.02],
        "threshold": model.threshold(),
        "model": f"{model.name}@{model.version}",
        "operating_point": model.default_operating_point,
        "recommendation": "-",
    }
    block = readme_block(doc, example)
    assert f"{iss['heldout']['auc']:.3f}" in block
    assert f"{iss['plain']['auc']:.3f}" in block


def test_a_served_blend_is_the_fitted_blend_and_its_refits_share_the_bags_resamples() -> None:
    """A blend (regression and bag, calibrated logits weighted) as the artifact stores it
    answers as the fit predicts, and its interval's refits are the blend refitted on the
    bag's resamples of crashes (refit j and member j see the same crashes)."""
    from models.offline.field.risk_blend import BlendFitted
    from models.offline.field.risk_fit import Spec, fit_spec
    from models.offline.field.risk_run import _boosted_doc, _logistic_doc, blend_refits

    cfg = RiskConfig(boost_members=3)
    d = load_risk_data(subsample=0.05, seed=4)
    y = d.outcomes[0].y
    spec = Spec(("delta_v", "belt", "age"), 1.0, "none", "blend", 30, ("pdof_relative",), 0.5)
    rows = np.arange(y.size)
    f = fit_spec(d, y, rows, spec, cfg)
    assert isinstance(f, BlendFitted)
    boot = blend_refits(d, y, spec, cfg)
    assert boot[0].shape == (3, len(f.logistic.columns))
    od = {
        "label": "ISS15+",
        "ais_level": None,
        "kind": "blend",
        "weight_boosted": 0.5,
        "logistic": _logistic_doc(f.logistic, boot),
        "boosted": _boosted_doc(f.boosted),
    }
    od = json.loads(json.dumps(od))  # as written and read
    served = RiskModel._outcome("iss15", od, ALL_COLUMNS_2)
    eta, refits = served.logits(d.x)
    assert np.allclose(eta, f.logit(d.x), rtol=1e-9, atol=1e-9)
    assert refits.shape == (y.size, 3)
    # refit j: the regression refitted on member j's crashes, blended with member j
    ix = crash_resamples(d.crash, 3, cfg.seed)[1]
    lr1 = fit_spec(d, y, ix.astype(np.int64), spec.part("logistic"), cfg)
    member1 = f.boosted.member_logits(d.x)[:, 1]
    assert np.allclose(refits[:, 1], 0.5 * lr1.logit(d.x) + 0.5 * member1, atol=1e-8)
    # an artifact's blend weight outside (0, 1) is refused
    with pytest.raises(ValueError, match="weight_boosted"):
        RiskModel._outcome("iss15", {**od, "weight_boosted": 1.0}, ALL_COLUMNS_2)
