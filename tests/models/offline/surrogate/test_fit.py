"""Hybrid LAR, analytic leave-one-out, exact recovery of polynomials."""

from __future__ import annotations

import numpy as np
import pytest

from models.offline.surrogate.build import latin_hypercube
from models.offline.surrogate.fit import fit_adaptive, fit_degree, loo_error, nested_ols_loo
from models.surrogate.basis import design_matrix, hyperbolic_multi_indices, stieltjes


def _basis(n: int, dim: int, degree: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    z = 2.0 * latin_hypercube(n, dim, np.random.default_rng(seed)) - 1.0
    recs = [stieltjes(z[:, j], None, degree) for j in range(dim)]
    idx = hyperbolic_multi_indices(dim, degree, 0.75)
    return design_matrix(z, recs, idx), idx


def test_loo_formula_matches_brute_force() -> None:
    rng = np.random.default_rng(5)
    psi = rng.standard_normal((40, 6))
    y = psi @ rng.standard_normal(6) + 0.3 * rng.standard_normal(40)
    brute = []
    for i in range(40):
        keep = np.arange(40) != i
        c, *_ = np.linalg.lstsq(psi[keep], y[keep], rcond=None)
        brute.append((y[i] - psi[i] @ c) ** 2)
    expected = np.mean(brute) / np.var(y)
    assert abs(loo_error(psi, y) - expected) < 1e-10 * expected
    loo, _, _, _ = nested_ols_loo(psi, y)
    assert abs(loo[-1] - expected) < 1e-10 * expected
    # every nested set as well
    for k in (1, 3, 5):
        assert abs(loo[k - 1] - loo_error(psi[:, :k], y)) < 1e-10


def test_known_polynomial_is_recovered_exactly() -> None:
    psi, idx = _basis(300, 3, 6)
    counts = [int(np.sum(idx.sum(axis=1) <= d)) for d in range(7)]
    true_terms = np.array([0, 2, 7, 15])
    true_coef = np.array([1.5, -2.0, 0.7, 0.25])
    y = psi[:, true_terms] @ true_coef
    fit = fit_adaptive(psi, y, counts, 6)
    full = np.zeros(psi.shape[1])
    full[fit.terms] = fit.coef
    expected = np.zeros(psi.shape[1])
    expected[true_terms] = true_coef
    np.testing.assert_allclose(full, expected, atol=1e-9)
    assert fit.loo < 1e-12


def test_sparse_fit_of_a_smooth_function() -> None:
    psi, idx = _basis(400, 2, 12, seed=2)
    z = None  # noqa: F841
    counts = [int(np.sum(idx.sum(axis=1) <= d)) for d in range(13)]
    # y = exp of the first basis direction: smooth, not a polynomial
    y = np.exp(psi[:, 1] / 2.0) + 0.1 * psi[:, 2] ** 2
    fit = fit_adaptive(psi, y, counts, 12)
    assert fit.loo < 1e-6
    assert fit.terms.size < psi.shape[1]


def test_rank_deficient_is_infinite() -> None:
    psi = np.ones((10, 2))
    assert loo_error(psi, np.arange(10.0)) == float("inf")
    f = fit_degree(np.ones((10, 1)), np.arange(10.0))
    assert f.terms.tolist() == [0]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_lar_order_matches_scikit_learn(seed: int) -> None:
    """Our LAR (written for its low per-step overhead) selects in sklearn's order."""
    from sklearn.linear_model import lars_path

    from models.offline.surrogate.fit import lar_order

    rng = np.random.default_rng(seed)
    x = rng.standard_normal((80, 12))
    x -= x.mean(axis=0)
    x /= np.linalg.norm(x, axis=0)
    y = x[:, [1, 4, 7]] @ np.array([3.0, -2.0, 1.0]) + 0.05 * rng.standard_normal(80)
    y -= y.mean()
    _, active, _ = lars_path(x, y, method="lar", max_iter=8)
    ours = lar_order(x, y, 8)
    assert list(ours[: len(active)]) == list(active)[: len(ours)]
    assert set(ours[:3]) == {1, 4, 7}
