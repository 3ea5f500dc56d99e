"""Kriging of the PCE residuals (models.surrogate.kriging) and its use in the pieces."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from models.offline.surrogate.kriging_fit import fit_residual_kriging
from models.offline.surrogate.report import without_kriging
from models.surrogate.evaluate import SurrogateLibrary, default_artifact_dir
from models.surrogate.kriging import ResidualKriging
from models.surrogate.spec import INPUT_NAMES


def _residual_data(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A hinge and a kink over 5 inputs on [-1, 1], two outputs."""
    u = np.random.default_rng(seed).uniform(-1.0, 1.0, (n, 5))
    r = np.stack([np.maximum(u[:, 0] + 0.5 * u[:, 2], 0.0), 0.3 * np.abs(u[:, 1])], axis=1)
    return u, r


@pytest.fixture(scope="module")
def fitted() -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    u, r = _residual_data(250, 0)
    return fit_residual_kriging(u, r, "piece0/")


def test_correction_is_the_kriging_predictor(
    fitted: tuple[dict[str, np.ndarray], dict[str, Any]],
) -> None:
    """The numpy request-path evaluation equals scikit-learn's GP mean for the same kernel."""
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel

    arrays, info = fitted
    u, r = _residual_data(250, 0)
    sd = np.asarray(info["residual_sd"])
    kernel = ConstantKernel(info["amplitude"], "fixed") * Matern(
        np.asarray(info["length_scale"]), "fixed", nu=1.5
    ) + WhiteKernel(info["noise_level"], "fixed")
    gp = GaussianProcessRegressor(kernel, optimizer=None).fit(u, r / sd)
    q = np.random.default_rng(5).uniform(-1.0, 1.0, (40, 5))
    kr = ResidualKriging.from_arrays(arrays, "piece0/")
    np.testing.assert_allclose(kr.correction(q), gp.predict(q) * sd, rtol=1e-7, atol=1e-9)


def test_correction_interpolates_and_generalises(
    fitted: tuple[dict[str, np.ndarray], dict[str, Any]],
) -> None:
    arrays, _ = fitted
    kr = ResidualKriging.from_arrays(arrays, "piece0/")
    u, r = _residual_data(250, 0)
    assert np.max(np.abs(kr.correction(u) - r)) < 0.05 * np.max(np.abs(r))
    q, rq = _residual_data(200, 9)  # fresh points: most of the residual is recovered
    assert np.mean(np.abs(kr.correction(q) - rq)) < 0.25 * np.mean(np.abs(rq))
    far = np.full((1, 5), 1e3)
    np.testing.assert_allclose(kr.correction(far), 0.0, atol=1e-12)


def test_malformed_kriging_is_rejected(
    fitted: tuple[dict[str, np.ndarray], dict[str, Any]],
) -> None:
    arrays, _ = fitted
    u = arrays["piece0/kriging/train_u"]
    ls = arrays["piece0/kriging/length_scale"]
    w = arrays["piece0/kriging/weights"]
    with pytest.raises(ValueError, match="shapes"):
        ResidualKriging(u, ls[:4], w)
    with pytest.raises(ValueError, match="shapes"):
        ResidualKriging(u, ls, w[:-1])
    with pytest.raises(ValueError, match="length scale"):
        ResidualKriging(u, -ls, w)
    bad = w.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        ResidualKriging(u, ls, bad)


@pytest.fixture(scope="module")
def shipped_library() -> SurrogateLibrary:
    return SurrogateLibrary.load()


def _artifact_arrays(name: str) -> dict[str, np.ndarray]:
    from models.surrogate.evaluate import default_artifact_dir
    from models.surrogate.store import read_artifact

    arrays, _ = read_artifact(default_artifact_dir() / f"{name}.npz")
    return arrays


def test_every_shipped_piece_has_its_kriging(shipped_library: SurrogateLibrary) -> None:
    for name, fam in shipped_library.families().items():
        for k, piece in enumerate(fam.meta["pieces"]):
            info = piece.get("kriging")
            assert info is not None, f"{name} piece {k}"
            assert np.all(np.asarray(info["length_scale"]) > 0.0)


def test_the_kriging_is_fitted_on_at_most_kriging_max_runs(
    shipped_library: SurrogateLibrary,
) -> None:
    """The request-path kernel is (sensor samples x Kriging runs): the runs are the
    first finite design rows, at most the ``kriging_max_runs`` each artifact's
    build recorded (its ``config``), and the shipped builds are default ones."""
    from models.offline.surrogate.build import default_config

    for name, fam in shipped_library.families().items():
        cap = int(fam.meta["config"]["kriging_max_runs"])
        assert cap == default_config().kriging_max_runs, name
        edges = fam.meta["config"]["delta_v_pieces_kmh"]
        assert tuple(edges) == default_config().delta_v_pieces_kmh, name
        arrays = _artifact_arrays(name)
        k = 0
        while f"piece{k}/design_x" in arrays:
            y = arrays[f"piece{k}/design_y"]
            finite = int(np.all(np.isfinite(y), axis=1).sum())
            n_k = arrays[f"piece{k}/kriging/train_u"].shape[0]
            assert n_k == min(finite, cap), (name, k, n_k, finite)
            k += 1
        assert k == len(edges) - 1, name


def test_kriging_lowers_the_pooled_heldout_error(shipped_library: SurrogateLibrary) -> None:
    """Over the 24 shipped families' held-out LPM runs, the PCE + Kriging surrogate
    has a lower median relative error of HIC15, Nij and every chest measure than
    the PCE alone (the same artifacts with the Kriging left out)."""
    errs: dict[str, tuple[list[float], list[float]]] = {}
    for name, fam in shipped_library.families().items():
        arrays = _artifact_arrays(name)
        xh, yh = arrays["heldout_x"], arrays["heldout_y"]
        ok = np.all(np.isfinite(yh), axis=1)
        with_k = fam.predict(xh[ok])
        without = without_kriging(fam, default_artifact_dir()).predict(xh[ok])
        for j, o in enumerate(fam.outputs):
            if o in ("p_iss15", "iss"):
                continue
            t = np.maximum(np.abs(yh[ok, j]), 1e-12)
            a, b = errs.setdefault(o, ([], []))
            a.extend(np.abs(with_k[:, j] - yh[ok, j]) / t)
            b.extend(np.abs(without[:, j] - yh[ok, j]) / t)
    for o in ("hic15", "nij", "chest_deflection_mm", "chest_vc_m_s", "chest_a3ms_g"):
        a, b = errs[o]
        assert np.median(a) < np.median(b), o


def test_propagation_through_a_kriged_piece_matches_predict(
    shipped_library: SurrogateLibrary,
) -> None:
    fam = shipped_library.families()["frontal__female_5th__belted__no_airbag"]
    point = {
        "delta_v_kmh": 80.0,
        "angle_deg": 10.0,
        "posture_deg": 12.0,
        "seat_track_mm": 30.0,
        "duration_ms": 95.0,
    }
    r = fam.propagate(**point, posture_sd_deg=0.0, seat_track_sd_mm=0.0)
    x = np.array([[point[n] for n in INPUT_NAMES]])
    pred = fam.predict(x)[0]
    for j, o in enumerate(fam.outputs):
        if o in r.measures:
            np.testing.assert_allclose(r.measures[o], pred[j], rtol=1e-9)
