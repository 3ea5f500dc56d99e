"""Orthonormal polynomial bases for arbitrary polynomial chaos (aPCE), numpy only.

The univariate polynomials of each input are orthonormal with respect to a
probability measure given by weighted nodes (the input's samples with equal
weights, or quadrature nodes of a known density). Their three-term recurrence
is built by the discretised Stieltjes procedure (Gautschi, *Orthogonal
Polynomials: Computation and Approximation*, 2004, section 2.2.3.1), which is
stable for the degrees used here (<= 15) when the inputs are first mapped to
[-1, 1]; no density family is assumed (Oladyshkin & Nowak 2012, aPCE).

Orthonormal recurrence (``beta_0 = 1`` for a probability measure)::

    p_{-1} = 0,  p_0 = 1,
    sqrt(beta_{k+1}) p_{k+1}(x) = (x - alpha_k) p_k(x) - sqrt(beta_k) p_{k-1}(x)

Multivariate basis functions are tensor products ``prod_j p_{a_j}(x_j)`` over
multi-indices ``a`` of a hyperbolic (q-norm) truncation (Blatman & Sudret 2011,
J. Comput. Phys. 230:2345): ``(sum_j a_j^q)^(1/q) <= degree``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from models.arrays import FloatArray, IntArray
from models.surrogate.kernels import univariate_rows

__all__ = [
    "Recurrence",
    "design_matrix",
    "evaluate_univariate",
    "evaluate_univariate_at",
    "graded_counts",
    "hyperbolic_multi_indices",
    "stieltjes",
    "uniform_recurrence",
]


#: Recurrence coefficients of one input: ``(alpha, beta)``, each shape (degree + 1,).
Recurrence = tuple[FloatArray, FloatArray]

#: Relative size of a squared norm below which the discrete measure is exhausted.
_NORM_EPS = 1e-13


def stieltjes(nodes: npt.ArrayLike, weights: npt.ArrayLike | None, degree: int) -> Recurrence:
    """Recurrence coefficients orthonormal for a discrete measure (Stieltjes).

    Parameters
    ----------
    nodes : array_like, shape (n,)
        Support points (samples or quadrature nodes), already standardised
        (e.g. to [-1, 1]).
    weights : array_like, shape (n,), optional
        Non-negative weights; normalised to sum 1. Equal weights when None
        (the empirical measure of samples).
    degree : int
        Highest polynomial degree; needs ``degree < n`` distinct nodes.

    Returns
    -------
    alpha, beta : ndarray, shape (degree + 1,)
        ``beta[0] = 1`` (probability measure).

    Raises
    ------
    ValueError
        When the measure has fewer than ``degree + 1`` distinct support points.
    """
    x = np.asarray(nodes, dtype=np.float64).ravel()
    w = np.full(x.size, 1.0 / x.size) if weights is None else np.asarray(weights, np.float64)
    w = w / w.sum()
    alpha = np.zeros(degree + 1)
    beta = np.zeros(degree + 1)
    beta[0] = 1.0
    p_prev = np.zeros_like(x)
    p = np.ones_like(x)  # orthonormal p_0
    for k in range(degree + 1):
        alpha[k] = float(np.sum(w * x * p * p))
        if k == degree:
            break
        q = (x - alpha[k]) * p - np.sqrt(beta[k]) * p_prev if k > 0 else (x - alpha[k]) * p
        nrm2 = float(np.sum(w * q * q))
        if not nrm2 > _NORM_EPS:
            raise ValueError(f"measure has too few distinct points for degree {degree}")
        beta[k + 1] = nrm2
        p_prev, p = p, q / np.sqrt(nrm2)
    return alpha, beta


def uniform_recurrence(degree: int) -> Recurrence:
    """Orthonormal Legendre recurrence for the uniform distribution on [-1, 1].

    ``alpha_k = 0``, ``beta_k = k^2 / (4 k^2 - 1)`` (Gautschi 2004, table 1.1).
    """
    k = np.arange(degree + 1, dtype=np.float64)
    beta = np.where(k > 0, k * k / np.maximum(4.0 * k * k - 1.0, 1.0), 1.0)
    return np.zeros(degree + 1), beta


def evaluate_univariate(x: npt.ArrayLike, rec: Recurrence, degree: int) -> FloatArray:
    """Orthonormal polynomials ``p_0 .. p_degree`` at `x`.

    Parameters
    ----------
    x : array_like, shape (n,)
        Standardised input values.
    rec : (alpha, beta)
        Recurrence with at least ``degree + 1`` coefficients.
    degree : int

    Returns
    -------
    ndarray, shape (n, degree + 1)
    """
    xv = np.ascontiguousarray(x, dtype=np.float64).ravel()
    alpha, beta = rec
    if alpha.shape[0] < degree + 1 or beta.shape[0] < degree + 1:
        raise ValueError(f"the recurrence has fewer than {degree + 1} coefficients")
    # a compiled pass per point (models.surrogate.kernels)
    return univariate_rows(
        xv,
        np.ascontiguousarray(alpha, dtype=np.float64),
        np.ascontiguousarray(beta, dtype=np.float64),
        int(degree),
    )


def evaluate_univariate_at(x: float, rec: Recurrence, degree: int) -> FloatArray:
    """:func:`evaluate_univariate` at one point, shape (degree + 1,), the same numbers.

    In Python floats (IEEE double, as numpy's element-wise operations): a request
    evaluates three inputs at one point each, where numpy's per-call overhead on
    one-element arrays would cost tens of microseconds.
    """
    alpha, beta = rec
    z = float(x)
    out = [1.0]
    if degree >= 1:
        out.append((z - float(alpha[0])) / math.sqrt(float(beta[1])))
    for k in range(1, degree):
        out.append(
            ((z - float(alpha[k])) * out[k] - math.sqrt(float(beta[k])) * out[k - 1])
            / math.sqrt(float(beta[k + 1]))
        )
    return np.array(out, dtype=np.float64)


def hyperbolic_multi_indices(
    dim: int, degree: int, q: float = 1.0, max_interaction: int | None = None
) -> IntArray:
    """Multi-indices of a hyperbolic (q-norm) truncation, graded order.

    Parameters
    ----------
    dim : int
        Number of inputs.
    degree : int
        Largest total degree (q-norm bound).
    q : float, optional
        q-norm in (0, 1]; 1 is the total-degree set.
    max_interaction : int, optional
        Largest number of non-zero entries (interaction order).

    Returns
    -------
    ndarray of int64, shape (n_terms, dim)
        Sorted by q-norm, then total degree, then lexicographically
        (descending per position): the set of degree ``d < degree`` is a
        leading block of rows (:func:`graded_counts`); the first row is the
        constant term.
    """
    rows: list[tuple[int, ...]] = []
    bound = float(degree) ** q + 1e-9

    def grow(prefix: tuple[int, ...], used: float, nonzero: int) -> None:
        if len(prefix) == dim:
            rows.append(prefix)
            return
        for v in range(degree + 1):
            cost = used + (float(v) ** q if v else 0.0)
            if cost > bound:
                break
            nz = nonzero + (1 if v else 0)
            if max_interaction is not None and nz > max_interaction:
                break
            grow((*prefix, v), cost, nz)

    grow((), 0.0, 0)
    rows.sort(key=lambda a: (round(_qnorm(a, q), 9), sum(a), tuple(-v for v in a)))
    return np.asarray(rows, dtype=np.int64).reshape(-1, dim)


def _qnorm(a: tuple[int, ...] | npt.NDArray[np.int64], q: float) -> float:
    nz = [float(v) for v in a if v]
    return float(sum(v**q for v in nz) ** (1.0 / q)) if nz else 0.0


def graded_counts(indices: npt.ArrayLike, q: float, degree: int) -> IntArray:
    """Number of leading rows of `indices` in the q-norm set of each degree 0..`degree`.

    Returns
    -------
    ndarray of int64, shape (degree + 1,)
    """
    idx = np.asarray(indices, dtype=np.int64)
    norms = np.array([_qnorm(tuple(r), q) for r in idx])
    return np.array([int(np.sum(norms <= d + 1e-9)) for d in range(degree + 1)], dtype=np.int64)


def design_matrix(
    x: npt.ArrayLike, recs: Sequence[Recurrence], indices: npt.ArrayLike
) -> FloatArray:
    """Multivariate basis ``Psi[i, t] = prod_j p_{indices[t, j]}(x[i, j])``.

    Parameters
    ----------
    x : array_like, shape (n, dim)
        Standardised inputs.
    recs : sequence of (alpha, beta), length dim
    indices : array_like of int, shape (n_terms, dim)

    Returns
    -------
    ndarray, shape (n, n_terms)
    """
    xv = np.atleast_2d(np.asarray(x, dtype=np.float64))
    idx = np.asarray(indices, dtype=np.int64)
    psi = np.ones((xv.shape[0], idx.shape[0]))
    for j, rec in enumerate(recs):
        deg = int(idx[:, j].max()) if idx.size else 0
        if deg == 0:
            continue
        uni = evaluate_univariate(xv[:, j], rec, deg)
        psi *= uni[:, idx[:, j]]
    return psi
