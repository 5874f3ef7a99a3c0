"""PlanarPath.pose_at of one arc length (a float) equals its array form bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.planning.planar import PlanarPath


@pytest.mark.parametrize("seed", range(5))
def test_pose_at_one_arc_length_equals_the_array_form(seed: int) -> None:
    rng = np.random.default_rng(seed)
    pts = np.cumsum(rng.uniform(-3.0, 3.0, (8, 2)), axis=0)
    path = PlanarPath.from_polyline(pts, radius_m=float(rng.uniform(0.1, 1.0)))
    ends = np.concatenate([[0.0], np.cumsum(path.length_m_pieces)])
    s_all = np.concatenate(
        [rng.uniform(-1.0, path.length_m + 1.0, 400), ends, [-0.0, path.length_m + 5.0]]
    )
    arcs = np.abs(path.curvature_1_m) > 0
    assert arcs.any()  # both kinds of piece are exercised
    assert (~arcs).any()
    for s in s_all:
        one = path.pose_at(float(s))
        ref = path.pose_at(np.asarray(s))  # the array form (a 0-d array)
        assert one.shape == ref.shape == (3,)
        np.testing.assert_array_equal(one, ref)
        np.testing.assert_array_equal(path.pose_at(np.float64(s)), ref)
    np.testing.assert_array_equal(path.pose_at(float("nan")), path.pose_at(np.asarray(np.nan)))
