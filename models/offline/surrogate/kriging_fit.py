"""Fit the Kriging of a delta-V piece's PCE residuals (offline, scikit-learn).

The method and its choices are described in :mod:`models.surrogate.kriging`,
which evaluates the stored correction on the request path with numpy alone
(:class:`models.surrogate.kriging.ResidualKriging`).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from models.arrays import FloatArray
from models.surrogate.kriging import (
    LENGTH_SCALE_BOUNDS,
    LENGTH_SCALE_START,
    MATERN_NU,
    NOISE_BOUNDS,
    NOISE_START,
)

__all__ = ["fit_residual_kriging"]


def fit_residual_kriging(
    u: FloatArray, residuals: FloatArray, prefix: str
) -> tuple[dict[str, FloatArray], dict[str, Any]]:
    """Fit the shared-kernel Kriging of a piece's PCE residuals.

    Parameters
    ----------
    u : ndarray, shape (n, 5)
        Design points on the piece's [-1, 1] scale.
    residuals : ndarray, shape (n, n_out)
        LPM minus point PCE on the fitted output scale, per output.
    prefix : str
        The piece's array prefix (``"piece0/"``).

    Returns
    -------
    arrays : dict
        ``<prefix>kriging/train_u``, ``length_scale`` and ``weights``
        (:class:`ResidualKriging`).
    info : dict
        Kernel hyperparameters and the log marginal likelihood, for the metadata.
    """
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel

    u = np.asarray(u, dtype=np.float64)
    res = np.asarray(residuals, dtype=np.float64)
    sd = res.std(axis=0)
    sd = np.where(sd > 0.0, sd, 1.0)
    kernel = ConstantKernel(1.0) * Matern(
        length_scale=np.full(u.shape[1], LENGTH_SCALE_START),
        length_scale_bounds=LENGTH_SCALE_BOUNDS,
        nu=MATERN_NU,
    ) + WhiteKernel(NOISE_START, NOISE_BOUNDS)
    gp = GaussianProcessRegressor(kernel, n_restarts_optimizer=0, random_state=0)
    with warnings.catch_warnings():
        # a hyperparameter at its bound (an input the residuals do not vary
        # with: length scale at the upper bound; the noise at its floor, the
        # LPM being deterministic) is an expected optimum, not a failure
        warnings.simplefilter("ignore", ConvergenceWarning)
        gp.fit(u, res / sd)
    k = gp.kernel_
    amplitude = float(k.k1.k1.constant_value)
    length_scale = np.atleast_1d(np.asarray(k.k1.k2.length_scale, dtype=np.float64))
    alpha = np.asarray(gp.alpha_, dtype=np.float64).reshape(u.shape[0], -1)
    weights = amplitude * alpha * sd[None, :]
    arrays = {
        prefix + "kriging/train_u": u,
        prefix + "kriging/length_scale": length_scale,
        prefix + "kriging/weights": weights,
    }
    info = {
        "kernel": "C * Matern(nu=1.5, anisotropic) + White",
        "amplitude": amplitude,
        "length_scale": [float(v) for v in length_scale],
        "noise_level": float(k.k2.noise_level),
        "log_marginal_likelihood": float(gp.log_marginal_likelihood_value_),
        "residual_sd": [float(v) for v in sd],
    }
    return arrays, info
