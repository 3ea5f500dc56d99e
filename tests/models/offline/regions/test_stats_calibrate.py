"""The crash bootstrap and the added-value test of calibrated measures, on synthetic crashes."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from sklearn.metrics import roc_auc_score

from models.offline.regions.calibrate import added_value, crash_folds
from models.offline.regions.stats import CrashBootstrap, crash_ids, weighted_auc


def _crashes(n_crash: int = 1500, seed: int = 0) -> pd.DataFrame:
    """Two occupants per crash; the outcome depends on delta-V and on a crash-level load."""
    rng = np.random.default_rng(seed)
    crash = np.repeat(np.arange(n_crash), 2)
    dv = np.repeat(rng.uniform(5, 70, n_crash), 2)
    load = np.repeat(rng.normal(0, 1, n_crash), 2)  # what delta-V does not see
    eta = -7.0 + 0.08 * dv + 1.2 * load
    y = rng.random(crash.size) < 1 / (1 + np.exp(-eta))
    return pd.DataFrame(
        {
            "year": 2000 + crash % 15,
            "psu": crash % 24,
            "caseno": crash,
            "crash": crash,
            "ratwgt": rng.uniform(1, 50, crash.size),
            "delta_v_kmh": dv,
            "mode": np.where(crash % 5 == 0, "near_side", "frontal"),
            "belted": 1,
            "age_years": 40.0,
            "female": 0.0,
            "frontal_airbag": "deployed",
            "rollover": 0,
            "multiple_impacts": 0,
            "signal": np.exp(load + 3.0),  # a measure that carries the hidden load
            "noise": rng.lognormal(3.0, 1.0, crash.size),  # one that carries nothing
            "y": y.astype(float),
        }
    )


def test_weighted_auc_is_sklearns() -> None:
    f = _crashes(300)
    w = f["ratwgt"].to_numpy()
    assert weighted_auc(f["y"].to_numpy(), f["delta_v_kmh"].to_numpy(), w) == pytest.approx(
        roc_auc_score(f["y"], f["delta_v_kmh"], sample_weight=w)
    )


def test_the_bootstrap_resamples_whole_crashes_and_covers_the_estimate() -> None:
    f = _crashes(600)
    boot = CrashBootstrap(f["crash"].to_numpy(), f["ratwgt"].to_numpy(), replicates=50, seed=1)
    counts = boot.weights(survey=False)
    assert np.all(counts[:, 0::2] == counts[:, 1::2])  # both occupants of a crash together
    assert np.allclose(counts.sum(axis=1), len(f))
    y = f["y"].to_numpy()
    iv = boot.interval(lambda w: float(np.average(y, weights=w)))
    assert iv.low < iv.value < iv.high
    assert iv.value == pytest.approx(np.average(y, weights=f["ratwgt"]))


def test_folds_keep_each_crash_on_one_side() -> None:
    f = _crashes(400)
    fold = crash_folds(crash_ids(f))
    assert set(np.unique(fold)) == {0, 1, 2, 3, 4}
    assert np.all(fold[0::2] == fold[1::2])


@pytest.mark.slow
def test_a_measure_that_carries_the_hidden_load_adds_and_noise_does_not() -> None:
    f = _crashes()
    fold = crash_folds(f["crash"].to_numpy())
    y = f["y"].to_numpy()
    real = added_value(f, y, "synthetic", ["signal"], fold)
    assert real.adds
    assert real.difference.low > 0.02
    noise = added_value(f, y, "synthetic", ["noise"], fold)
    assert not noise.adds
