"""Paths y(x): polynomials up to fifth order (the deliverable's paths) and straight lines.

Section 2.6.1 of the deliverable: "the paths are modeled using a fifth order polynomial
to generate reasonably difficult curved paths for the robots to follow". A path is the
graph of ``y(x) = c0 + c1 x + ... + c5 x^5`` for ``x`` from ``x_start_m`` to ``x_end_m``
(either direction), travelled from its start to its end. A straight line is a path of
order one.

Arc length is integrated by composite Gauss-Legendre quadrature (the integrand
``sqrt(1 + y'^2)`` is smooth), to about 1e-12 relative; points equally spaced in arc
length are found by Newton's method on the arc length.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.polynomial import polynomial as npoly
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError

__all__ = ["PolynomialPath", "straight_line"]


_PANELS = 256
"""Quadrature panels over the path's x range."""
_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(12)
"""Gauss-Legendre nodes and weights on [-1, 1] (exact for polynomials of degree 23)."""


@dataclass(frozen=True)
class PolynomialPath:
    """The path ``y = sum_k coefficients[k] x^k`` from ``x_start_m`` to ``x_end_m``.

    Attributes
    ----------
    coefficients : tuple of float
        ``c0 .. c5`` (at most six; fewer for lower orders) [m^(1-k)].
    x_start_m, x_end_m : float
        Where the path starts and ends [m]; ``x_end_m < x_start_m`` travels towards -x.

    Examples
    --------
    >>> from firefleet.planning import PolynomialPath
    >>> parabola = PolynomialPath((0.0, 0.0, 1.0), x_start_m=0.0, x_end_m=2.0)
    >>> float(parabola.y(2.0)), float(parabola.slope(2.0)), float(parabola.curvature(0.0))
    (4.0, 4.0, 2.0)
    >>> round(parabola.length_m, 4)  # sqrt(17) + asinh(4) / 4
    4.6468
    """

    coefficients: tuple[float, ...]
    x_start_m: float
    x_end_m: float

    def __post_init__(self) -> None:
        c = self.coefficients
        if not 1 <= len(c) <= 6:
            raise InputError(f"a path has 1 to 6 coefficients (order <= 5), got {len(c)}")
        if not all(math.isfinite(v) for v in (*c, self.x_start_m, self.x_end_m)):
            raise InputError("path coefficients and ends must be finite numbers")
        if self.x_start_m == self.x_end_m:
            raise InputError(f"a path needs x_end_m != x_start_m, both are {self.x_start_m}")

    @property
    def direction(self) -> float:
        """+1 if the path is travelled towards +x, -1 otherwise."""
        return 1.0 if self.x_end_m > self.x_start_m else -1.0

    def y(self, x: ArrayLike) -> FloatArray:
        """Height of the path at ``x`` [m] (any shape)."""
        return np.asarray(npoly.polyval(np.asarray(x, dtype=np.float64), self.coefficients))

    def slope(self, x: ArrayLike) -> FloatArray:
        """``dy/dx`` at ``x``."""
        return np.asarray(npoly.polyval(np.asarray(x, dtype=np.float64), self._d1))

    def heading(self, x: ArrayLike) -> FloatArray:
        """Direction of travel at ``x`` [rad], in [-pi, pi]: the tangent, exactly."""
        d = self.direction
        along = np.full(np.shape(x), d, dtype=np.float64)
        return np.asarray(np.arctan2(d * self.slope(x), along), dtype=np.float64)

    def curvature(self, x: ArrayLike) -> FloatArray:
        """Signed curvature ``y'' / (1 + y'^2)^(3/2)`` [1/m] (positive turning left
        when travelled towards +x)."""
        xx = np.asarray(x, dtype=np.float64)
        d1 = npoly.polyval(xx, self._d1)
        d2 = npoly.polyval(xx, self._d2)
        return np.asarray(self.direction * d2 / (1.0 + d1 * d1) ** 1.5)

    @cached_property
    def _d1(self) -> FloatArray:
        return np.asarray(npoly.polyder(np.asarray(self.coefficients)), dtype=np.float64)

    @cached_property
    def _d2(self) -> FloatArray:
        return np.asarray(npoly.polyder(np.asarray(self.coefficients), 2), dtype=np.float64)

    def _speed(self, x: FloatArray) -> FloatArray:
        """``ds/dx = sqrt(1 + y'^2)``."""
        d1 = npoly.polyval(x, self._d1)
        return np.asarray(np.sqrt(1.0 + d1 * d1))

    @cached_property
    def _table(self) -> tuple[FloatArray, FloatArray]:
        """Panel edges ``x`` (ascending in travel) and the arc length at each [m]."""
        edges = np.linspace(self.x_start_m, self.x_end_m, _PANELS + 1)
        return edges, np.r_[0.0, np.cumsum(self._panel_lengths(edges[:-1], edges[1:]))]

    def _panel_lengths(self, a: FloatArray, b: FloatArray) -> FloatArray:
        """Arc length from ``a`` to ``b`` (elementwise, |b - a| small), by Gauss-Legendre."""
        half = 0.5 * (b - a)
        mid = 0.5 * (b + a)
        nodes = mid[..., None] + half[..., None] * _GAUSS_X
        return np.asarray(np.abs(half) * (self._speed(nodes) @ _GAUSS_W))

    @property
    def length_m(self) -> float:
        """Length of the path [m]."""
        return float(self._table[1][-1])

    def arc_length(self, x: ArrayLike) -> FloatArray:
        """Arc length from the start to ``x`` [m] (``x`` clipped to the path's range)."""
        edges, cum = self._table
        lo, hi = sorted((self.x_start_m, self.x_end_m))
        xx = np.clip(np.asarray(x, dtype=np.float64), lo, hi)
        # panel index of each x, counted along the direction of travel
        u = (xx - self.x_start_m) / (self.x_end_m - self.x_start_m) * _PANELS
        k = np.clip(np.floor(u).astype(np.int64), 0, _PANELS - 1)
        return np.asarray(cum[k] + self._panel_lengths(edges[k], xx))

    def x_at(self, s: ArrayLike) -> FloatArray:
        """The ``x`` at arc length ``s`` from the start [m] (``s`` clipped to the length).

        Newton's method from the tabulated arc length; converges to rounding in a few
        iterations because ``ds/dx >= 1``.
        """
        edges, cum = self._table
        ss = np.clip(np.asarray(s, dtype=np.float64), 0.0, self.length_m)
        x = np.interp(ss, cum, edges)
        for _ in range(20):
            step = (self.arc_length(x) - ss) / self._speed(x) * self.direction
            x = x - step
            if np.all(np.abs(step) < 1e-13 * (1.0 + np.abs(x))):
                break
        return np.asarray(x)

    def sample(self, n: int) -> FloatArray:
        """``n`` equal pieces: ``n + 1`` points equally spaced in arc length.

        Parameters
        ----------
        n : int
            Number of pieces (the same for every robot of a team, so a longer path gets
            sparser points, section 2.6.3).

        Returns
        -------
        ndarray, shape (n + 1, 3)
            x [m], y [m] and the path's heading there [rad]; row 0 is the start, row
            ``n`` the end.
        """
        if n < 1:
            raise InputError(f"a path is sampled into n >= 1 pieces, got {n}")
        x = self.x_at(np.linspace(0.0, self.length_m, n + 1))
        x[0], x[-1] = self.x_start_m, self.x_end_m
        return np.stack([x, self.y(x), self.heading(x)], axis=1)

    def distance(self, points: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Distance from points to the path, and the arc length of the closest point.

        Parameters
        ----------
        points : array_like, shape (..., 2)
            x, y [m].

        Returns
        -------
        distance : ndarray, shape (...)
            Euclidean distance to the nearest point of the path (ends included) [m].
        s : ndarray, shape (...)
            Arc length of that nearest point from the start [m].
        """
        pts = np.asarray(points, dtype=np.float64)
        if pts.ndim == 0 or pts.shape[-1] != 2:
            raise InputError(f"points must have shape (..., 2), got {pts.shape}")
        flat = pts.reshape(-1, 2)
        lo, hi = sorted((self.x_start_m, self.x_end_m))
        grid = np.linspace(lo, hi, 2049)
        gy = self.y(grid)
        best = np.empty(flat.shape[0])
        for start in range(0, flat.shape[0], 4096):  # bounded memory for long runs
            chunk = flat[start : start + 4096]
            d2 = (chunk[:, :1] - grid) ** 2 + (chunk[:, 1:] - gy) ** 2
            best[start : start + chunk.shape[0]] = grid[np.argmin(d2, axis=1)]
        # Newton on g(x) = (x - px) + (y(x) - py) y'(x) = 0, kept inside the range
        x = best
        px, py = flat[:, 0], flat[:, 1]
        for _ in range(8):
            d1 = npoly.polyval(x, self._d1)
            d2c = npoly.polyval(x, self._d2)
            r = self.y(x) - py
            g = (x - px) + r * d1
            dg = 1.0 + d1 * d1 + r * d2c
            x = np.clip(x - np.where(dg > 1e-12, g / np.where(dg > 1e-12, dg, 1.0), 0.0), lo, hi)
        dist = np.hypot(x - px, self.y(x) - py)
        shape = pts.shape[:-1]
        return dist.reshape(shape), self.arc_length(x).reshape(shape)


def straight_line(start: tuple[float, float], end: tuple[float, float]) -> PolynomialPath:
    """The straight path from ``start`` to ``end`` (x, y in m; ``end`` not straight above).

    Raises
    ------
    InputError
        If the two points have the same x (a vertical line is not a graph y(x)).

    Examples
    --------
    >>> from firefleet.planning import straight_line
    >>> line = straight_line((0.0, 0.0), (3.0, 4.0))
    >>> line.coefficients, round(line.length_m, 12)
    ((0.0, 1.3333333333333333), 5.0)
    >>> line.sample(2)[:, :2].round(12).tolist()
    [[0.0, 0.0], [1.5, 2.0], [3.0, 4.0]]
    """
    (x0, y0), (x1, y1) = start, end
    if x0 == x1:
        raise InputError("a straight path y(x) cannot be vertical: start and end share x")
    slope = (y1 - y0) / (x1 - x0)
    return PolynomialPath((y0 - slope * x0, slope), x0, x1)
