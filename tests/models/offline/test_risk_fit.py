"""The field risk fit's machinery: folds by crash, the recalibration, a reduced fit end to end.

The reduced fit (15 % of the crashes, 3 folds, 3 refits) runs the whole
tool as ``aacn-triage fit-field`` does and checks that the model card, the
README block and the artifact agree: every figure they print is the artifact's.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

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
    assert kinds <= {"logistic", "boosted"}
    assert model.decision.n_bootstrap == (2 if doc["outcomes"]["iss15"]["kind"] == "boosted" else 3)
    for o in doc["outcomes"].values():  # each kind was chosen on the lower held-out log loss
        assert o["selection"]["kind_loss"][o["kind"]] == min(o["selection"]["kind_loss"].values())
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
