"""Planar paths of line segments and circular arcs, parametrised by arc length.

A :class:`PlanarPath` is a chain of pieces, each a straight segment (curvature 0) or a
circular arc (curvature ``kappa`` != 0), joined with a continuous heading (C1): the
shape a polyline takes once its corners are rounded by arcs tangent to both sides.
Positions, headings and arc lengths are closed-form on every piece::

    theta(t) = theta_0 + kappa t
    x(t) = x_0 + (sin theta(t) - sin theta_0) / kappa      (x_0 + t cos theta_0 if kappa = 0)
    y(t) = y_0 - (cos theta(t) - cos theta_0) / kappa      (y_0 + t sin theta_0 if kappa = 0)

It offers what the path follower needs (the point and the path heading at an arc
length, :meth:`PlanarPath.pose_at`; the nearest arc length to a point,
:meth:`PlanarPath.project`) and :meth:`PlanarPath.sample` with the same meaning as
:meth:`firefleet.planning.PolynomialPath.sample`, so a
:class:`firefleet.planning.Trajectory` can be cut from it too.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet._typing import FloatArray
from firefleet.errors import InputError, as_float_array

__all__ = ["PlanarPath"]

_TINY = 1e-12


def _wrap(a: FloatArray) -> FloatArray:
    return np.asarray((a + np.pi) % (2.0 * np.pi) - np.pi)


@dataclass(frozen=True, eq=False)
class PlanarPath:
    """A C1 chain of segments and arcs.

    Attributes
    ----------
    start_m : ndarray, shape (P, 2)
        Where each piece starts [m].
    heading_rad : ndarray, shape (P,)
        The heading at each piece's start [rad].
    length_m_pieces : ndarray, shape (P,)
        Each piece's arc length [m] (> 0).
    curvature_1_m : ndarray, shape (P,)
        Each piece's curvature [1/m] (0 for a segment, > 0 turning left).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.planning.planar import PlanarPath
    >>> square = PlanarPath.from_polyline([[0, 0], [2, 0], [2, 2]], radius_m=0.5)
    >>> round(square.length_m, 6)  # 2 x (2 - 0.5) + a quarter circle of radius 0.5
    3.785398
    >>> square.pose_at([0.0, 1.5 + np.pi / 8]).round(4).tolist()  # start, middle of the arc
    [[0.0, 0.0, 0.0], [1.8536, 0.1464, 0.7854]]
    """

    start_m: FloatArray
    heading_rad: FloatArray
    length_m_pieces: FloatArray
    curvature_1_m: FloatArray

    def __post_init__(self) -> None:
        p = self.length_m_pieces.shape[0]
        if p == 0 or self.start_m.shape != (p, 2) or self.heading_rad.shape != (p,):
            raise InputError("a planar path needs P >= 1 pieces: start (P, 2), heading (P,)")
        if self.curvature_1_m.shape != (p,) or np.any(self.length_m_pieces <= 0.0):
            raise InputError("a planar path's pieces need curvature (P,) and lengths > 0")

    @classmethod
    def from_polyline(cls, points: ArrayLike, radius_m: ArrayLike = 0.0) -> PlanarPath:
        """A polyline with each interior corner rounded by a tangent arc.

        Parameters
        ----------
        points : array_like, shape (K, 2)
            Vertices [m], K >= 2; repeated vertices are dropped.
        radius_m : float or array_like, shape (K - 2,)
            Arc radius at each interior corner [m] (0: a sharp corner, the heading
            jumps there). A radius whose tangent points would pass the middle of either
            adjacent segment is reduced until they meet it.

        Returns
        -------
        PlanarPath
        """
        pts = as_float_array(points, "points", (None, 2))
        keep = np.ones(len(pts), dtype=bool)
        keep[1:] = np.hypot(*np.diff(pts, axis=0).T) > _TINY
        pts = pts[keep]
        if len(pts) < 2:
            raise InputError("a path needs at least two distinct points")
        radii = np.broadcast_to(np.asarray(radius_m, dtype=float), (max(len(pts) - 2, 0),))
        seg = np.diff(pts, axis=0)
        seg_len = np.hypot(seg[:, 0], seg[:, 1])
        seg_dir = np.arctan2(seg[:, 1], seg[:, 0])
        turn = _wrap(np.diff(seg_dir))  # (K - 2,)
        half_tan = np.tan(np.abs(turn) / 2.0)
        tangent = np.minimum(radii * half_tan, np.minimum(seg_len[:-1], seg_len[1:]) / 2.0)
        tangent = np.where(np.abs(turn) < 1e-9, 0.0, tangent)
        starts: list[FloatArray] = []
        headings: list[float] = []
        lengths: list[float] = []
        curvs: list[float] = []
        cursor = pts[0].copy()
        for i in range(len(seg)):
            u = np.array([math.cos(seg_dir[i]), math.sin(seg_dir[i])])
            end_cut = tangent[i] if i < len(seg) - 1 else 0.0
            line_end = pts[i + 1] - end_cut * u
            line_len = float(np.hypot(*(line_end - cursor)))
            if line_len > 1e-9:
                starts.append(cursor.copy())
                headings.append(float(seg_dir[i]))
                lengths.append(line_len)
                curvs.append(0.0)
            cursor = line_end
            if i < len(seg) - 1 and tangent[i] > 1e-9:
                radius = tangent[i] / half_tan[i]
                starts.append(cursor.copy())
                headings.append(float(seg_dir[i]))
                lengths.append(float(radius * abs(turn[i])))
                curvs.append(float(math.copysign(1.0 / radius, turn[i])))
                v = np.array([math.cos(seg_dir[i + 1]), math.sin(seg_dir[i + 1])])
                cursor = pts[i + 1] + tangent[i] * v
        return cls(np.array(starts), np.array(headings), np.array(lengths), np.array(curvs))

    @cached_property
    def _s0(self) -> FloatArray:
        return np.concatenate([[0.0], np.cumsum(self.length_m_pieces)])

    @property
    def length_m(self) -> float:
        """Total arc length [m]."""
        return float(self._s0[-1])

    def _piece_pose(self, k: NDArray[np.integer[Any]], t: FloatArray) -> FloatArray:
        th0 = self.heading_rad[k]
        kap = self.curvature_1_m[k]
        th = th0 + kap * t
        x0, y0 = self.start_m[k, 0], self.start_m[k, 1]
        straight = np.abs(kap) < _TINY
        safe = np.where(straight, 1.0, kap)
        x = np.where(straight, x0 + t * np.cos(th0), x0 + (np.sin(th) - np.sin(th0)) / safe)
        y = np.where(straight, y0 + t * np.sin(th0), y0 - (np.cos(th) - np.cos(th0)) / safe)
        return np.stack([x, y, _wrap(th)], axis=-1)

    def pose_at(self, s_m: ArrayLike) -> FloatArray:
        """Point and heading at arc lengths ``s_m`` (clamped to the path), shape (..., 3):
        x [m], y [m], heading [rad] in [-pi, pi)."""
        if isinstance(s_m, float) and math.isfinite(s_m):  # one arc length: no arrays
            return self._pose_at_one(s_m)
        s = np.clip(np.asarray(s_m, dtype=float), 0.0, self.length_m)
        k = np.clip(
            np.searchsorted(self._s0, s, side="right") - 1, 0, len(self.length_m_pieces) - 1
        )
        return self._piece_pose(k, s - self._s0[k])

    @cached_property
    def _s0_list(self) -> list[float]:
        return [float(v) for v in self._s0]

    def _pose_at_one(self, s_m: float) -> FloatArray:
        """:meth:`pose_at` of one finite arc length, shape (3,): the same operations on
        the same float64 scalars as the array form (the navigation's lookahead point,
        once per robot and control period), without its arrays."""
        s0 = self._s0_list
        s = min(max(s_m, 0.0), s0[-1])
        k = min(max(bisect.bisect_right(s0, s) - 1, 0), len(s0) - 2)
        t = np.float64(s) - self._s0[k]
        th0 = self.heading_rad[k]
        kap = self.curvature_1_m[k]
        x0, y0 = self.start_m[k, 0], self.start_m[k, 1]
        if abs(kap) < _TINY:
            x = x0 + t * np.cos(th0)
            y = y0 + t * np.sin(th0)
        else:
            th = th0 + kap * t
            x = x0 + (np.sin(th) - np.sin(th0)) / kap
            y = y0 - (np.cos(th) - np.cos(th0)) / kap
        th = th0 + kap * t
        return np.array([x, y, (th + np.pi) % (2.0 * np.pi) - np.pi])

    def curvature_at(self, s_m: ArrayLike) -> FloatArray:
        """Curvature at arc lengths ``s_m`` [1/m] (the piece's on its left end)."""
        s = np.clip(np.asarray(s_m, dtype=float), 0.0, self.length_m)
        k = np.clip(
            np.searchsorted(self._s0, s, side="right") - 1, 0, len(self.length_m_pieces) - 1
        )
        return np.asarray(self.curvature_1_m[k])

    def sample(self, n: int) -> FloatArray:
        """``n + 1`` points equally spaced in arc length, start to end, shape (n + 1, 3)."""
        if n < 1:
            raise InputError(f"pieces must be >= 1, got {n}")
        return self.pose_at(np.linspace(0.0, self.length_m, n + 1))

    def project(self, points: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """The arc length of the nearest path point to each point, and the distance.

        Parameters
        ----------
        points : array_like, shape (M, 2)
            Points [m].

        Returns
        -------
        s_m : ndarray, shape (M,)
            Arc length of the nearest point of the path [m].
        distance_m : ndarray, shape (M,)
            Distance to it [m].

        Examples
        --------
        >>> path = PlanarPath.from_polyline([[0, 0], [4, 0]])
        >>> s, d = path.project([[1.0, 0.5], [5.0, 0.0]])
        >>> s.tolist(), d.tolist()
        ([1.0, 4.0], [0.5, 1.0])
        """
        p = as_float_array(points, "points", (None, 2))
        a = self.start_m[None]  # (1, P, 2)
        th0 = self.heading_rad[None]
        kap = self.curvature_1_m[None]
        length = self.length_m_pieces[None]
        q = p[:, None, :] - a  # (M, P, 2)
        straight = np.abs(kap) < _TINY
        t_line = np.clip(q[..., 0] * np.cos(th0) + q[..., 1] * np.sin(th0), 0.0, length)
        safe = np.where(straight, 1.0, kap)
        # arc: centre at a + n / kappa, n the left normal; the angle swept to the point
        cx = -np.sin(th0) / safe
        cy = np.cos(th0) / safe
        ang0 = np.arctan2(-cy, -cx)
        angp = np.arctan2(q[..., 1] - cy, q[..., 0] - cx)
        sweep = np.mod(np.sign(safe) * (angp - ang0), 2.0 * np.pi)
        t_arc = sweep / np.abs(safe)
        past = t_arc > length
        # past the end of the arc: the nearer end (its angular distance decides)
        back = 2.0 * np.pi / np.abs(safe) - t_arc
        t_arc = np.where(past, np.where(t_arc - length < back, length, 0.0), t_arc)
        t = np.where(straight, t_line, t_arc)
        k = np.broadcast_to(np.arange(length.shape[1])[None], t.shape)
        pose = self._piece_pose(k, t)
        d = np.hypot(pose[..., 0] - p[:, None, 0], pose[..., 1] - p[:, None, 1])
        best = np.argmin(d, axis=1)
        rows = np.arange(p.shape[0])
        s = self._s0[best] + t[rows, best]
        return np.asarray(s), np.asarray(d[rows, best])
