"""Array type aliases shared by the physics and solver layers."""

from typing import TypeAlias

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray: TypeAlias = NDArray[np.float64]
BoolArray: TypeAlias = NDArray[np.bool_]

__all__ = ["ArrayLike", "BoolArray", "FloatArray", "as_float"]


def as_float(value: object) -> FloatArray:
    """``value`` as a float64 array (typed, so that NumPy arithmetic stays checked)."""
    return np.asarray(value, dtype=np.float64)
