"""Compiled loops of the surrogates' request path (numba).

:func:`grouped_coefficients` forms, per (posture, seat track) group of a
piece's terms, the coefficients weighted by each term's fixed-input factor
(:meth:`models.surrogate.pieces._Piece.samples`). Why hand-written rather than
scipy's sparse product: the coefficients of a piece are sparse too (each
bootstrap replicate's least-angle regression keeps about a sixth of the
candidate terms), and a sparse-times-sparse product into a dense block
is not in scipy without building two sparse matrices per request. [R] 197 ->
about 30 us on the 445 x 906 block of the frontal 50M belted with airbag
(measured 2026-12-04), the same numbers as ``csr_array(...) @ coef``: each entry
is the same sum in the same order, without its terms that are exactly zero.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from models.arrays import FloatArray, IntArray

__all__ = [
    "add_correction",
    "gather_p_sets",
    "grouped_coefficients",
    "matern32_in_place",
    "pooled_order_statistics",
    "univariate_rows",
    "warm_up",
]


@njit(cache=True, nogil=True)
def grouped_coefficients(
    factors: FloatArray,
    group_ptr: IntArray,
    row_ptr: IntArray,
    cols: IntArray,
    vals: FloatArray,
    n_cols: int,
) -> FloatArray:
    """``sum over the terms t of group g of factors[t] * coef[t, :]``, coef in CSR.

    Parameters
    ----------
    factors : ndarray, shape (T,)
        One factor per term (terms sorted by group).
    group_ptr : ndarray of int64, shape (G + 1,)
        Group g holds the terms ``group_ptr[g]:group_ptr[g + 1]``.
    row_ptr, cols, vals : ndarray, shapes (T + 1,), (nnz,), (nnz,)
        The coefficient matrix (T, n_cols) in compressed sparse rows, the
        columns of each row in increasing order.
    n_cols : int

    Returns
    -------
    ndarray, shape (G, n_cols)
    """
    n_groups = group_ptr.shape[0] - 1
    out = np.zeros((n_groups, n_cols))
    for g in range(n_groups):
        row = out[g]
        for t in range(group_ptr[g], group_ptr[g + 1]):
            a = factors[t]
            for k in range(row_ptr[t], row_ptr[t + 1]):
                row[cols[k]] += a * vals[k]
    return out


@njit(cache=True, nogil=True)
def _distances_in_place(cross: FloatArray, q_sq: FloatArray, train_sq: FloatArray) -> FloatArray:
    """``r = sqrt(max(-2 cross + q_sq[i] + train_sq[j], 0))`` into `cross`; returns ``-r``."""
    m, n = cross.shape
    neg = np.empty((m, n))
    for i in range(m):
        for j in range(n):
            x = cross[i, j] * -2.0
            x = x + q_sq[i]
            x = x + train_sq[j]
            r = math.sqrt(x if x > 0.0 else 0.0)
            cross[i, j] = r
            neg[i, j] = -r
    return neg


@njit(cache=True, nogil=True)
def _times_one_plus(r: FloatArray, e: FloatArray) -> None:
    """``r = (r + 1) e`` in place."""
    m, n = r.shape
    for i in range(m):
        for j in range(n):
            r[i, j] = (r[i, j] + 1.0) * e[i, j]


def matern32_in_place(cross: FloatArray, q_sq: FloatArray, train_sq: FloatArray) -> FloatArray:
    """Matern 3/2 kernel values ``(1 + r) exp(-r)`` from scaled dot products, in place.

    Parameters
    ----------
    cross : ndarray, shape (m, n), C-contiguous
        ``q @ s.T`` of the scaled query and design points (overwritten with the result).
    q_sq, train_sq : ndarray, shapes (m,), (n,)
        Their squared norms.

    Returns
    -------
    ndarray, shape (m, n)
        `cross`, now ``(1 + r) exp(-r)`` with ``r = |q_i - s_j|``. The passes of
        the numpy expression fused into two loops and numpy's exponential
        between them: the same numbers (each element the same IEEE operations
        in the same order; the exponential numpy's own). [R] 0.47 -> about 0.25 ms
        on 97 x 1000 (measured 2026-12-04).
    """
    neg = _distances_in_place(cross, q_sq, train_sq)
    np.exp(neg, out=neg)
    _times_one_plus(cross, neg)
    return cross


@njit(cache=True, nogil=True)
def univariate_rows(x: FloatArray, alpha: FloatArray, beta: FloatArray, degree: int) -> FloatArray:
    """Orthonormal polynomials ``p_0 .. p_degree`` at each `x` by their three-term recurrence.

    ``p_1 = (x - alpha_0) / sqrt(beta_1)``, ``p_(k+1) = ((x - alpha_k) p_k -
    sqrt(beta_k) p_(k-1)) / sqrt(beta_(k+1))``: the operations, in their order,
    of the numpy form in :func:`models.surrogate.basis.evaluate_univariate`
    (no multiply-add fused; square roots correctly rounded in both), one pass
    per point instead of a dozen array operations per degree. [R] 39 -> 3.5 us
    for 97 points at degree 15 (measured 2026-12-04).

    Parameters
    ----------
    x : ndarray, shape (n,)
    alpha, beta : ndarray, shape (>= degree + 1,)
        Recurrence coefficients.
    degree : int

    Returns
    -------
    ndarray, shape (n, degree + 1)
    """
    n = x.shape[0]
    out = np.empty((n, degree + 1))
    sq = np.empty(degree + 1)
    for k in range(degree + 1):
        sq[k] = math.sqrt(beta[k])
    for i in range(n):
        xi = x[i]
        out[i, 0] = 1.0
        if degree >= 1:
            prev = 1.0
            cur = (xi - alpha[0]) / sq[1]
            out[i, 1] = cur
            for k in range(1, degree):
                nxt = ((xi - alpha[k]) * cur - sq[k] * prev) / sq[k + 1]
                out[i, k + 1] = nxt
                prev = cur
                cur = nxt
    return out


@njit(cache=True, nogil=True)
def gather_p_sets(raw: FloatArray, rows: IntArray, subset: IntArray) -> FloatArray:
    """The measure sets of the P(ISS >= 15) interval, in one copy.

    Parameters
    ----------
    raw : ndarray, shape (n_out, B + 1, S + 1)
        Surrogate outputs (any strides): replicate 0 the point PCE, sample 0 the reading.
    rows : ndarray of int, shape (m,)
        The measures' rows of `raw`.
    subset : ndarray of int, shape (k,)
        Sensor samples (0-based, without the reading) the replicates are taken at.

    Returns
    -------
    ndarray, shape (m, S + B k)
        Per measure: the point PCE at every sensor sample, then each replicate
        at the subset: ``concatenate((raw[rows, 0, 1:], raw[rows][:, 1:, 1 +
        subset].reshape(m, -1)), axis=1)``, without its four temporaries.
    """
    m = rows.shape[0]
    nb1 = raw.shape[1]
    ns = raw.shape[2] - 1
    k = subset.shape[0]
    out = np.empty((m, ns + (nb1 - 1) * k))
    for i in range(m):
        r = rows[i]
        for s in range(ns):
            out[i, s] = raw[r, 0, 1 + s]
        col = ns
        for b in range(1, nb1):
            for j in range(k):
                out[i, col] = raw[r, b, 1 + subset[j]]
                col += 1
    return out


@njit(cache=True, nogil=True)
def add_correction(out: FloatArray, corr: FloatArray) -> None:
    """``out += corr.T[:, None, :]`` in place, in the order `out` lies in memory.

    Parameters
    ----------
    out : ndarray, shape (n_out, B + 1, n)
        Fitted-scale outputs of every replicate (any strides: the transpose of
        a product, its samples' axis outermost, or C order).
    corr : ndarray, shape (n, n_out)
        The correction at each sample, the same for every replicate.

    Each element gets the same single addition as numpy's broadcast; numpy
    walks the broadcast operand's strides instead. [R] 6 x 151 x 97: 45 ->
    about 25 us (measured 2026-12-05).
    """
    n_out, nb1, n = out.shape
    if out.strides[2] > out.strides[1]:  # samples outermost in memory
        for s in range(n):
            for o in range(n_out):
                c = corr[s, o]
                for b in range(nb1):
                    out[o, b, s] += c
    else:
        for o in range(n_out):
            for b in range(nb1):
                for s in range(n):
                    out[o, b, s] += corr[s, o]


@njit(cache=True, nogil=True)
def _select_in_place(a: FloatArray, lo: int, hi: int, k: int) -> None:
    """Reorder ``a[lo:hi + 1]`` so that ``a[k]`` holds its (k - lo)-th smallest value.

    Quickselect (Hoare's partition about the median of three); the values
    below ``k`` are then <= ``a[k]`` and those above >= it. `a` holds no NaN.
    """
    while hi > lo:
        mid = (lo + hi) >> 1
        x, y, z = a[lo], a[mid], a[hi]
        if x < y:
            m = mid if y < z else (hi if x < z else lo)
        else:
            m = lo if x < z else (hi if y < z else mid)
        p = a[m]
        i, j = lo, hi
        while i <= j:
            while a[i] < p:
                i += 1
            while a[j] > p:
                j -= 1
            if i <= j:
                t = a[i]
                a[i] = a[j]
                a[j] = t
                i += 1
                j -= 1
        if k <= j:
            hi = j
        elif k >= i:
            lo = i
        else:
            return


#: Every how many pooled values :func:`pooled_order_statistics` samples to place
#: its windows. [R] 900 of 14,400 values: the windows hold about 5 % of them.
_ORDER_SAMPLE_STEP = 16
#: Half width of a window about the sample's rank, in standard deviations of that
#: rank (binomial), plus two ranks. [R] At 4 a window misses its order statistic
#: about once in 10,000 windows or fewer (a rank beyond 4 standard deviations),
#: which then costs one quickselect of the whole row.
_ORDER_WINDOW_SD = 4.0


@njit(cache=True, nogil=True)
def _window(sample: FloatArray, k: int, n: int) -> tuple[float, float]:
    """Bounds ``[a, b]`` (sample values) that likely hold the k-th smallest of n values."""
    m = sample.shape[0]
    c = k * (m / n)
    p = min(max(k / n, 0.0), 1.0)
    d = _ORDER_WINDOW_SD * math.sqrt(m * p * (1.0 - p)) + 2.0
    ra, rb = int(math.floor(c - d)), int(math.ceil(c + d))
    a, b = -np.inf, np.inf
    start = 0
    if ra > 0:
        _select_in_place(sample, 0, m - 1, ra)
        a = sample[ra]
        start = ra  # the sample's values from ra on are >= a
    if rb < m - 1:
        _select_in_place(sample, start, m - 1, rb)
        b = sample[rb]
    return a, b


@njit(cache=True, nogil=True)
def _pick(window: FloatArray, below: int, n_in: int, k: int, view: FloatArray) -> float:
    """The k-th smallest of `view[1:, 1:]`: from its window's `n_in` values when they
    hold it (`below` values lie under the window), else by a quickselect of them all."""
    if below <= k < below + n_in:
        _select_in_place(window, 0, n_in - 1, k - below)
        return float(window[k - below])
    rows, cols = view.shape[0] - 1, view.shape[1] - 1
    full = np.empty(rows * cols)
    for r in range(rows):
        for j in range(cols):
            full[r * cols + j] = view[1 + r, 1 + j]
    _select_in_place(full, 0, full.shape[0] - 1, k)
    return float(full[k])


@njit(cache=True, nogil=True)
def pooled_order_statistics(
    raw: FloatArray, k_lo: int, k_hi: int
) -> tuple[FloatArray, FloatArray, bool]:
    """The k_lo-th and k_hi-th smallest of each output's pooled replicates x samples.

    Parameters
    ----------
    raw : ndarray, shape (n_out, B + 1, S + 1)
        Fitted-scale outputs (any strides); replicate 0 and sample 0 (the point
        PCE, the reading) are left out of the pool.
    k_lo, k_hi : int
        0-based ranks in the pool of B S values.

    Returns
    -------
    lo, hi : ndarray, shape (n_out,)
        The order statistics: exactly those of ``np.partition`` of each pooled row.
    finite : bool
        False when the pool holds a NaN (then `lo` and `hi` are not computed: the
        caller takes numpy's order, which puts NaN last).

    Why not ``np.partition``: its selection costs 0.25 ms per row of 14,400 values
    on this machine (numpy 2.4, measured 2026-12-08), which made the intervals'
    order statistics the largest single step of the surrogate. Here each row is
    read once, in memory order: a regular sample of it places a narrow window about
    each rank, the values below a window are counted and those inside kept, and the
    rank is selected among the kept few (Floyd and Rivest 1975, "Expected time
    bounds for selection", Commun. ACM 18(3):165-172, the same idea); when a window
    misses its rank the whole row is selected instead. Exact either way.
    """
    n_out, nb1, ns1 = raw.shape
    n = (nb1 - 1) * (ns1 - 1)
    m = (n + _ORDER_SAMPLE_STEP - 1) // _ORDER_SAMPLE_STEP
    sample = np.empty(m)
    cand_lo, cand_hi = np.empty(n), np.empty(n)
    lo_out, hi_out = np.empty(n_out), np.empty(n_out)
    for o in range(n_out):
        view = raw[o].T if raw.strides[2] > raw.strides[1] else raw[o]  # memory order
        cols = view.shape[1] - 1
        for t in range(m):
            idx = t * _ORDER_SAMPLE_STEP
            sample[t] = view[1 + idx // cols, 1 + idx % cols]
        a_lo, b_lo = _window(sample, k_lo, n)
        a_hi, b_hi = _window(sample, k_hi, n)
        below_lo = below_hi = n_lo = n_hi = 0
        for r in range(1, view.shape[0]):
            for j in range(1, cols + 1):
                x = view[r, j]
                if x != x:
                    return lo_out, hi_out, False
                if x < a_lo:
                    below_lo += 1
                elif x <= b_lo:
                    cand_lo[n_lo] = x
                    n_lo += 1
                if x < a_hi:
                    below_hi += 1
                elif x <= b_hi:
                    cand_hi[n_hi] = x
                    n_hi += 1
        lo_out[o] = _pick(cand_lo, below_lo, n_lo, k_lo, view)
        hi_out[o] = _pick(cand_hi, below_hi, n_hi, k_hi, view)
    return lo_out, hi_out, True


def warm_up() -> None:
    """Compile (or load from the numba cache) the loops of this module."""
    ptr = np.array([0, 1], dtype=np.int64)
    grouped_coefficients(np.ones(1), ptr, ptr, np.zeros(1, dtype=np.int64), np.ones(1), 1)
    matern32_in_place(np.zeros((1, 1)), np.zeros(1), np.zeros(1))
    univariate_rows(np.zeros(1), np.zeros(2), np.ones(2), 1)
    gather_p_sets(np.zeros((1, 2, 2)), np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.int64))
    add_correction(np.zeros((1, 1, 1)), np.zeros((1, 1)))
    pooled_order_statistics(np.zeros((1, 2, 2)), 0, 0)
