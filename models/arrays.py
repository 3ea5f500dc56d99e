"""The engine's array type aliases (numpy typing), defined once."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = ["BoolArray", "FloatArray", "IntArray"]

#: Float64 array of any shape (shapes are in each function's docstring).
FloatArray = npt.NDArray[np.float64]
#: Int64 array.
IntArray = npt.NDArray[np.int64]
#: Boolean array.
BoolArray = npt.NDArray[np.bool_]
