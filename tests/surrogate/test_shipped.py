"""The shipped artifacts match the current LPM code and parameter set.

The checksum test fails after any change of
the LPM code or parameters until ``aacn-triage build-surrogates`` is rerun.
"""

from __future__ import annotations

import pytest

from models.lpm.fingerprint import lpm_code_sha256
from models.lpm.params import load_parameter_set
from models.surrogate.evaluate import SurrogateLibrary


def test_shipped_artifacts_match_the_current_lpm() -> None:
    lib = SurrogateLibrary.load()  # verifies every checksum of the manifest
    assert lib.lpm_code_sha256 == lpm_code_sha256(), "rerun aacn-triage build-surrogates"
    assert lib.parameter_set_sha256 == load_parameter_set().sha256
    assert lib.stale_reason() is None


def _pooled_heldout() -> tuple[dict[str, float], float]:
    """Pooled held-out errors of the shipped families against their own stored LPM runs."""
    import numpy as np

    from models.surrogate.evaluate import default_artifact_dir
    from models.surrogate.store import read_artifact

    lib = SurrogateLibrary.load()
    rel: dict[str, list[float]] = {}
    agree: list[bool] = []
    for name, fam in lib.families().items():
        arrays, _ = read_artifact(default_artifact_dir() / f"{name}.npz")
        x, y = arrays["heldout_x"], arrays["heldout_y"]
        ok = np.all(np.isfinite(y), axis=1)
        pred = fam.predict(x[ok])
        y = y[ok]
        for k, o in enumerate(fam.outputs):
            if o == "p_iss15":
                agree += list((pred[:, k] >= 0.5) == (y[:, k] >= 0.5))
            elif o != "iss":
                err = np.abs(pred[:, k] - y[:, k]) / np.maximum(np.abs(y[:, k]), 1e-12)
                rel.setdefault(o, []).extend(err)
    return {o: float(np.median(v)) for o, v in rel.items()}, float(np.mean(agree))


def test_shipped_heldout_pooled() -> None:
    """Issue 5 held-out check on the shipped artifacts (their stored held-out LPM runs,
    150 uniform random points per family): pooled median relative error of every
    measure under 5 %; ISS15+ agreement held to a 95 % regression bound (target 97 %,
    see the xfail below and REPORT.md for the per-family figures)."""
    errors, agreement = _pooled_heldout()
    assert all(e < 0.05 for e in errors.values()), errors
    assert agreement >= 0.95, agreement


def test_shipped_heldout_agreement_target() -> None:
    """Issue 5 target on the pooled held-out points of the 24 families (REPORT.md
    Table B)."""
    _, agreement = _pooled_heldout()
    assert agreement > 0.97, agreement


def test_shipped_heldout_agreement_at_the_service_decision() -> None:
    """Pooled over the 24 families, the surrogate and the LPM take the same decision as
    the service does (zero-load-corrected P(ISS >= 15) against the mode's threshold) on
    more than 97 % of the held-out points (REPORT.md)."""
    import numpy as np

    from models.surrogate.evaluate import default_artifact_dir
    from models.surrogate.report import service_raw_threshold
    from models.surrogate.store import read_artifact

    agree: list[bool] = []
    for name, fam in SurrogateLibrary.load().families().items():
        arrays, _ = read_artifact(default_artifact_dir() / f"{name}.npz")
        x, y = arrays["heldout_x"], arrays["heldout_y"]
        ok = np.all(np.isfinite(y), axis=1)
        k = fam.outputs.index("p_iss15")
        thr = service_raw_threshold(name, fam.outputs)
        assert 0.10 < thr < 0.15, "the threshold on the uncorrected scale lies above t"
        pred = fam.predict(x[ok])[:, k]
        agree += list((pred >= thr) == (y[ok][:, k] >= thr))
    assert float(np.mean(agree)) > 0.97


@pytest.mark.xfail(
    strict=True,
    reason="open item: per family, the frontal families with a head-strike threshold"
    " (belted without airbag 91-94 %) and four others stay at 95-97 % (REPORT.md Table B)",
)
def test_shipped_heldout_agreement_target_per_family() -> None:
    import numpy as np

    from models.surrogate.evaluate import default_artifact_dir
    from models.surrogate.store import read_artifact

    low = {}
    for name, fam in SurrogateLibrary.load().families().items():
        arrays, _ = read_artifact(default_artifact_dir() / f"{name}.npz")
        x, y = arrays["heldout_x"], arrays["heldout_y"]
        ok = np.all(np.isfinite(y), axis=1)
        k = fam.outputs.index("p_iss15")
        pred = fam.predict(x[ok])[:, k]
        agreement = float(np.mean((pred >= 0.5) == (y[ok][:, k] >= 0.5)))
        if agreement <= 0.97:
            low[name] = agreement
    assert low == {}
