"""``np.interp`` on the radiance tables, compiled and scalar (for the kernels that convert
temperature to band radiance and back pixel by pixel: the detector's fill fractions, the
simulated camera). NumPy's formula and special cases, so NumPy's result bit for bit
(tests/perception/test_detect_kernel.py)."""

from __future__ import annotations

import numba
import numpy as np

from firefleet._typing import FloatArray

__all__ = [
    "interp_sorted",
    "interp_sorted_from",
    "interp_sorted_slopes",
    "interp_table",
    "table_slopes",
]


@numba.njit(cache=True)
def interp_table(x: float, xp: FloatArray, fp: FloatArray) -> float:  # pragma: no cover - compiled
    """``np.interp(x, xp, fp)`` for a table of equal steps and ``xp[0] <= x <= xp[-1]``.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal._table import interp_table
    >>> xp = np.arange(0.0, 10.25, 0.25)
    >>> float(interp_table(3.1, xp, xp**2)) == float(np.interp(3.1, xp, xp**2))
    True
    """
    if x >= xp[-1]:
        return float(fp[-1])
    step = (xp[-1] - xp[0]) / (xp.size - 1)
    j = min(max(int((x - xp[0]) / step), 0), xp.size - 2)
    while j > 0 and xp[j] > x:
        j -= 1
    while j < xp.size - 2 and xp[j + 1] <= x:
        j += 1
    if xp[j] == x:
        return float(fp[j])
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    return float(slope * (x - xp[j]) + fp[j])


@numba.njit(cache=True)
def _bracket(x: float, xp: FloatArray, lo: int, hi: int) -> int:  # pragma: no cover - compiled
    """The interval ``lo`` with ``xp[lo] <= x < xp[lo + 1]``, for ``xp[0] <= x < xp[-1]``
    (``xp`` ascending, n >= 2), by bisection from the guess ``xp[lo] <= x < xp[hi]``;
    a guess that does not hold widens to the whole table."""
    n = xp.size
    lo = min(max(lo, 0), n - 2)
    hi = min(max(hi, lo + 1), n - 1)
    if xp[lo] > x:
        lo = 0
    if xp[hi] <= x:
        hi = n - 1
    while hi - lo > 1:  # xp[lo] <= x < xp[hi]
        mid = (lo + hi) // 2
        if xp[mid] <= x:
            lo = mid
        else:
            hi = mid
    return lo


@numba.njit(cache=True)
def interp_sorted(x: float, xp: FloatArray, fp: FloatArray) -> float:  # pragma: no cover - compiled
    """``np.interp(x, xp, fp)`` for strictly increasing ``xp`` (bisection), clamped to
    ``fp[0]`` and ``fp[-1]`` outside.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal._table import interp_sorted
    >>> xp = np.array([0.0, 1.0, 4.0, 9.0])
    >>> [float(interp_sorted(v, xp, np.sqrt(xp))) for v in (-1.0, 2.5, 9.0, 20.0)]
    [0.0, 1.5, 3.0, 3.0]
    """
    n = xp.size
    if x >= xp[n - 1]:
        return float(fp[n - 1])
    if x < xp[0]:
        return float(fp[0])
    lo = _bracket(x, xp, 0, n - 1)
    if xp[lo] == x:
        return float(fp[lo])
    slope = (fp[lo + 1] - fp[lo]) / (xp[lo + 1] - xp[lo])
    return float(slope * (x - xp[lo]) + fp[lo])


@numba.njit(cache=True)
def interp_sorted_from(
    x: float, xp: FloatArray, fp: FloatArray, lo: int, hi: int
) -> float:  # pragma: no cover - compiled
    """:func:`interp_sorted` with the search started in ``xp[lo:hi + 1]`` (cheap when the
    answer lies there; the same result wherever it lies).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal._table import interp_sorted_from
    >>> xp = np.array([0.0, 1.0, 4.0, 9.0])
    >>> [float(interp_sorted_from(2.5, xp, np.sqrt(xp), g, g + 1)) for g in (0, 1, 2)]
    [1.5, 1.5, 1.5]
    """
    n = xp.size
    if x >= xp[n - 1]:
        return float(fp[n - 1])
    if x < xp[0]:
        return float(fp[0])
    lo = _bracket(x, xp, lo, hi)
    if xp[lo] == x:
        return float(fp[lo])
    slope = (fp[lo + 1] - fp[lo]) / (xp[lo + 1] - xp[lo])
    return float(slope * (x - xp[lo]) + fp[lo])


def table_slopes(xp: FloatArray, fp: FloatArray) -> FloatArray:
    """Each interval's slope ``(fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])``, shape (n - 1,):
    the numbers :func:`interp_sorted_from` divides out at every call (the same IEEE
    operations, so the same values), for :func:`interp_sorted_slopes`.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal._table import table_slopes
    >>> table_slopes(np.array([0.0, 1.0, 4.0]), np.array([0.0, 1.0, 2.0])).tolist()
    [1.0, 0.3333333333333333]
    """
    x = np.asarray(xp, dtype=np.float64)
    f = np.asarray(fp, dtype=np.float64)
    out: FloatArray = (f[1:] - f[:-1]) / (x[1:] - x[:-1])
    return out


@numba.njit(cache=True)
def interp_sorted_slopes(
    x: float, xp: FloatArray, fp: FloatArray, slope: FloatArray, lo: int, hi: int
) -> float:  # pragma: no cover - compiled
    """:func:`interp_sorted_from` with the intervals' slopes given (:func:`table_slopes`
    of ``xp`` and ``fp``): the same search and the same result, without a division.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal._table import (
    ...     interp_sorted_from, interp_sorted_slopes, table_slopes)
    >>> xp = np.array([0.0, 1.0, 4.0, 9.0])
    >>> fp = np.sqrt(xp)
    >>> k = table_slopes(xp, fp)
    >>> x = (-1.0, 0.5, 2.5, 4.0, 8.9, 20.0)
    >>> [interp_sorted_slopes(v, xp, fp, k, 1, 2) == interp_sorted_from(v, xp, fp, 1, 2) for v in x]
    [True, True, True, True, True, True]
    """
    n = xp.size
    if x >= xp[n - 1]:
        return float(fp[n - 1])
    if x < xp[0]:
        return float(fp[0])
    lo = _bracket(x, xp, lo, hi)
    if xp[lo] == x:
        return float(fp[lo])
    return float(slope[lo] * (x - xp[lo]) + fp[lo])
