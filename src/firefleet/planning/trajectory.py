"""The trajectory planner: every robot's path cut into the same number of pieces, with
the next desired point released periodically (section 2.6.3 of the deliverable).

"The trajectory planner has pre-defined paths, it divides each path into same number of
pieces regardless of their length and shape. [...] The points are sent to the robot
periodically and since the number of points are always the same hence the robots will
always reach their destinations at the same time."

Point ``j`` (``j = 0 .. n``; 0 the start, ``n`` the end) falls due at ``j * period_s``.
At time ``t`` a robot's desired point is the next one not yet due,
``j(t) = min(floor(t / period_s) + 1, n)``: the same index for every robot, which is the
x-coordination of section 2.6.2.6. The last point is the desired one from
``(n - 1) * period_s`` on and falls due at ``n * period_s = duration_s``.

Past the end the schedule goes on: the release index ``floor(t / period_s) + 1`` keeps
growing, and the desired point moves on along the path's end tangent at the same pace
(one piece's arc length per period), so a robot still short of its end keeps a point
ahead of it instead of one that stops and pulls it in at ever lower speed. This
extension is written here once; the simulator's compiled loop computes the same
points.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.planning.paths import PolynomialPath

__all__ = ["Trajectory"]


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Desired points of a team, released on a common schedule.

    Attributes
    ----------
    points : ndarray, shape (N, n + 1, 3)
        Each robot's points: x [m], y [m], path heading [rad]; equally spaced in arc
        length along its own path.
    period_s : float
        Time between two releases [s].
    spacing_m : ndarray, shape (N,), optional
        Each robot's distance between two points along its path [m] (its path's arc
        length / n): the pace of the extension past the end. None: the length of the
        last piece's chord.

    Examples
    --------
    >>> from firefleet.planning import Trajectory, straight_line
    >>> line = straight_line((0.0, 0.0), (4.0, 0.0))
    >>> traj = Trajectory.from_paths([line], pieces=4, duration_s=8.0)
    >>> traj.points.shape, traj.period_s, traj.duration_s
    ((1, 5, 3), 2.0, 8.0)
    >>> traj.index(3.0), traj.desired(3.0).round(12).tolist()
    (2, [[2.0, 0.0, 0.0]])
    """

    points: FloatArray
    period_s: float
    spacing_m: FloatArray | None = None

    def __post_init__(self) -> None:
        if self.points.ndim != 3 or self.points.shape[1] < 2 or self.points.shape[2] != 3:
            raise InputError(f"points must have shape (N, n + 1, 3), got {self.points.shape}")
        if not (math.isfinite(self.period_s) and self.period_s > 0):
            raise InputError(f"period_s must be > 0, got {self.period_s}")
        if self.spacing_m is not None and self.spacing_m.shape != self.points.shape[:1]:
            raise InputError(
                f"spacing_m must have shape ({self.points.shape[0]},), got {self.spacing_m.shape}"
            )

    @classmethod
    def from_paths(
        cls, paths: Sequence[PolynomialPath], *, pieces: int, duration_s: float
    ) -> Trajectory:
        """Cut every path into ``pieces`` and release them so the last falls due at
        ``duration_s`` [s]."""
        if not paths:
            raise InputError("a trajectory needs at least one path")
        if not (math.isfinite(duration_s) and duration_s > 0):
            raise InputError(f"duration_s must be > 0, got {duration_s}")
        # a path shared by several robots (the same path three times, a large team on a
        # few routes) is sampled once: the points are the same bits either way
        samples = {path: path.sample(pieces) for path in dict.fromkeys(paths)}
        points = np.stack([samples[p] for p in paths])
        spacing = np.array([p.length_m / pieces for p in paths])
        return cls(points=points, period_s=duration_s / pieces, spacing_m=spacing)

    @property
    def pieces(self) -> int:
        """Number of pieces n of every path."""
        return int(self.points.shape[1] - 1)

    @property
    def duration_s(self) -> float:
        """When the last point falls due [s]."""
        return self.pieces * self.period_s

    @property
    def end_spacing_m(self) -> FloatArray:
        """Distance between two points past the end, shape (N,) [m] (``spacing_m``)."""
        if self.spacing_m is not None:
            return self.spacing_m
        last = self.points[:, -1, :2] - self.points[:, -2, :2]
        return np.asarray(np.hypot(last[:, 0], last[:, 1]))

    def release_index(self, t_s: float) -> int:
        """Index of the point released next at ``t_s`` (the same for every robot).

        ``floor(t_s / period_s) + 1`` (with 1e-9 of slack for the float quotient);
        greater than ``pieces`` past the end.
        """
        return math.floor(t_s / self.period_s + 1e-9) + 1

    def index(self, t_s: float) -> int:
        """Index of the desired point among the path's points at ``t_s`` (at most n)."""
        return min(self.release_index(t_s), self.pieces)

    def desired(self, t_s: float) -> FloatArray:
        """Desired points at ``t_s``, shape (N, 3): x [m], y [m], path heading [rad].

        Point ``release_index(t_s)``; past the end (index ``j > n``) the end point moved
        on ``(j - n) * spacing`` along the end heading.

        Examples
        --------
        >>> from firefleet.planning.paths import straight_line
        >>> line = straight_line((0.0, 0.0), (4.0, 0.0))
        >>> traj = Trajectory.from_paths([line], pieces=4, duration_s=4.0)
        >>> traj.desired(0.5)[0, :2].round(12).tolist()  # point 1 is next
        [1.0, 0.0]
        >>> traj.desired(5.0)[0, :2].round(12).tolist()  # two periods past the end
        [6.0, 0.0]
        """
        j = self.release_index(t_s)
        n = self.pieces
        if j <= n:
            return np.asarray(self.points[:, j])
        end = self.points[:, n]
        beyond = (j - n) * self.end_spacing_m
        heading = end[:, 2]
        return np.stack(
            [end[:, 0] + beyond * np.cos(heading), end[:, 1] + beyond * np.sin(heading), heading],
            axis=1,
        )
