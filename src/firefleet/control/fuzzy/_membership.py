"""MATLAB's membership functions, defined once as a compiled scalar function.

:func:`mf_value` is the one definition of every input membership function of
the engine. Everything else is built from it: :func:`membership` loops it over an
array, the system evaluation (:func:`firefleet.control.fuzzy.evaluate`, one sample or
a batch) and the simulator's compiled team loop call it through
:func:`firefleet.control.fuzzy._kernel.eval_one`. The tests compare it with a NumPy
transcription of MATLAB's formulas and with scikit-fuzzy on random parameters and
points, breakpoints included.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal, get_args

import numba
import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError

__all__ = ["MF_CODES", "MfKind", "membership", "membership_one", "mf_value"]


MfKind = Literal["trimf", "trapmf", "gaussmf", "gbellmf", "sigmf", "smf", "zmf"]
"""Input membership function shapes (MATLAB names)."""

MF_KINDS: tuple[str, ...] = get_args(MfKind)
MF_CODES = {"trimf": 0, "trapmf": 1, "gaussmf": 2, "gbellmf": 3, "sigmf": 4, "smf": 5, "zmf": 6}
"""Integer code of each membership-function kind (the ``kind`` of :func:`membership_one`)."""
N_PARAMS: dict[str, int] = {
    "trimf": 3,
    "trapmf": 4,
    "gaussmf": 2,
    "gbellmf": 3,
    "sigmf": 2,
    "smf": 2,
    "zmf": 2,
}
_PARAM_NAMES: dict[str, str] = {
    "trimf": "[a b c]",
    "trapmf": "[a b c d]",
    "gaussmf": "[sigma c]",
    "gbellmf": "[a b c]",
    "sigmf": "[a c]",
    "smf": "[a b]",
    "zmf": "[a b]",
}


def check_mf_params(kind: str, params: Sequence[float], where: str) -> tuple[float, ...]:
    """Validate ``params`` for ``kind`` as MATLAB does; returns them as floats."""
    if kind not in N_PARAMS:
        raise InputError(
            f"{where}: unknown membership function type {kind!r}; "
            f"expected one of {', '.join(MF_KINDS)}"
        )
    try:
        values = tuple(float(p) for p in params)
    except (TypeError, ValueError):
        raise InputError(f"{where}: {kind} parameters must be numbers, got {params!r}") from None
    n = N_PARAMS[kind]
    if len(values) != n:
        raise InputError(
            f"{where}: {kind} takes {n} parameters {_PARAM_NAMES[kind]}, got {len(values)}"
        )
    if not all(math.isfinite(v) for v in values):
        raise InputError(f"{where}: {kind} parameters must be finite, got {list(values)}")
    if kind == "trimf":
        a, b, c = values
        if not a <= b <= c:
            raise InputError(f"{where}: trimf [a b c] needs a <= b <= c, got {list(values)}")
    elif kind == "trapmf":
        a, b, c, d = values
        if not (a <= b and c <= d):
            raise InputError(
                f"{where}: trapmf [a b c d] needs a <= b and c <= d, got {list(values)}"
            )
    elif kind == "gaussmf" and values[0] == 0.0:
        raise InputError(f"{where}: gaussmf [sigma c] needs sigma != 0")
    elif kind == "gbellmf" and values[0] == 0.0:
        raise InputError(f"{where}: gbellmf [a b c] needs a != 0")
    return values


@numba.njit(cache=True, error_model="numpy")
def mf_value(
    kind: int, a: float, b: float, c: float, d: float, x: float
) -> float:  # pragma: no cover
    """Degree of ``x`` in a membership function: the engine's one definition.

    Parameters
    ----------
    kind : int
        The shape, ``MF_CODES[name]``.
    a, b, c, d : float
        Its parameters in MATLAB's order, padded with zeros (``gaussmf [sigma c]``
        is ``a = sigma, b = c``; ``sigmf [a c]`` is ``a, b = c``).
    x : float
        The point, finite.

    Returns
    -------
    float
        The degree in [0, 1]. Degenerate shapes are MATLAB's: a vertical side of
        ``trimf``/``trapmf`` is 1 at the shoulder itself; ``smf``/``zmf`` with
        a >= b are the step at the midpoint; ``gbellmf`` with b < 0 is 0 at its
        centre; values beyond the float range give 0 or 1, never NaN.
    """
    if kind == 0:  # trimf [a b c]
        if x == b:
            return 1.0
        if a < x < b:
            return (x - a) / (b - a)
        if b < x < c:
            return (c - x) / (c - b)
        return 0.0
    if kind == 1:  # trapmf [a b c d]
        y1 = 1.0 if x >= b else ((x - a) / (b - a) if x >= a and a != b else 0.0)
        y2 = 1.0 if x <= c else ((d - x) / (d - c) if x <= d and c != d else 0.0)
        return min(y1, y2)
    if kind == 2:  # gaussmf [sigma c]
        return math.exp(-((x - b) ** 2) / (2.0 * a**2))
    if kind == 3:  # gbellmf [a b c]
        ratio: float = abs((x - c) / a)
        return 1.0 / (1.0 + math.pow(ratio, 2.0 * b))
    if kind == 4:  # sigmf [a c]
        return 1.0 / (1.0 + math.exp(-a * (x - b)))
    if kind == 5:  # smf [a b]
        if a >= b:
            return 1.0 if x >= 0.5 * (a + b) else 0.0
        if x <= a:
            return 0.0
        if x <= 0.5 * (a + b):
            return 2.0 * ((x - a) / (b - a)) ** 2
        if x <= b:
            return 1.0 - 2.0 * ((x - b) / (b - a)) ** 2
        return 1.0
    # zmf [a b]
    if a >= b:
        return 1.0 if x <= 0.5 * (a + b) else 0.0
    if x <= a:
        return 1.0
    if x <= 0.5 * (a + b):
        return 1.0 - 2.0 * ((x - a) / (b - a)) ** 2
    if x <= b:
        return 2.0 * ((x - b) / (b - a)) ** 2
    return 0.0


@numba.njit(cache=True)
def membership_one(kind: int, p: FloatArray, m: int, x: float) -> float:  # pragma: no cover
    """:func:`mf_value` of membership function ``m``, parameters row ``m`` of ``p`` (M, 4)."""
    return mf_value(kind, float(p[m, 0]), float(p[m, 1]), float(p[m, 2]), float(p[m, 3]), x)


@numba.njit(cache=True)
def _membership_many(kind: int, p: FloatArray, x: FloatArray, out: FloatArray) -> bool:
    """``out[k] = membership_one(kind, p, 0, x[k])``; False (and stop) at a non-finite x."""
    for k in range(x.shape[0]):  # pragma: no cover - jit
        if not math.isfinite(x[k]):
            return False
        out[k] = membership_one(kind, p, 0, x[k])
    return True


def membership(kind: MfKind, params: Sequence[float], x: ArrayLike) -> FloatArray:
    """Membership degrees of ``x`` in one MATLAB membership function.

    Parameters
    ----------
    kind : {"trimf", "trapmf", "gaussmf", "gbellmf", "sigmf", "smf", "zmf"}
        The shape, with MATLAB's parameters:

        * ``trimf [a b c]``: triangle, feet a and c, peak b; a <= b <= c;
        * ``trapmf [a b c d]``: trapezoid ``min((x - a)/(b - a), 1, (d - x)/(d - c))``
          clipped to [0, 1]; a <= b, c <= d (b > c gives MATLAB's flat-topped
          triangle below 1);
        * ``gaussmf [sigma c]``: ``exp(-(x - c)^2 / (2 sigma^2))``, sigma != 0;
        * ``gbellmf [a b c]``: ``1 / (1 + |(x - c)/a|^(2 b))``, a != 0;
        * ``sigmf [a c]``: ``1 / (1 + exp(-a (x - c)))``;
        * ``smf [a b]``, ``zmf [a b]``: quadratic S and Z splines from a to b; for
          a >= b MATLAB's step at the midpoint (``x >= (a + b)/2``, ``x <= ...``).

        A vertical side (a == b or c == d in trimf and trapmf) is MATLAB's: the
        membership is 1 at the shoulder itself.
    params : sequence of float
        The parameters, in MATLAB's order.
    x : array_like
        Points, any shape, in the input's units.

    Returns
    -------
    ndarray of float64
        Degrees in [0, 1], the shape of ``x``.

    Raises
    ------
    InputError
        Unknown ``kind``, wrong number of parameters, parameters MATLAB rejects, or
        non-finite ``x``.

    Notes
    -----
    Computed by :func:`membership_one`, the definition every evaluation path uses.

    Examples
    --------
    >>> from firefleet.control.fuzzy import membership
    >>> membership("trimf", [0, 2, 4], [1.0, 2.0, 3.5]).tolist()
    [0.5, 1.0, 0.25]
    """
    values = check_mf_params(kind, params, "membership")
    arr = np.asarray(x, dtype=np.float64)
    p = np.zeros((1, 4))
    p[0, : len(values)] = values
    flat = np.ascontiguousarray(arr).reshape(-1)
    out = np.empty(flat.shape[0])
    if not _membership_many(MF_CODES[kind], p, flat, out):
        raise InputError("membership: x must be finite, got non-finite values")
    return out.reshape(arr.shape)
