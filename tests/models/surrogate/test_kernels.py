"""The surrogates' compiled loops equal the numpy/scipy expressions they replace, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.sparse import csr_array

from models.surrogate.family import linear_percentiles
from models.surrogate.kernels import (
    add_correction,
    gather_p_sets,
    grouped_coefficients,
    matern32_in_place,
    pooled_order_statistics,
    warm_up,
)


@pytest.mark.parametrize("density", [0.0, 0.17, 1.0])
def test_grouped_coefficients_is_the_csr_product(density: float) -> None:
    rng = np.random.default_rng(11)
    n_terms, n_cols = 300, 151 * 6
    coef = rng.normal(size=(n_terms, n_cols)) * (rng.random((n_terms, n_cols)) < density)
    sizes = rng.integers(1, 12, size=60)
    group_ptr = np.concatenate([[0], np.cumsum(sizes)])
    group_ptr = group_ptr[group_ptr < n_terms]
    group_ptr = np.append(group_ptr, n_terms).astype(np.int64)
    factors = rng.normal(size=n_terms) * 10.0 ** rng.uniform(-8, 3, size=n_terms)
    n_groups = group_ptr.size - 1
    reference = np.asarray(
        csr_array((factors, np.arange(n_terms), group_ptr), shape=(n_groups, n_terms)) @ coef
    )
    rows, cols = np.nonzero(coef)
    ptr = np.searchsorted(rows, np.arange(n_terms + 1)).astype(np.int64)
    out = grouped_coefficients(
        factors, group_ptr, ptr, cols.astype(np.int64), coef[rows, cols], n_cols
    )
    assert out.shape == (n_groups, n_cols)
    assert np.array_equal(out, reference)


def test_matern32_is_the_numpy_expression() -> None:
    rng = np.random.default_rng(12)
    q = rng.uniform(-3, 3, size=(97, 5))
    s = np.concatenate([rng.uniform(-3, 3, size=(400, 5)), q[:3]])  # exact zero distances too
    q_sq, s_sq = np.einsum("ij,ij->i", q, q), np.einsum("ij,ij->i", s, s)
    r = q @ s.T
    r *= -2.0
    r += q_sq[:, None]
    r += s_sq[None, :]
    np.maximum(r, 0.0, out=r)
    np.sqrt(r, out=r)
    e = np.exp(np.negative(r))
    reference = (r + 1.0) * e
    out = matern32_in_place(q @ s.T, q_sq, s_sq)
    assert np.array_equal(out, reference)
    assert np.all(out > 0.0)
    assert np.all(out <= 1.0)
    # at a design point itself r = 0 and k = 1 (up to the expanded form's cancellation)
    assert np.allclose(out[np.arange(3), 400 + np.arange(3)], 1.0, rtol=0.0, atol=1e-6)


def test_warm_up_runs() -> None:
    warm_up()


@pytest.mark.parametrize("degree", [0, 1, 2, 15])
def test_univariate_rows_is_the_numpy_recurrence(degree: int) -> None:
    from models.surrogate.basis import evaluate_univariate

    rng = np.random.default_rng(13 + degree)
    x = rng.uniform(-1.5, 1.5, size=2000)
    alpha = rng.normal(scale=0.1, size=degree + 3)
    beta = rng.uniform(0.1, 0.5, size=degree + 3)
    # the array form the compiled loop replaces, degree by degree
    sq = [math.sqrt(float(b)) for b in beta[: degree + 1]]
    rows = np.empty((degree + 1, x.size))
    rows[0] = 1.0
    if degree >= 1:
        rows[1] = (x - alpha[0]) / sq[1]
    for k in range(1, degree):
        rows[k + 1] = ((x - alpha[k]) * rows[k] - sq[k] * rows[k - 1]) / sq[k + 1]
    assert np.array_equal(evaluate_univariate(x, (alpha, beta), degree), rows.T)
    with pytest.raises(ValueError, match="coefficients"):
        evaluate_univariate(x, (alpha[:degree], beta[:degree]), degree)


@pytest.mark.parametrize("transposed", [False, True])
def test_gather_p_sets_is_the_numpy_gather(transposed: bool) -> None:
    """The copy of the P sets equals numpy's fancy indexing, in either memory layout."""
    rng = np.random.default_rng(5)
    raw = (
        rng.normal(size=(97, 6, 151)).transpose(1, 2, 0)
        if transposed
        else rng.normal(size=(6, 151, 97))
    )
    rows = np.array([0, 1, 2, 3, 5])
    subset = np.arange(0, 96, 4)
    reference = np.concatenate(
        (raw[rows, 0, 1:], raw[:, 1:, 1 + subset][rows].reshape(rows.size, -1)), axis=1
    )
    assert np.array_equal(gather_p_sets(raw, rows, subset), reference)


