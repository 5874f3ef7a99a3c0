"""The one exception type for bad input.

Every check of user input (a scenario field, an array's shape, a file) raises
:class:`InputError`, a :class:`ValueError` subclass whose message names the field,
the value and what was expected. The command line turns it into one line on stderr
and exit status 2.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["InputError", "as_float_array"]


class InputError(ValueError):
    """Bad input: the message names what is wrong and what was expected."""


def as_float_array(
    value: ArrayLike, name: str, shape: tuple[int | None, ...]
) -> NDArray[np.float64]:
    """Convert ``value`` to a float64 array and check its shape.

    Parameters
    ----------
    value : array_like
        The input.
    name : str
        Its name in error messages.
    shape : tuple of int or None
        Expected shape; ``None`` matches any length on that axis.

    Returns
    -------
    ndarray of float64
        The array, with the expected shape.

    Raises
    ------
    InputError
        If the number of axes or a fixed axis length differ, or a value is not finite.
    """
    arr = np.asarray(value, dtype=np.float64)
    expected = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
    if arr.ndim != len(shape) or any(
        s is not None and a != s for a, s in zip(arr.shape, shape, strict=True)
    ):
        raise InputError(f"{name} must have shape {expected}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name} must be finite, got non-finite values")
    return arr
