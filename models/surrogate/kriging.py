"""Kriging of a delta-V piece's PCE residuals (PC-Kriging, the PCE as trend).

The sparse PCE of a piece rounds the hinges of the LPM response (a contact
starting, the HIC window or the Nij load case switching). Its residuals on the
design runs are spatially correlated along those hinges, so a Gaussian process
on them restores part of what the polynomial misses. This is the sequential
form of PCE-Kriging: a LAR-selected sparse PCE as the trend and ordinary Kriging
of its residuals (Kersaudy, Sudret, Varsier, Picon, Wiart 2015, "A new
surrogate modeling technique combining Kriging and polynomial chaos expansions
- Application to uncertainty analysis in computational dosimetry", J. Comput.
Phys. 286, 103-117; Schoebi, Sudret, Wiart 2015, "Polynomial-chaos-based
Kriging", Int. J. Uncertainty Quantification 5(2), 171-193).

* One kernel per piece, shared by its outputs (each output's residuals scaled
  to unit variance for the fit): the request path then needs one kernel matrix
  for all outputs. [R] Measured 2026-12-02 on the belted 5F without airbag
  (150 held-out points, HIC15 / Nij median relative error): one kernel per
  output 6.3 / 6.1 %, one shared 6.0 / 5.9 % (PCE alone 9.4 / 6.3 %).
* Matern 3/2 (once differentiable: the responses are hinged, not smooth),
  anisotropic, plus a white-noise term, hyperparameters by maximum likelihood
  (scikit-learn's ``GaussianProcessRegressor``, one L-BFGS start). [R] Matern
  5/2 measured the same day: 5.8 / 5.5 % on that family, chest VC of the
  unbelted 50M without airbag 6.4 % against 6.1 %; no clear gain.
* The correction is a deterministic function of the design: it is added to the
  point PCE and to every bootstrap replicate alike, so the replicate spread
  (the intervals' bootstrap part) stays the PCE's.

Fitting uses scikit-learn (offline, :mod:`models.offline.surrogate.kriging_fit`); the
request path evaluates
the stored kernel and weights in numpy (:class:`ResidualKriging`): a kernel
matrix of (points x design runs) and one matrix product.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Final

import numpy as np
import numpy.typing as npt

from models.arrays import FloatArray
from models.surrogate.kernels import matern32_in_place

#: Matern smoothness of the residual kernel (3/2; see the module notes).
MATERN_NU: Final[float] = 1.5
#: Starting length scale of every input on the [-1, 1] design scale, and its bounds.
LENGTH_SCALE_START: Final[float] = 0.6
LENGTH_SCALE_BOUNDS: Final[tuple[float, float]] = (2e-2, 2e2)
#: Starting white-noise level (of unit-variance residuals) and its bounds: the
#: LPM is deterministic, so the noise term only absorbs what the kernel cannot
#: resolve between neighbouring runs.
NOISE_START: Final[float] = 1e-4
NOISE_BOUNDS: Final[tuple[float, float]] = (1e-10, 1.0)

_SQRT3: Final[float] = math.sqrt(3.0)


class ResidualKriging:
    """Kriging correction of one piece, on the fitted output scale (immutable).

    Parameters
    ----------
    train_u : ndarray, shape (n, 5)
        Design points on the piece's [-1, 1] scale (:func:`models.surrogate.spec.to_unit`).
    length_scale : ndarray, shape (5,)
        Kernel length scales on that scale.
    weights : ndarray, shape (n, n_out)
        Kriging weights: the correction at ``u`` is ``k(u, train_u) @ weights``
        with the unit-amplitude Matern 3/2 kernel ``k`` (the amplitude and each
        output's residual scale are folded into the weights).
    """

    __slots__ = ("_inv_ls", "_scaled", "_sq", "_weights", "n_outputs")

    n_outputs: int
    _inv_ls: FloatArray
    _scaled: FloatArray
    _sq: FloatArray
    _weights: FloatArray

    def __setattr__(self, key: str, value: object) -> None:
        raise AttributeError(f"ResidualKriging is immutable ({key})")

    def __init__(self, train_u: FloatArray, length_scale: FloatArray, weights: FloatArray) -> None:
        u = np.asarray(train_u, dtype=np.float64)
        ls = np.asarray(length_scale, dtype=np.float64)
        w = np.asarray(weights, dtype=np.float64)
        if u.ndim != 2 or ls.shape != (u.shape[1],) or w.ndim != 2 or w.shape[0] != u.shape[0]:
            raise ValueError(
                f"kriging: inconsistent shapes (points {u.shape}, length scales "
                f"{ls.shape}, weights {w.shape})"
            )
        if not (np.all(np.isfinite(u)) and np.all(np.isfinite(w)) and np.all(ls > 0.0)):
            raise ValueError("kriging: non-finite points or weights, or a length scale <= 0")
        # distances are kept as sqrt(3) r / l, the Matern 3/2 argument
        inv_ls = _SQRT3 / ls
        scaled = np.ascontiguousarray(u * inv_ls)
        sq = np.einsum("ij,ij->i", scaled, scaled)
        weights_c = np.ascontiguousarray(w)
        for arr in (inv_ls, scaled, sq, weights_c):
            arr.flags.writeable = False
        sa = object.__setattr__
        sa(self, "_inv_ls", inv_ls)
        sa(self, "_scaled", scaled)
        sa(self, "_sq", sq)
        sa(self, "_weights", weights_c)
        sa(self, "n_outputs", int(w.shape[1]))

    @classmethod
    def from_arrays(cls, arrays: Mapping[str, npt.NDArray[Any]], prefix: str) -> ResidualKriging:
        """The correction stored under ``<prefix>kriging/`` (written by the offline fit)."""
        return cls(
            arrays[prefix + "kriging/train_u"],
            arrays[prefix + "kriging/length_scale"],
            arrays[prefix + "kriging/weights"],
        )

    def correction(self, u: FloatArray) -> FloatArray:
        """Correction at points on the piece's [-1, 1] scale.

        Parameters
        ----------
        u : ndarray, shape (m, 5)

        Returns
        -------
        ndarray, shape (m, n_out)
            To add to the PCE values on the fitted output scale.
        """
        q = np.asarray(u, dtype=np.float64) * self._inv_ls
        # k = (1 + r) exp(-r) with r = sqrt(3) |u - u_j| / l, in place on one
        # (m, runs) buffer (models.surrogate.kernels)
        k = matern32_in_place(q @ self._scaled.T, np.einsum("ij,ij->i", q, q), self._sq)
        return np.asarray(k @ self._weights, dtype=np.float64)
