"""The one exception type for bad input.

Every check of user input (a scenario field, an array's shape, a file) raises
:class:`InputError`, a :class:`ValueError` subclass whose message names the field,
the value and what was expected. The command line turns it into one line on stderr
and exit status 2.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["InputError", "as_float_array", "check_fields"]


class InputError(ValueError):
    """Bad input: the message names what is wrong and what was expected.

    Examples
    --------
    >>> from firefleet.errors import InputError
    >>> issubclass(InputError, ValueError)
    True
    """


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

    Examples
    --------
    >>> from firefleet.errors import InputError, as_float_array
    >>> as_float_array([[1, 2, 3]], "pose", (None, 3)).dtype
    dtype('float64')
    >>> try:
    ...     as_float_array([1.0, 2.0], "pose", (None, 3))
    ... except InputError as error:
    ...     print(error)
    pose must have shape (N, 3), got (2,)
    """
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim != len(shape) or any(
        s is not None and a != s for a, s in zip(arr.shape, shape, strict=True)
    ):
        expected = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
        raise InputError(f"{name} must have shape {expected}, got {arr.shape}")
    # the method, not np.all(): this runs in every simulator tick, and np.all's dispatch
    # costs about a microsecond more than the check itself on a small array
    if not np.isfinite(arr).all():
        raise InputError(f"{name} must be finite, got non-finite values")
    return arr


def check_fields(
    obj: object,
    section: str,
    *,
    positive: Iterable[str] = (),
    non_negative: Iterable[str] = (),
) -> None:
    """Check numeric fields of a parameter dataclass, naming ``section.field`` on failure.

    Raises
    ------
    InputError
        If a field in ``positive`` is not a finite number > 0, or one in
        ``non_negative`` is not a finite number >= 0.

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> from firefleet.errors import InputError, check_fields
    >>> @dataclass
    ... class Wheel:
    ...     radius_m: float
    >>> try:
    ...     check_fields(Wheel(radius_m=-0.1), "robot", positive=("radius_m",))
    ... except InputError as error:
    ...     print(error)
    robot.radius_m must be > 0, got -0.1
    """
    prefix = f"{section}." if section else ""
    for names, ok, bound in ((positive, float.__gt__, "> 0"), (non_negative, float.__ge__, ">= 0")):
        for name in names:
            value = getattr(obj, name)
            if not (math.isfinite(value) and ok(float(value), 0.0)):
                raise InputError(f"{prefix}{name} must be {bound}, got {value}")
