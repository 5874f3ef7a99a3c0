"""Rigid alignment and the absolute trajectory error, against known motions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.estimation.alignment import absolute_trajectory_error, align_rigid_2d


def test_recovers_a_known_rigid_motion() -> None:
    rng = np.random.default_rng(0)
    src = rng.uniform(-50, 50, (200, 2))
    a = 2.5  # rad: beyond 90 degrees, where a naive fit flips
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    dst = src @ rot.T + [10.0, -3.0]
    r, t = align_rigid_2d(src, dst)
    np.testing.assert_allclose(r, rot, atol=1e-12)
    np.testing.assert_allclose(t, [10.0, -3.0], atol=1e-10)
    assert absolute_trajectory_error(src, dst) < 1e-10


def test_no_scale_is_fitted() -> None:
    # a circle of radius 11 against one of radius 10: by symmetry the best rigid motion is
    # the identity and every point stays 1 m off (a fit with scale would reach 0)
    a = np.linspace(0, 2 * math.pi, 360, endpoint=False)
    ref = 10.0 * np.stack([np.cos(a), np.sin(a)], axis=1)
    r, t = align_rigid_2d(1.1 * ref, ref)
    np.testing.assert_allclose(r, np.eye(2), atol=1e-12)
    np.testing.assert_allclose(t, [0.0, 0.0], atol=1e-12)
    assert absolute_trajectory_error(1.1 * ref, ref) == pytest.approx(1.0, rel=1e-12)
