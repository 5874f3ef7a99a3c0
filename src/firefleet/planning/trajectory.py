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
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from firefleet.errors import InputError
from firefleet.planning.paths import PolynomialPath

__all__ = ["Trajectory"]

FloatArray = NDArray[np.float64]


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
    """

    points: FloatArray
    period_s: float

    def __post_init__(self) -> None:
        if self.points.ndim != 3 or self.points.shape[1] < 2 or self.points.shape[2] != 3:
            raise InputError(f"points must have shape (N, n + 1, 3), got {self.points.shape}")
        if not (math.isfinite(self.period_s) and self.period_s > 0):
            raise InputError(f"period_s must be > 0, got {self.period_s}")

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
        points = np.stack([p.sample(pieces) for p in paths])
        return cls(points=points, period_s=duration_s / pieces)

    @property
    def pieces(self) -> int:
        """Number of pieces n of every path."""
        return int(self.points.shape[1] - 1)

    @property
    def duration_s(self) -> float:
        """When the last point falls due [s]."""
        return self.pieces * self.period_s

    def index(self, t_s: float) -> int:
        """Index of the desired point at time ``t_s`` (the same for every robot)."""
        return min(math.floor(t_s / self.period_s + 1e-9) + 1, self.pieces)

    def desired(self, t_s: float) -> FloatArray:
        """Desired points at ``t_s``, shape (N, 3): x [m], y [m], path heading [rad]."""
        return np.asarray(self.points[:, self.index(t_s)])
