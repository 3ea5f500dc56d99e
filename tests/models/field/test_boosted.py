"""Bagged boosted trees: the served numpy evaluation against scikit-learn, the artifact form.

The service never imports scikit-learn: :class:`models.field.boosted.TreeBag`
evaluates the trees the offline fit exported. These tests hold the two to the
same raw scores (to rounding of the sums), trees stopped early by scikit-learn
(a leaf above the last level) included, and check that the stored form reads
back exactly and is refused when malformed.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

from models.field.boosted import ALWAYS_LEFT, TREE_DEPTH, TreeBag
from models.offline.field.risk_boosted import export_bag, fit_bag, single_boosted

NAMES = ("intercept", "a", "b", "c", "d")


def _data(n: int = 3000, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    x = np.column_stack([np.ones(n), rng.normal(size=(n, 3)), rng.integers(0, 2, n)])
    eta = -2.0 + 1.2 * x[:, 1] - 0.8 * x[:, 2] * x[:, 4] + 0.5 * np.abs(x[:, 3])
    y = (rng.random(n) < 1.0 / (1.0 + np.exp(-eta))).astype(float)
    crash = np.arange(n) // 2  # two occupants per crash
    return x, y, crash


def test_the_numpy_evaluation_is_scikit_learns() -> None:
    x, y, _ = _data()
    cols = [1, 2, 3, 4]
    members = []
    for seed, leaf in ((1, 20), (2, 400)):  # min_samples_leaf 400 stops some trees early
        m = single_boosted(60, seed)
        m.set_params(min_samples_leaf=leaf)
        members.append(m.fit(x[:, cols], y))
    bag = export_bag(members, cols)
    assert np.any(bag.thresholds == ALWAYS_LEFT), "an early leaf is padded"
    got = bag.member_scores(x)
    for j, m in enumerate(members):
        assert np.allclose(got[:, j], m.decision_function(x[:, cols]), rtol=0, atol=1e-12)
    assert bag.member_scores(x[:1]).shape == (1, 2)


def test_the_stored_form_reads_back_exactly_and_refuses_malformed() -> None:
    x, y, crash = _data(1500, 3)
    fitted = fit_bag(x, y, np.ones_like(y), crash, [1, 2, 3, 4], 30, 3, 5)
    doc = fitted.bag.to_document(NAMES)
    back = TreeBag.from_document(doc, NAMES, "t")
    assert back.columns == fitted.bag.columns
    for a in ("features", "thresholds", "leaves", "baselines"):
        assert np.array_equal(getattr(back, a), getattr(fitted.bag, a))
    assert np.array_equal(back.member_scores(x), fitted.bag.member_scores(x))
    bad = copy.deepcopy(doc)
    bad["depth"] = TREE_DEPTH + 1
    with pytest.raises(ValueError, match="depth"):
        TreeBag.from_document(bad, NAMES, "t")
    bad = copy.deepcopy(doc)
    bad["columns"] = ["a", "nope"]
    with pytest.raises(ValueError, match="columns"):
        TreeBag.from_document(bad, NAMES, "t")
    bad = copy.deepcopy(doc)
    bad["leaves"]["base64"] = bad["leaves"]["base64"][:-8]
    with pytest.raises(ValueError, match="leaves"):
        TreeBag.from_document(bad, NAMES, "t")
    bad = copy.deepcopy(doc)
    bad["columns"] = ["a"]  # splits name columns 1-3 of a one-column bag
    with pytest.raises(ValueError, match="column"):
        TreeBag.from_document(bad, NAMES, "t")


def test_a_bag_refit_is_bit_identical_and_ranks_the_signal() -> None:
    x, y, crash = _data(2000, 7)
    a = fit_bag(x, y, np.ones_like(y), crash, [1, 2, 3, 4], 40, 3, 11)
    b = fit_bag(x, y, np.ones_like(y), crash, [1, 2, 3, 4], 40, 3, 11)
    assert np.array_equal(a.bag.leaves, b.bag.leaves)
    assert a.calibration == b.calibration
    # the score rises with the feature of positive effect, all else at the median
    probe = np.tile(np.median(x, axis=0), (5, 1))
    probe[:, 1] = np.linspace(-2.0, 2.0, 5)
    assert np.all(np.diff(a.probability(probe)) >= 0.0)
    assert a.probability(probe)[-1] > a.probability(probe)[0] + 0.2
    # out-of-bag recalibration: the mean prediction matches the observed rate
    assert a.probability(x).mean() == pytest.approx(y.mean(), rel=0.15)


def test_repeated_rows_score_as_each_row_alone() -> None:
    """Rows walked once per distinct row give each row the bits of its own walk."""
    x, y, crash = _data(1500, 5)
    bag = fit_bag(x, y, np.ones_like(y), crash, [1, 2, 3, 4], 30, 3, 5).bag
    rng = np.random.default_rng(6)
    rows = x[rng.integers(0, 12, size=64)]  # 64 rows, at most 12 distinct
    rows[7, 3] = np.nan  # a distinct row (NaN goes left at every split)
    got = bag.member_scores(rows)
    alone = np.concatenate([bag.member_scores(r[None, :]) for r in rows])
    assert np.array_equal(got, alone, equal_nan=True)
