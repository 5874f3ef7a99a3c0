"""The simulated drive: the loop, the ground truth, the sensor's view."""

from __future__ import annotations

import math

import numpy as np

from firefleet.estimation.particle_filter import predict_range_bearing
from firefleet.sim.world import DriveParams, loop_path, simulate_drive


def test_loop_is_100_m_and_closed() -> None:
    prm = DriveParams()
    assert prm.loop_length_m == 100.0 or abs(prm.loop_length_m - 100.0) < 0.01
    path = loop_path(prm, spacing_m=0.01)
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    assert seg.max() < 0.0101  # continuous: no jump between pieces
    np.testing.assert_allclose(path[0], [0.0, 0.0], atol=1e-12)
    assert np.linalg.norm(path[-1] - path[0]) < 0.011


def test_drive_follows_the_loop_and_sees_only_in_view() -> None:
    d = simulate_drive(np.random.default_rng(3))
    log = d.log
    path = loop_path(DriveParams(), spacing_m=0.02)
    dist = np.min(np.linalg.norm(d.truth[:, None, :2] - path[None], axis=2), axis=1)
    assert dist.max() < 0.15  # pure pursuit keeps the robot on the loop
    travelled = np.sum(np.linalg.norm(np.diff(d.truth[:, :2], axis=0), axis=1))
    assert abs(travelled - 100.0) < 1.0  # one lap at 0.5 m/s
    assert np.linalg.norm(d.truth[-1, :2]) < 0.5  # back at the start
    real = log.obs_landmark >= 0
    z_true = predict_range_bearing(d.truth[log.obs_step[real]], d.landmarks[log.obs_landmark[real]])
    assert np.all(np.abs(z_true[:, 1]) <= math.radians(51.0) / 2)  # the Lepton's view
    assert np.all(z_true[:, 0] <= DriveParams().sensor.max_range_m)
    err = log.obs_z[real] - z_true
    err[:, 1] = (err[:, 1] + math.pi) % (2 * math.pi) - math.pi
    # noise as configured (0.1 m, 0.5 deg), sample sd within 10 % (thousands of samples)
    np.testing.assert_allclose(err.std(axis=0), [0.1, math.radians(0.5)], rtol=0.1)
    # the odometry in the log composes to the encoders' dead reckoning
    np.testing.assert_allclose(log.dead_reckoning(), d.odometry_pose, atol=1e-9)


def test_same_seed_same_drive() -> None:
    prm = DriveParams(laps=0.1)
    a = simulate_drive(np.random.default_rng(9), params=prm)
    b = simulate_drive(np.random.default_rng(9), params=prm)
    np.testing.assert_array_equal(a.truth, b.truth)
    np.testing.assert_array_equal(a.log.obs_z, b.log.obs_z)
