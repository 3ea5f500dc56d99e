"""A tiny surrogate library, built on the fly against the current LPM code.

Frontal, 50th male, belted with airbag, delta-V 40-60 km/h in one piece (the
shipped families cover 5-120 km/h in four pieces): 250 LPM runs, 150
bootstrap replicates with the selection rerun, 100 held-out points; about
10-20 s on one core.
"""

from __future__ import annotations

from dataclasses import replace

from models.offline.surrogate.build import BuildConfig
from models.surrogate.spec import FAMILIES, FamilySpec

TINY_NAME = "frontal__male_50th__belted__airbag"
TINY_DELTA_V = (40.0, 60.0)
TINY_CONFIG = BuildConfig(
    n_train=250,
    n_train_by_mode=(),
    n_holdout=100,
    n_boot=150,
    seed=7,
    delta_v_pieces_kmh=TINY_DELTA_V,
)


def tiny_spec() -> FamilySpec:
    spec = next(s for s in FAMILIES if s.name == TINY_NAME)
    return replace(spec, ranges=(TINY_DELTA_V, *spec.ranges[1:]))
