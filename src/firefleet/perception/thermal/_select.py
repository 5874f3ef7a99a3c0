"""Two neighbouring order statistics of a float array, exactly and fast (compiled).

The detector takes medians of small sets many times a frame: the column steps of the
destriping (79 sets of ~60 differences) and the frame's background (4,800 pixels).
Hoare's quickselect on such sets spends most of its time in branches it cannot
predict. :func:`order_pair` buckets the values instead: a key monotone in the value
(``int((x - min) * scale)``: floating-point subtraction, multiplication and truncation
are monotone), the buckets' counts, then a quickselect among the few values of the one
or two buckets that hold the ranks asked for. Equal floats are the same bits but for
the two zeros: a set holding a negative zero goes to quickselect as a whole, so that
which zero comes out is the one quickselect gives. The result is the values NumPy's
``partition`` (and so ``median``) finds, bit for bit
(tests/perception/test_thermal_select.py).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from firefleet._typing import FloatArray

__all__ = ["order_pair", "quickselect"]


@numba.njit(cache=True)
def quickselect(buf: FloatArray, m: int, k: int) -> float:  # pragma: no cover - compiled
    """The ``k``-th smallest of ``buf[:m]`` (Hoare's quickselect, in place: afterwards
    ``buf[:k]`` holds the ``k`` smallest).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal._select import quickselect
    >>> float(quickselect(np.array([5.0, 1.0, 4.0, 2.0, 3.0]), 5, 1))
    2.0
    """
    lo, hi = 0, m - 1
    while lo < hi:
        pivot = buf[(lo + hi) // 2]
        i, j = lo, hi
        while i <= j:
            while buf[i] < pivot:
                i += 1
            while buf[j] > pivot:
                j -= 1
            if i <= j:
                buf[i], buf[j] = buf[j], buf[i]
                i += 1
                j -= 1
        if k <= j:
            hi = j
        elif k >= i:
            lo = i
        else:
            break
    return float(buf[k])


@numba.njit(cache=True)
def _pair_by_select(
    x: FloatArray, m: int, k: int, work: FloatArray
) -> tuple[float, float]:  # pragma: no cover - compiled
    """:func:`order_pair` by quickselect on a copy (the reference, and the fallback)."""
    for i in range(m):
        work[i] = x[i]
    upper = quickselect(work, m, k)
    if k == 0:
        return upper, upper
    lower = work[0]
    for i in range(1, k):
        lower = max(lower, work[i])
    return lower, upper


@numba.njit(cache=True)
def _in_bucket(
    x: FloatArray, m: int, lo: float, scale: float, top: int, bucket: int, r: int, work: FloatArray
) -> float:  # pragma: no cover - compiled
    """The ``r``-th smallest of the values of ``x[:m]`` in ``bucket``."""
    cnt = 0
    for i in range(m):
        if min(int((x[i] - lo) * scale), top) == bucket:
            work[cnt] = x[i]
            cnt += 1
    return quickselect(work, cnt, r)


@numba.njit(cache=True)
def order_pair(
    x: FloatArray, m: int, k: int, counts: np.ndarray, work: FloatArray
) -> tuple[float, float]:  # pragma: no cover - compiled
    """The ``(k - 1)``-th and the ``k``-th smallest of ``x[:m]`` (0-based; both the
    ``k``-th when ``k`` is 0), as quickselect finds them (module notes).

    Parameters
    ----------
    x : ndarray, shape (>= m,)
        Finite values (left as they are).
    m : int
        How many (>= 1); ``0 <= k < m``.
    k : int
    counts : ndarray of int64, shape (B,)
        Work space for the buckets (B >= 2; more for larger sets: ~m / 4).
    work : ndarray, shape (>= m,)
        Work space.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal._select import order_pair
    >>> x = np.random.default_rng(0).normal(size=101)
    >>> lower, upper = order_pair(x, 101, 50, np.zeros(32, np.int64), np.empty(101))
    >>> (lower, upper) == tuple(np.sort(x)[49:51]), bool(upper == np.median(x))
    (True, True)
    """
    lo = x[0]
    hi = x[0]
    signed_zero = False
    for i in range(m):
        v = x[i]
        lo = min(lo, v)
        hi = max(hi, v)
        if v == 0.0 and math.copysign(1.0, v) < 0.0:
            signed_zero = True
    nb = counts.size
    scale = (nb - 1) / (hi - lo) if hi > lo else 0.0
    if lo == hi or signed_zero or not (0.0 < scale < np.inf):
        if lo == hi and not signed_zero:
            return float(lo), float(lo)  # all the same bits
        return _pair_by_select(x, m, k, work)
    top = nb - 1
    counts[:] = 0
    for i in range(m):
        counts[min(int((x[i] - lo) * scale), top)] += 1
    # the buckets holding ranks k - 1 and k, and the ranks within them
    below = 0
    b_lo = -1
    r_lo = 0
    want_lo = max(k - 1, 0)
    for b in range(nb):
        c = counts[b]
        if b_lo < 0 and below + c > want_lo:
            b_lo, r_lo = b, want_lo - below
        if below + c > k:
            upper = _in_bucket(x, m, lo, scale, top, b, k - below, work)
            if k == 0:
                return upper, upper
            if b == b_lo:  # both in one bucket (k - below >= 1): the smaller ones first
                lower = work[0]
                for i in range(1, k - below):
                    lower = max(lower, work[i])
                return lower, upper
            lower = _in_bucket(x, m, lo, scale, top, b_lo, r_lo, work)
            return lower, upper
        below += c
    return _pair_by_select(x, m, k, work)  # pragma: no cover - the counts add up to m