def test_linear_percentiles_are_numpy_percentile() -> None:
    """Sizes 1 to 300, ties, the interval's (2.5, 97.5) and random percents, 0 and 100."""
    rng = np.random.default_rng(8)
    for trial in range(3000):
        x = rng.normal(size=int(rng.integers(1, 301)))
        if trial % 3 == 0:
            x = np.round(x, 1)  # ties
        percents = (2.5, 97.5) if trial % 2 else (0.0, *rng.uniform(0, 100, 3), 100.0)
        assert np.array_equal(np.array(linear_percentiles(x, percents)), np.percentile(x, percents))


@pytest.mark.parametrize("transposed", [False, True])
def test_add_correction_is_the_broadcast_add(transposed: bool) -> None:
    rng = np.random.default_rng(9)
    out = (
        rng.normal(size=(97, 6, 151)).transpose(1, 2, 0)
        if transposed
        else rng.normal(size=(6, 151, 97))
    )
    corr = rng.normal(size=(97, 6)) * 1e-3
    expected = out + corr.T[:, None, :]
    add_correction(out, corr)
    assert np.array_equal(out, expected)


def _partition_statistics(raw: np.ndarray, k_lo: int, k_hi: int) -> tuple[np.ndarray, ...]:
    pooled = np.array(raw[:, 1:, 1:]).reshape(raw.shape[0], -1)
    return (
        np.partition(pooled, k_lo, axis=1)[:, k_lo],
        np.partition(pooled, k_hi, axis=1)[:, k_hi],
    )


def test_pooled_order_statistics_are_numpy_partition() -> None:
    """Any shape, either memory layout, ties, constant and sorted pools, extreme ranks."""
    rng = np.random.default_rng(21)
    for trial in range(300):
        shape = (int(rng.integers(1, 7)), int(rng.integers(2, 160)), int(rng.integers(2, 100)))
        raw = rng.normal(size=shape) * 10.0 ** rng.uniform(-3, 3)
        if trial % 4 == 1:
            raw = np.round(raw, 1)  # ties
        if trial % 4 == 2:  # the samples' axis outermost (a product's transpose)
            raw = np.ascontiguousarray(raw.transpose(2, 0, 1)).transpose(1, 2, 0)
        if trial % 7 == 3:
            raw[:] = 2.0
        if trial % 5 == 4:
            raw = np.sort(raw, axis=2)
        n = (shape[1] - 1) * (shape[2] - 1)
        interval = (max(math.ceil(0.025 * n) - 1, 0), max(math.ceil(0.975 * n) - 1, 0))
        some = tuple(int(k) for k in sorted(rng.integers(0, n, 2)))
        for k_lo, k_hi in (interval, (0, n - 1), some):
            lo, hi, finite = pooled_order_statistics(raw, k_lo, k_hi)
            ref_lo, ref_hi = _partition_statistics(raw, k_lo, k_hi)
            assert finite
            assert np.array_equal(lo, ref_lo), (trial, shape, k_lo)
            assert np.array_equal(hi, ref_hi), (trial, shape, k_hi)


def test_pooled_order_statistics_refuse_a_nan() -> None:
    raw = np.random.default_rng(22).normal(size=(3, 20, 30))
    raw[1, 4, 5] = np.nan
    assert not pooled_order_statistics(raw, 10, 500)[2]
    raw[1, 4, 5] = 0.0
    raw[:, 0, :] = np.nan  # the point PCE and the reading are not in the pool
    raw[:, :, 0] = np.nan
    assert pooled_order_statistics(raw, 10, 500)[2]
