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


def test_past_the_end_the_point_moves_on_along_the_end_tangent_at_the_same_pace() -> None:
    # a quarter circle's worth of path ending at 45 degrees: y = x on [0, 2]
    from firefleet.planning.paths import PolynomialPath

    diag = PolynomialPath(coefficients=(0.0, 1.0), x_start_m=0.0, x_end_m=2.0)
    traj = Trajectory.from_paths([diag], pieces=4, duration_s=8.0)
    assert traj.spacing_m is not None
    step = float(traj.spacing_m[0])
    assert step == pytest.approx(2.0 * np.sqrt(2.0) / 4, abs=1e-12)  # arc length / pieces
    assert traj.release_index(7.0) == 4
    assert traj.index(7.0) == 4
    np.testing.assert_allclose(traj.desired(7.0)[0], [2.0, 2.0, np.pi / 4], atol=1e-12)
    # 8 s: index 5, one spacing beyond the end; 11 s: index 6, two
    assert traj.release_index(8.0) == 5
    assert traj.index(8.0) == 4
    for t, beyond in ((8.0, 1), (11.0, 2)):
        along = 2.0 + beyond * step / np.sqrt(2.0)
        np.testing.assert_allclose(traj.desired(t)[0], [along, along, np.pi / 4], atol=1e-12)
    # without a spacing, the last chord sets the pace (a straight path: the same)
    bare = Trajectory(points=traj.points, period_s=traj.period_s)
    np.testing.assert_allclose(bare.desired(11.0), traj.desired(11.0), atol=1e-12)
    with pytest.raises(InputError, match="spacing_m"):
        Trajectory(points=traj.points, period_s=1.0, spacing_m=np.ones(2))
