"""The compiled region blocks and P(ISS >= t) equal the numpy batch reference, bit for bit."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

from models.impact_mode import ImpactMode
from models.injury.batch import (
    MEASURE_NAMES,
    p_iss15_batch,
    p_iss_at_least_batch,
    region_blocks_checked,
)
from models.injury.batch_compiled import (
    curve_inputs,
    p_iss15_trusted,
    p_iss_at_least_compiled,
    region_blocks_compiled,
)
from models.notification import Body
from tests.models.injury.test_injury_batch import MODE_MEASURES, SCALES, _random_measures


@pytest.mark.parametrize("mode", list(ImpactMode))
@pytest.mark.parametrize("body", list(Body))
@pytest.mark.parametrize("age", [None, 0.0, 35.0, 82.5])
def test_compiled_equals_numpy_batch_bit_for_bit(
    mode: ImpactMode, body: Body, age: float | None
) -> None:
    """Every mode's measures, their subsets and the CTI given directly, many thresholds.

    HIC up to 4,000 reaches the levels above AIS 4, where the curves cross and
    are forced monotone; exact zeros reach the HIC curve's limit.
    """
    names = MODE_MEASURES[mode]
    seed = zlib.crc32(f"compiled {mode.value} {body.value} {age}".encode())
    values = _random_measures(names, 700, seed)
    subsets = [names, names[:2], names[2:], ("hic15",), ("nij",), ()]
    if mode is not ImpactMode.REAR:
        subsets.append(("chest_deflection_mm", "chest_cti", "hic15"))
        values["chest_cti"] = _random_measures(("chest_cti",), 700, seed + 1)["chest_cti"]
    for subset in subsets:
        v = {k: values[k] for k in subset}
        n = 700 if v else 0
        inputs = curve_inputs(v, n, body, age, mode)
        for threshold in (1.0, 9.0, 15.0, 16.0, 25.0, 41.0, 75.0):
            expected = p_iss_at_least_batch(v, body, age, mode, threshold) if v else np.zeros(0)
            got = p_iss_at_least_compiled(inputs, threshold)
            assert got.shape == (n,)
            assert np.array_equal(got, expected), (subset, threshold)
        if v:
            assert np.array_equal(
                p_iss15_trusted(v, body, age, mode), p_iss15_batch(v, body, age, mode)
            )
        blocks = region_blocks_compiled(v, n, body, age, mode)
        reference = region_blocks_checked(v, n, body, age, mode)
        assert list(blocks) == list(reference)
        for region, block in reference.items():
            assert np.array_equal(blocks[region], block), (subset, region)
        one = {k: x[:1] for k, x in v.items()}  # the assessment's single set
        single = region_blocks_compiled(one, 1, body, age, mode)
        for region, block in region_blocks_checked(one, 1, body, age, mode).items():
            assert np.array_equal(single[region], block), (subset, region)


def test_saturated_and_tiny_measures() -> None:
    """Far past every curve's saturation and at the smallest positive values."""
    n = 50
    big = {k: np.full(n, 1e6 * SCALES[k]) for k in MEASURE_NAMES if k in SCALES}
    tiny = {k: np.full(n, 1e-300) for k in big}
    for values in (big, tiny):
        for mode in ImpactMode:
            v = {k: values[k] for k in MODE_MEASURES[mode]}
            got = p_iss15_trusted(v, Body.MALE_50TH, 40.0, mode)
            assert np.array_equal(got, p_iss15_batch(v, Body.MALE_50TH, 40.0, mode))


def test_age_is_checked() -> None:
    with pytest.raises(ValueError, match="age_years"):
        curve_inputs({"chest_deflection_mm": np.ones(2)}, 2, Body.MALE_50TH, -1.0, "frontal")
