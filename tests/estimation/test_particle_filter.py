"""Motion and measurement models, resampling, and Monte Carlo localisation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.estimation.particle_filter import (
    MclParams,
    MclResult,
    OdometryNoise,
    bearing_log_likelihood,
    compose,
    gaussian_particles,
    low_variance_resample,
    odometry_covariance,
    predict_range_bearing,
    range_bearing_jacobians,
    range_bearing_log_likelihood,
    relative_pose,
    run_mcl,
    sample_odometry,
    uniform_particles,
)
from firefleet.models.kinematics import RobotGeometry
from firefleet.sim.world import DriveResult


def test_compose_hand_case_and_inverse() -> None:
    # from (1, 2) facing +y, 3 m ahead and 1 m to the left is (0, 5)
    out = compose(np.array([1.0, 2.0, math.pi / 2]), np.array([3.0, 1.0, 0.5]))
    np.testing.assert_allclose(out, [0.0, 5.0, math.pi / 2 + 0.5], atol=1e-12)
    rng = np.random.default_rng(0)
    a = rng.uniform(-5, 5, (50, 3))
    b = rng.uniform(-5, 5, (50, 3))
    b[:, 2] = (b[:, 2] + math.pi) % (2 * math.pi) - math.pi
    np.testing.assert_allclose(compose(a, relative_pose(a, b)), b, atol=1e-12)


def test_odometry_covariance_straight_line_by_hand() -> None:
    # 1 m straight: s_R = s_L = 1, J = [[.5, .5], [1/(2L), -1/(2L)] * 1, [1/L, -1/L]]
    k2, L = 1e-4, 0.2
    cov = odometry_covariance(
        np.array([[1.0, 0.0, 0.0]]),
        RobotGeometry(axle_length_m=L),
        OdometryNoise(wheel_variance_m=k2, floor_sigma_xy_m=0.0, floor_sigma_theta_rad=0.0),
    )[0]
    expected = k2 * np.array(
        [[0.5, 0.0, 0.0], [0.0, 2 / (4 * L * L), 2 / (2 * L * L)], [0.0, 2 / (2 * L * L), 2 / L**2]]
    )
    np.testing.assert_allclose(cov, expected, rtol=1e-12, atol=1e-18)


def test_sample_odometry_has_the_given_covariance() -> None:
    cov = np.array([[4e-4, 1e-4, 0.0], [1e-4, 2e-4, 5e-5], [0.0, 5e-5, 1e-4]])
    x = sample_odometry(
        np.zeros((40_000, 3)), np.array([1.0, 0.0, 0.0]), cov, np.random.default_rng(3)
    )
    # from the origin the composed pose is delta + noise itself
    np.testing.assert_allclose(x.mean(axis=0), [1.0, 0.0, 0.0], atol=4e-4)  # > 5 sigma/sqrt(N)
    # sample covariance: relative sd of a variance is sqrt(2/N) = 0.7 %; 5 % covers 7 sd
    np.testing.assert_allclose(np.cov(x.T), cov, rtol=0.05, atol=5e-6)


def test_range_bearing_hand_case() -> None:
    z = predict_range_bearing(np.array([1.0, 1.0, math.pi / 2]), np.array([4.0, 5.0]))
    np.testing.assert_allclose(z, [5.0, math.atan2(4.0, 3.0) - math.pi / 2], atol=1e-12)


def test_jacobians_match_central_differences() -> None:
    rng = np.random.default_rng(5)
    poses = rng.uniform(-3, 3, (20, 3))
    lms = rng.uniform(-3, 3, (20, 2)) + 8.0
    h_x, h_m = range_bearing_jacobians(poses, lms)
    eps = 1e-6
    for i in range(3):
        d = np.zeros(3)
        d[i] = eps
        num = (predict_range_bearing(poses + d, lms) - predict_range_bearing(poses - d, lms)) / (
            2 * eps
        )
        np.testing.assert_allclose(h_x[..., i], num, atol=1e-8)  # O(eps^2) truncation
    for i in range(2):
        d = np.zeros(2)
        d[i] = eps
        num = (predict_range_bearing(poses, lms + d) - predict_range_bearing(poses, lms - d)) / (
            2 * eps
        )
        np.testing.assert_allclose(h_m[..., i], num, atol=1e-8)


def test_log_likelihoods_by_hand() -> None:
    cov = np.diag([0.04, 0.01])
    got = range_bearing_log_likelihood(np.array([5.2, 0.1]), np.array([5.0, 0.0]), cov)
    expected = -0.5 * (0.2**2 / 0.04 + 0.1**2 / 0.01) - math.log(2 * math.pi * math.sqrt(4e-4))
    assert got == pytest.approx(expected, rel=1e-12)
    # bearing wraps: 3.1 and -3.1 rad are 0.083 rad apart, not 6.2
    got = bearing_log_likelihood(3.1, -3.1, 0.1)
    e = 2 * math.pi - 6.2
    assert got == pytest.approx(-0.5 * (e / 0.1) ** 2 - math.log(0.1 * math.sqrt(2 * math.pi)))


def test_low_variance_resampling_keeps_the_weights() -> None:
    rng = np.random.default_rng(11)
    w = rng.random(1000) ** 3
    w /= w.sum()
    idx = low_variance_resample(w, rng)
    counts = np.bincount(idx, minlength=w.size)
    # systematic resampling copies particle i floor(P w_i) or ceil(P w_i) times
    assert np.all(counts >= np.floor(1000 * w) - 1e-9)
    assert np.all(counts <= np.ceil(1000 * w) + 1e-9)
    # over repetitions, the expected number of copies is exactly P w_i
    total = np.zeros(w.size)
    for _ in range(400):
        total += np.bincount(low_variance_resample(w, rng), minlength=w.size)
    # each count varies by at most one copy, so its mean's error is below 1/sqrt(400) * 0.5
    np.testing.assert_allclose(total / 400, 1000 * w, atol=0.1)


def _mcl(
    drive: DriveResult,
    particles: np.ndarray,
    rng: np.random.Generator,
    params: MclParams | None = None,
) -> MclResult:
    """MCL over the drive's log with the true landmark map."""
    log = drive.log
    assert log.truth_landmark_ids is not None
    assert log.truth_landmarks is not None
    lm = {
        int(i): (float(x), float(y))
        for i, (x, y) in zip(log.truth_landmark_ids, log.truth_landmarks, strict=True)
    }
    return run_mcl(
        log.odometry,
        log.odometry_cov,
        log.obs_step,
        log.obs_landmark,
        log.obs_z,
        log.obs_cov,
        lm,
        particles,
        rng,
        params=params,
    )


