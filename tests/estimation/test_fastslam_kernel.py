"""The compiled landmark update (one definition for both associations) = NumPy reference.

The reference is the textbook EKF of a range-bearing landmark (Thrun et al. 2005,
Table 13.1) written with ``np.linalg``: ``Q = H S H^T + R``, ``K = S H^T Q^-1``,
``mu' = mu + K nu``, ``S' = S - K Q K^T``, weight ``log N(nu; 0, Q)``; initialisation
``m = x + r (cos, sin)(theta + phi)``, ``S = H^-1 R H^-T``.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

from firefleet.estimation.fastslam._kernel import (
    _init_landmark,
    _landmark_update,
    update_landmarks,
)

FloatArray = NDArray[np.float64]

coord = st.floats(-100.0, 100.0)
angle = st.floats(-math.pi, math.pi)
rng_m = st.floats(0.5, 50.0)
sd = st.floats(0.01, 2.0)
corr = st.floats(-0.9, 0.9)


def cov2(s0: float, s1: float, c: float) -> FloatArray:
    """A 2 x 2 covariance from two standard deviations and a correlation."""
    return np.array([[s0 * s0, c * s0 * s1], [c * s0 * s1, s1 * s1]])


def wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def jacobian(pose: FloatArray, m: FloatArray) -> FloatArray:
    """d(range, bearing)/d(landmark) at ``pose``."""
    dx, dy = m - pose[:2]
    q = dx * dx + dy * dy
    d = math.sqrt(q)
    return np.array([[dx / d, dy / d], [-dy / q, dx / q]])


def reference_update(
    pose: FloatArray, z: FloatArray, r: FloatArray, mu: FloatArray, s: FloatArray
) -> tuple[FloatArray, FloatArray, float]:
    dx, dy = mu - pose[:2]
    z_hat = np.array([math.hypot(dx, dy), wrap(math.atan2(dy, dx) - pose[2])])
    nu = np.array([z[0] - z_hat[0], wrap(z[1] - z_hat[1])])
    h = jacobian(pose, mu)
    q = h @ s @ h.T + r
    k = s @ h.T @ np.linalg.inv(q)
    s_new = s - k @ q @ k.T
    log_lik = float(
        -0.5 * nu @ np.linalg.solve(q, nu)
        - 0.5 * math.log(np.linalg.det(q))
        - math.log(2 * math.pi)
    )
    return mu + k @ nu, 0.5 * (s_new + s_new.T), log_lik


@settings(max_examples=200, deadline=None)
@given(
    x=coord, y=coord, th=angle, rho=rng_m, phi=angle, ex=sd, ey=sd,
    s0=sd, s1=sd, c=corr, r0=st.floats(0.01, 1.0), r1=st.floats(0.001, 0.2), rc=corr,
    zr=st.floats(-1.0, 1.0), zb=st.floats(-0.3, 0.3),
)  # fmt: skip
def test_compiled_landmark_update_equals_the_numpy_ekf(
    x: float, y: float, th: float, rho: float, phi: float, ex: float, ey: float,
    s0: float, s1: float, c: float, r0: float, r1: float, rc: float, zr: float, zb: float,
) -> None:  # fmt: skip
    pose = np.array([x, y, th])
    # a landmark at range rho, bearing phi, its estimate ex, ey off; the measurement near it
    mu = pose[:2] + rho * np.array([math.cos(th + phi), math.sin(th + phi)]) + [ex, ey]
    s, r = cov2(s0, s1, c), cov2(r0, r1, rc)
    z = np.array([rho + zr, wrap(phi + zb)])
    want_mu, want_s, want_w = reference_update(pose, z, r, mu, s)
    got_mu, got_s = mu.copy(), s.copy()
    got_w = _landmark_update(x, y, th, z[0], z[1], r, got_mu, got_s)
    scale = float(np.abs(s).max() + np.abs(r).max())
    np.testing.assert_allclose(got_mu, want_mu, rtol=1e-9, atol=1e-9 * (1 + rho))
    np.testing.assert_allclose(got_s, want_s, rtol=1e-7, atol=1e-9 * scale)
    assert math.isclose(got_w, want_w, rel_tol=1e-8, abs_tol=1e-8)


@settings(max_examples=200, deadline=None)
@given(x=coord, y=coord, th=angle, rho=rng_m, phi=angle, r0=sd, r1=st.floats(0.001, 0.2), rc=corr)
def test_compiled_landmark_initialisation_equals_the_numpy_inverse(
    x: float, y: float, th: float, rho: float, phi: float, r0: float, r1: float, rc: float
) -> None:
    pose = np.array([x, y, th])
    r = cov2(r0, r1, rc)
    want_mu = pose[:2] + rho * np.array([math.cos(th + phi), math.sin(th + phi)])
    h_inv = np.linalg.inv(jacobian(pose, want_mu))
    want_s = h_inv @ r @ h_inv.T
    got_mu, got_s = np.zeros(2), np.zeros((2, 2))
    _init_landmark(x, y, th, rho, phi, r, got_mu, got_s)
    np.testing.assert_allclose(got_mu, want_mu, rtol=1e-12, atol=1e-12 * (1 + rho))
    np.testing.assert_allclose(got_s, want_s, rtol=1e-8, atol=1e-12 * float(np.abs(want_s).max()))


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_p=st.integers(1, 30))
def test_batched_update_is_the_scalar_update_per_particle(seed: int, n_p: int) -> None:
    # unknown association: each particle updates its own slot, initialises it, or skips
    rng = np.random.default_rng(seed)
    c = 4
    poses = rng.normal(0.0, [5.0, 5.0, 1.0], (n_p, 3))
    mu = poses[:, None, :2] + rng.uniform(2.0, 10.0, (n_p, c, 2))
    a = rng.normal(0.0, 0.3, (n_p, c, 2, 2))
    sigma = a @ np.swapaxes(a, -1, -2) + 0.01 * np.eye(2)
    slots = rng.integers(-1, c, n_p)
    new = rng.random(n_p) < 0.3
    z = np.array([rng.uniform(1.0, 10.0), rng.uniform(-1.0, 1.0)])
    r = cov2(0.1, 0.02, 0.1)
    got_mu, got_s = mu.copy(), sigma.copy()
    update_landmarks(poses, got_mu, got_s, slots, new, z, r)
    want_mu, want_s = mu.copy(), sigma.copy()
    for i in range(n_p):
        j = slots[i]
        if j < 0:
            continue
        if new[i]:
            px, py, pth = poses[i]
            _init_landmark(px, py, pth, z[0], z[1], r, want_mu[i, j], want_s[i, j])
        else:
            want_mu[i, j], want_s[i, j], _ = reference_update(poses[i], z, r, mu[i, j], sigma[i, j])
    np.testing.assert_allclose(got_mu, want_mu, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(got_s, want_s, rtol=1e-7, atol=1e-10)
    untouched = np.ones((n_p, c), dtype=bool)
    untouched[np.arange(n_p)[slots >= 0], slots[slots >= 0]] = False
    np.testing.assert_array_equal(got_mu[untouched], mu[untouched])
