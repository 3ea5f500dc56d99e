"""The children's calibration as fitted offline: weighted score equations, adults untouched."""

from __future__ import annotations

import numpy as np
from scipy.special import expit

from models.field.risk_children import ALL_COLUMNS_3
from models.offline.field.risk_children_fit import (
    ChildrenAware,
    _apply,
    _fit,
    weighted_log_loss,
)


def _design(n: int, rng: np.random.Generator) -> np.ndarray:
    x = np.zeros((n, len(ALL_COLUMNS_3)))
    x[:, 0] = 1.0
    group = rng.integers(0, 3, n)
    for g, name in enumerate(("age_0_4", "age_5_9", "age_10_15")):
        x[group == g, ALL_COLUMNS_3.index(name)] = 1.0
    x[:, ALL_COLUMNS_3.index("child_seat")] = (group == 0) & (rng.random(n) < 0.8)
    return x


def test_the_weighted_fit_matches_each_groups_weighted_events() -> None:
    """Weighted maximum likelihood with group terms: sum w (y - p) = 0 in every group (the
    score equations), so the fitted sample's weighted predicted/observed is 1 per group."""
    rng = np.random.default_rng(7)
    n = 6000
    x = _design(n, rng)
    eta = rng.normal(-3.5, 1.2, n)
    shift = x[:, ALL_COLUMNS_3.index("age_0_4")] * 0.8 - x[:, ALL_COLUMNS_3.index("age_5_9")] * 0.6
    y = (rng.random(n) < expit(eta + shift)).astype(np.float64)
    w = rng.lognormal(0.0, 1.0, n)
    coef = _fit(eta, x, y, w)
    p = expit(_apply(coef, eta, x))
    for name in ("age_0_4", "age_5_9", "age_10_15", "child_seat"):
        m = x[:, ALL_COLUMNS_3.index(name)] > 0
        assert abs(np.sum(w[m] * p[m]) / np.sum(w[m] * y[m]) - 1.0) < 1e-6, name
    # and the shared logit miscalibrated by group is worse, by the weighted log loss
    assert weighted_log_loss(y, p, w) < weighted_log_loss(y, expit(eta), w)


class _Constant:
    """A fitted decision stand-in of known probability (the calibration's input)."""

    def probability(self, x_all: np.ndarray) -> np.ndarray:
        return np.full(x_all.shape[0], 0.02)


def test_children_aware_calibrates_child_rows_only() -> None:
    x = np.zeros((2, len(ALL_COLUMNS_3)))
    x[:, 0] = 1.0
    x[1, ALL_COLUMNS_3.index("age_5_9")] = 1.0
    coef = np.array([0.3, 1.0, -0.5, 0.0, 0.0])
    p = ChildrenAware(_Constant(), coef).probability(x)  # type: ignore[arg-type]
    assert p[0] == 0.02
    logit = np.log(0.02 / 0.98)
    assert abs(p[1] - expit(0.3 + logit - 0.5)) < 1e-12