def test_mcl_tracking_error_below_20_cm(drive: DriveResult) -> None:
    start = gaussian_particles(
        [0, 0, 0], np.diag([0.01, 0.01, 1e-3]), 500, np.random.default_rng(0)
    )
    res = _mcl(drive, start, np.random.default_rng(0))
    err = np.linalg.norm(res.mean[:, :2] - drive.truth[:, :2], axis=1)
    assert np.sqrt(np.mean(err**2)) <= 0.2  # the bound
    # the reported covariance is honest: few errors beyond 3 sigma of the spread
    sd = np.sqrt(res.cov[:, 0, 0] + res.cov[:, 1, 1])
    assert np.mean(err > 3 * sd + 0.05) < 0.05


def test_global_localisation_converges_within_30_s(drive: DriveResult) -> None:
    bounds = (-20.0, 20.0, -5.0, 27.0)  # the whole map: 40 m x 32 m, any heading
    start = uniform_particles(bounds, 20_000, np.random.default_rng(0))
    res = _mcl(drive, start, np.random.default_rng(0))
    err = np.linalg.norm(res.mean[:, :2] - drive.truth[:, :2], axis=1)
    assert err[0] > 0.5  # it starts lost
    late = np.flatnonzero(err > 0.5)
    converged = 0 if late.size == 0 else int(late[-1]) + 1
    assert drive.t_s[converged] <= 30.0  # the bound: within 0.5 m for good by 30 s
    assert np.sqrt(np.mean(err[converged:] ** 2)) <= 0.2  # then tracks within 20 cm


def test_mcl_bearing_only_tracks(drive: DriveResult) -> None:
    start = gaussian_particles(
        [0, 0, 0], np.diag([0.01, 0.01, 1e-3]), 500, np.random.default_rng(0)
    )
    res = _mcl(drive, start, np.random.default_rng(2), params=MclParams(bearing_only=True))
    err = np.linalg.norm(res.mean[:, :2] - drive.truth[:, :2], axis=1)
    assert np.sqrt(np.mean(err**2)) <= 0.2  # bearings of ~3 landmarks at a time fix x, y


def test_mcl_same_seed_same_run(drive: DriveResult) -> None:
    runs = [
        _mcl(
            drive,
            gaussian_particles([0, 0, 0], np.eye(3) * 1e-3, 200, np.random.default_rng(4)),
            np.random.default_rng(4),
        ).mean
        for _ in range(2)
    ]
    np.testing.assert_array_equal(runs[0], runs[1])


def test_bad_inputs_raise_input_error() -> None:
    with pytest.raises(InputError, match="bounds"):
        uniform_particles([1, 0, 0, 1], 10, np.random.default_rng(0))
    with pytest.raises(InputError, match="odometry must have shape"):
        run_mcl(
            np.zeros((3, 2)),
            np.zeros((3, 3, 3)),
            [],
            [],
            np.zeros((0, 2)),
            np.zeros((0, 2, 2)),
            {},
            np.zeros((5, 3)),
            np.random.default_rng(0),
        )
    with pytest.raises(InputError, match="resample_threshold"):
        MclParams(resample_threshold=0.0)
