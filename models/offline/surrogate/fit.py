"""Sparse PCE regression: hybrid least-angle regression with analytic leave-one-out.

The method of Blatman & Sudret (2011, J. Comput. Phys. 230:2345), as in UQLab
and ``pce-notes.md`` ("hybrid LAR"): least-angle regression (:func:`lar_order`,
checked against ``sklearn.linear_model.lars_path(method="lar")``) orders the
candidate terms on unit-norm, centred columns;
every leading active set of that order is refitted by ordinary least squares
(one QR decomposition gives all of them, because the sets are nested), and the
set with the smallest *corrected* leave-one-out error is kept. The degree is
chosen the same way, adaptively from 1 up to :data:`MAX_DEGREE`.

Analytic leave-one-out (Allen 1974; Blatman & Sudret 2010)::

    LOO = mean(((y - yhat) / (1 - h))^2) / var(y)

with ``h`` the diagonal of the hat matrix of the OLS fit; the corrected LOO
multiplies it by Chapelle's factor ``T = N / (N - P) * (1 + tr(C^-1) / N)``,
``C = Psi^T Psi / N`` (Chapelle, Vapnik & Bengio 2002; UQLab manual).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from models.arrays import FloatArray, IntArray

__all__ = [
    "MAX_DEGREE",
    "SparseFit",
    "fit_degree",
    "fit_adaptive",
    "lar_order",
    "loo_error",
    "nested_ols_loo",
]


#: Largest PCE degree tried (reference paper section 2.5: truncated at 15).
MAX_DEGREE = 15
#: The degree search stops after this many degrees without a better LOO (UQLab default 2).
DEGREE_PATIENCE = 2
#: Largest number of LARS steps (active terms) per fit; bounds the cost. [R]
#: the selected models of the LPM outputs have 30-110 terms on 300-run designs.
MAX_ACTIVE = 60
#: Smallest ratio of samples to active terms kept (guards the LOO of tiny designs).
MIN_SAMPLES_PER_TERM = 2.0
#: Leverage above which a point counts as fitted exactly (LOO undefined).
_MAX_LEVERAGE = 1.0 - 1e-10


@dataclass(frozen=True)
class SparseFit:
    """One sparse PCE fit.

    Attributes
    ----------
    terms : ndarray of int64, shape (k,)
        Rows of the candidate multi-index set in the model (term 0 = constant first).
    coef : ndarray, shape (k,)
        Coefficients of those terms.
    loo : float
        Analytic leave-one-out error, relative to the variance of y.
    loo_corrected : float
        LOO times Chapelle's correction factor (the selection criterion).
    degree : int
    """

    terms: IntArray
    coef: FloatArray
    loo: float
    loo_corrected: float
    degree: int


def loo_error(psi: FloatArray, y: FloatArray) -> float:
    """Analytic relative LOO error of the OLS fit of `y` on the columns of `psi`.

    Parameters
    ----------
    psi : ndarray, shape (n, p)
    y : ndarray, shape (n,)

    Returns
    -------
    float
        ``mean(((y - yhat) / (1 - h))^2) / var(y)``; inf when a leverage is 1
        or the matrix is rank deficient.
    """
    q, r = np.linalg.qr(psi)
    if np.min(np.abs(np.diag(r))) <= 1e-12 * np.max(np.abs(np.diag(r))):
        return float("inf")
    yhat = q @ (q.T @ y)
    h = np.sum(q * q, axis=1)
    if np.max(h) >= _MAX_LEVERAGE:
        return float("inf")
    var = float(np.var(y))
    return float(np.mean(((y - yhat) / (1.0 - h)) ** 2) / var) if var > 0 else 0.0


def nested_ols_loo(
    psi: FloatArray, y: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """LOO of the OLS fits on every leading column set ``psi[:, :k]``, k = 1..p.

    Parameters
    ----------
    psi : ndarray, shape (n, p)
        Columns in order of entry (constant first).
    y : ndarray, shape (n,)

    Returns
    -------
    loo : ndarray, shape (p,)
        Relative LOO error of the first k columns at index k - 1 (inf where
        the set is rank deficient or a leverage reaches 1).
    loo_corrected : ndarray, shape (p,)
    q, r : ndarray
        Reduced QR decomposition of `psi` (coefficients of set k solve
        ``r[:k, :k] c = (q.T y)[:k]``).
    """
    n, p = psi.shape
    q, r = np.linalg.qr(psi)
    d = np.abs(np.diag(r))
    ok = np.cumprod(d > 1e-10 * max(float(d.max()), 1e-300)).astype(bool)
    qty = q.T @ y
    var = float(np.var(y))
    # fitted values and leverages of every nested set
    yhat = np.cumsum(q * qty[None, :], axis=1)
    h = np.cumsum(q * q, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        res = (y[:, None] - yhat) / (1.0 - h)
        loo = np.mean(res * res, axis=0) / (var if var > 0 else 1.0)
    bad = (~ok) | (np.max(h, axis=0) >= _MAX_LEVERAGE) | ~np.isfinite(loo)
    # trace of (Psi_k^T Psi_k)^-1 = squared Frobenius norm of the leading block of R^-1
    k_ok = int(ok.sum())
    tr = np.full(p, np.inf)
    if k_ok:
        rinv = np.linalg.solve(r[:k_ok, :k_ok], np.eye(k_ok))
        tr[:k_ok] = np.cumsum(np.sum(np.triu(rinv) ** 2, axis=0))
    k = np.arange(1, p + 1, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = np.where(k < n, n / (n - k) * (1.0 + tr), np.inf)
    loo = np.where(bad, np.inf, loo)
    return loo, loo * factor, q, r


def lar_order(x: FloatArray, y: FloatArray, max_steps: int) -> IntArray:
    """Order in which least-angle regression (LAR) activates the columns of `x`.

    Efron, Hastie, Johnstone & Tibshirani (2004), *Least angle regression*,
    Ann. Statist. 32:407, algorithm of section 2 (no lasso modification), on
    the Gram matrix of the active set grown column by column: each step costs O(n p). Gives
    the same order as ``sklearn.linear_model.lars_path(method="lar")`` (tests)
    at a fraction of its per-step overhead, which dominates the 150-replicate
    bootstrap.

    Parameters
    ----------
    x : ndarray, shape (n, p)
        Centred columns of unit norm.
    y : ndarray, shape (n,)
        Centred response.
    max_steps : int

    Returns
    -------
    ndarray of int64, shape (k,)
        Column indices in order of entry, ``k <= min(max_steps, p)``.
    """
    n, p = x.shape
    xt = np.ascontiguousarray(x.T)  # (p, n): rows are columns of x
    c = xt @ y
    kmax = min(max_steps, p, n - 1)
    g_aa = np.empty((kmax, kmax))  # Gram matrix of the active columns, grown per step
    x_a = np.empty((kmax, n))  # active columns as rows
    active: list[int] = []
    inactive = np.ones(p, dtype=bool)
    tiny = 1e-12 * max(float(np.max(np.abs(c))), 1e-300)
    for k in range(kmax):
        j = int(np.argmax(np.where(inactive, np.abs(c), -1.0)))
        cmax = abs(float(c[j]))
        if cmax <= tiny:
            break
        x_a[k] = xt[j]
        col = x_a[:k] @ xt[j]
        g_aa[k, :k] = col
        g_aa[:k, k] = col
        g_aa[k, k] = float(xt[j] @ xt[j])
        active.append(j)
        inactive[j] = False
        sgn = np.sign(c[active])
        try:
            xs = np.linalg.solve(g_aa[: k + 1, : k + 1] * np.outer(sgn, sgn), np.ones(k + 1))
        except np.linalg.LinAlgError:
            active.pop()
            break
        denom = float(np.sum(xs))
        if not denom > 0.0:
            active.pop()
            break
        big_a = 1.0 / np.sqrt(denom)
        u = (sgn * big_a * xs) @ x_a[: k + 1]  # equiangular direction
        a = xt @ u
        if not inactive.any():
            break
        ci, ai = c[inactive], a[inactive]
        with np.errstate(divide="ignore", invalid="ignore"):
            g1 = (cmax - ci) / (big_a - ai)
            g2 = (cmax + ci) / (big_a + ai)
        steps = np.concatenate([g1, g2])
        steps = steps[np.isfinite(steps) & (steps > 1e-15)]
        gamma = float(steps.min()) if steps.size else cmax / big_a
        c = c - gamma * a
    return np.asarray(active, dtype=np.int64)


def fit_degree(psi: FloatArray, y: FloatArray, degree: int = 0) -> SparseFit:
    """Hybrid LAR on one candidate basis.

    Parameters
    ----------
    psi : ndarray, shape (n, p)
        Candidate basis evaluated at the design; column 0 is the constant.
    y : ndarray, shape (n,)
    degree : int, optional
        Recorded in the result.

    Returns
    -------
    SparseFit
        ``loo`` is inf when no active set could be fitted.
    """
    n, p = psi.shape
    if p == 1:
        order = np.zeros(1, dtype=np.int64)
    else:
        x = psi[:, 1:] - psi[:, 1:].mean(axis=0)
        nrm = np.linalg.norm(x, axis=0)
        nrm[nrm == 0.0] = 1.0
        x = x / nrm
        yc = y - y.mean()
        max_k = int(min(p - 1, MAX_ACTIVE, max(1, n / MIN_SAMPLES_PER_TERM - 1)))
        active = lar_order(x, yc, max_k)
        order = np.concatenate([[0], active + 1])
    loo, loo_c, q, r = nested_ols_loo(psi[:, order], y)
    if not np.any(np.isfinite(loo_c)):
        return SparseFit(order[:1], np.array([float(np.mean(y))]), np.inf, np.inf, degree)
    best = int(np.argmin(loo_c))
    coef = np.asarray(
        np.linalg.solve(r[: best + 1, : best + 1], (q.T @ y)[: best + 1]), dtype=np.float64
    )
    terms = order[: best + 1]
    srt = np.argsort(terms, kind="stable")
    return SparseFit(terms[srt], coef[srt], float(loo[best]), float(loo_c[best]), degree)


def fit_adaptive(
    psi_full: FloatArray,
    y: FloatArray,
    n_terms_by_degree: npt.ArrayLike,
    max_degree: int = MAX_DEGREE,
) -> SparseFit:
    """Hybrid LAR with the degree chosen by the corrected LOO, 1..`max_degree`.

    Parameters
    ----------
    psi_full : ndarray, shape (n, p_max)
        Candidate basis of the largest degree, graded (the terms of degree <= d
        are the first ``n_terms_by_degree[d]`` columns).
    y : ndarray, shape (n,)
    n_terms_by_degree : array_like of int, shape (max_degree + 1,)
    max_degree : int, optional

    Returns
    -------
    SparseFit
    """
    counts = np.asarray(n_terms_by_degree, dtype=np.int64)
    best: SparseFit | None = None
    since = 0
    for d in range(1, max_degree + 1):
        fit = fit_degree(psi_full[:, : counts[d]], y, d)
        if best is None or fit.loo_corrected < best.loo_corrected:
            best, since = fit, 0
        else:
            since += 1
            if since >= DEGREE_PATIENCE:
                break
    assert best is not None
    return best
