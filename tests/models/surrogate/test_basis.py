"""Orthonormal bases: Stieltjes recurrences, multi-indices, design matrices."""

from __future__ import annotations

from math import comb

import numpy as np
import pytest

from models.offline.surrogate.build import latin_hypercube
from models.surrogate.basis import (
    design_matrix,
    evaluate_univariate,
    evaluate_univariate_at,
    hyperbolic_multi_indices,
    stieltjes,
    uniform_recurrence,
)


def test_stieltjes_on_gauss_legendre_is_legendre() -> None:
    nodes, weights = np.polynomial.legendre.leggauss(40)
    alpha, beta = stieltjes(nodes, weights, 15)
    a_ref, b_ref = uniform_recurrence(15)
    np.testing.assert_allclose(alpha, a_ref, atol=1e-13)
    np.testing.assert_allclose(beta, b_ref, rtol=1e-12)


def test_orthonormal_against_the_uniform_distribution() -> None:
    nodes, weights = np.polynomial.legendre.leggauss(40)
    rec = stieltjes(nodes, weights, 15)
    p = evaluate_univariate(nodes, rec, 15)
    gram = (p * (weights / 2.0)[:, None]).T @ p
    np.testing.assert_allclose(gram, np.eye(16), atol=1e-12)


def test_orthonormal_against_a_gaussian() -> None:
    # probabilists' Hermite: beta_k = k for the standard normal
    nodes, weights = np.polynomial.hermite_e.hermegauss(40)
    alpha, beta = stieltjes(nodes, weights, 12)
    np.testing.assert_allclose(alpha, 0.0, atol=1e-11)
    np.testing.assert_allclose(beta[1:], np.arange(1, 13), rtol=1e-10)


def test_apce_from_samples_is_orthonormal_for_the_samples() -> None:
    rng = np.random.default_rng(3)
    x = rng.gamma(2.0, size=2000)  # skewed data, no density family assumed
    z = 2.0 * (x - x.min()) / (x.max() - x.min()) - 1.0
    rec = stieltjes(z, None, 15)
    p = evaluate_univariate(z, rec, 15)
    np.testing.assert_allclose(p.T @ p / z.size, np.eye(16), atol=1e-9)


def test_matches_chaospy_stieltjes() -> None:
    chaospy = pytest.importorskip("chaospy")
    (alpha, beta), _, _ = chaospy.stieltjes(8, chaospy.Uniform(-1.0, 1.0))
    a, b = uniform_recurrence(8)
    np.testing.assert_allclose(np.ravel(alpha)[:9], a, atol=1e-10)
    np.testing.assert_allclose(np.ravel(beta)[1:9], b[1:], rtol=1e-8)


def test_too_few_points_raise() -> None:
    with pytest.raises(ValueError, match="too few"):
        stieltjes(np.array([0.0, 1.0, 0.0]), None, 3)


@pytest.mark.parametrize(("dim", "degree"), [(2, 5), (5, 4), (3, 15)])
def test_total_degree_counts(dim: int, degree: int) -> None:
    idx = hyperbolic_multi_indices(dim, degree, 1.0)
    assert idx.shape == (comb(dim + degree, degree), dim)
    assert np.all(idx[0] == 0)
    assert np.all(np.diff(idx.sum(axis=1)) >= 0)  # graded


def test_hyperbolic_truncation() -> None:
    idx = hyperbolic_multi_indices(5, 15, 0.5)
    q = np.sum(idx.astype(float) ** 0.5, axis=1) ** 2
    assert np.all(q <= 15 + 1e-9)
    assert idx.shape[0] == 446
    assert len({tuple(r) for r in idx}) == idx.shape[0]
    assert hyperbolic_multi_indices(5, 15, 0.5, max_interaction=1).shape[0] == 1 + 5 * 15


def test_multivariate_basis_on_lhs_is_nearly_orthonormal() -> None:
    rng = np.random.default_rng(0)
    z = 2.0 * latin_hypercube(4000, 3, rng) - 1.0
    recs = [stieltjes(z[:, j], None, 4) for j in range(3)]
    idx = hyperbolic_multi_indices(3, 4, 1.0)
    psi = design_matrix(z, recs, idx)
    np.testing.assert_allclose(psi.T @ psi / z.shape[0], np.eye(idx.shape[0]), atol=0.08)


def test_latin_hypercube_strata() -> None:
    u = latin_hypercube(50, 4, np.random.default_rng(1))
    for j in range(4):
        assert sorted(np.floor(u[:, j] * 50).astype(int).tolist()) == list(range(50))


def _column_by_column(x: np.ndarray, rec: tuple[np.ndarray, np.ndarray], degree: int) -> np.ndarray:
    """The recurrence as first written (columns of an (n, degree + 1) array): the reference."""
    alpha, beta = rec
    out = np.empty((x.size, degree + 1))
    out[:, 0] = 1.0
    if degree >= 1:
        out[:, 1] = (x - alpha[0]) / np.sqrt(beta[1])
    for k in range(1, degree):
        out[:, k + 1] = ((x - alpha[k]) * out[:, k] - np.sqrt(beta[k]) * out[:, k - 1]) / np.sqrt(
            beta[k + 1]
        )
    return out


@pytest.mark.parametrize("degree", [0, 1, 2, 7, 15])
def test_row_layout_and_scalar_path_give_the_same_bits(degree: int) -> None:
    """The request path's two evaluations agree bit for bit with the plain recurrence."""
    rng = np.random.default_rng(degree)
    z = 2.0 * rng.random(500) - 1.0
    rec = stieltjes(rng.gamma(2.0, size=800) / 8.0 - 1.0, None, 15)
    reference = _column_by_column(z, rec, degree)
    assert np.array_equal(evaluate_univariate(z, rec, degree), reference)
    for i in range(0, 500, 7):
        assert np.array_equal(evaluate_univariate_at(float(z[i]), rec, degree), reference[i])
