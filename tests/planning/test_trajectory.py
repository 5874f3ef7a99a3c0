"""The trajectory planner: equal pieces, a common release schedule."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.planning.paths import straight_line
from firefleet.planning.trajectory import Trajectory


def test_points_fall_due_together_and_longer_paths_get_sparser_points() -> None:
    short = straight_line((0.0, 0.0), (10.0, 0.0))
    long = straight_line((0.0, 1.0), (20.0, 1.0))
    traj = Trajectory.from_paths([short, long], pieces=40, duration_s=60.0)
    assert traj.points.shape == (2, 41, 3)
    assert traj.period_s == 1.5
    assert traj.duration_s == 60.0
    gaps = np.diff(traj.points[:, :, 0], axis=1)
    np.testing.assert_allclose(gaps[0], 0.25, atol=1e-12)
    np.testing.assert_allclose(gaps[1], 0.5, atol=1e-12)
    # the schedule: point j falls due at j * period; the next one is desired
    assert traj.index(0.0) == 1
    assert traj.index(1.4999) == 1
    assert traj.index(1.5) == 2
    assert traj.index(58.5) == 40  # the last point is desired from (n - 1) * period on
    assert traj.index(1e6) == 40
    np.testing.assert_allclose(traj.desired(3.0)[:, :2], [[0.75, 0.0], [1.5, 1.0]], atol=1e-12)


def test_bad_trajectories() -> None:
    line = straight_line((0.0, 0.0), (1.0, 0.0))
    with pytest.raises(InputError, match="at least one path"):
        Trajectory.from_paths([], pieces=5, duration_s=1.0)
    with pytest.raises(InputError, match="duration_s must be > 0"):
        Trajectory.from_paths([line], pieces=5, duration_s=0.0)
    with pytest.raises(InputError, match="shape"):
        Trajectory(points=np.zeros((2, 3)), period_s=1.0)
