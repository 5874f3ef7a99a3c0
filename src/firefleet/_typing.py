"""Array type aliases shared by the package (batch-first NumPy arrays)."""

import numpy as np
from numpy.typing import NDArray

__all__ = ["BoolArray", "Float32Array", "FloatArray", "IntArray"]

FloatArray = NDArray[np.float64]
"""A float64 array (SI units; shapes in each function's docstring)."""
Float32Array = NDArray[np.float32]
"""A float32 array (images, disparities)."""
IntArray = NDArray[np.int64]
"""An int64 array (indices, counts)."""
BoolArray = NDArray[np.bool_]
"""A boolean mask."""
