"""FastSLAM's per-particle updates as compiled (numba) loops: the one definition of each.

``_landmark_update`` (the landmark EKF update and its weight) and ``_init_landmark``
(a landmark from its first observation) are written once here and used by both
associations: given association through :func:`update_known_v1` and
:func:`update_known_v2`, unknown association through :func:`update_landmarks` (the
association itself, with its gates, stays NumPy over particles). A step loops over its
few observations (Victoria Park: 0 to 5, the PythonRobotics scenario: 8), and each NumPy
call on a (P, 2, 2) stack pays ~1-5 us of overhead for ~0.1 us of arithmetic per
particle: these kernels do the arithmetic per particle and observation in one compiled
call, with no allocation in the loops (2 x 2 and 3 x 3 matrices in scalars). The random
draws stay in NumPy (the caller passes them in), so a seed gives the same run as before.
``tests/estimation/test_fastslam_kernel.py`` checks them against a NumPy reference.

Equations (Thrun et al. 2005, Tables 13.1 and 13.3): landmark initialisation
``m = x + r (cos, sin)(theta + phi)``, ``S = H_m^-1 R H_m^-T``; EKF update
``Q = H_m S H_m^T + R``, ``K = S H_m^T Q^-1``; weight ``N(nu; 0, Q)`` (1.0) or
``N(nu; 0, H_x Sigma_x H_x^T + Q)`` (2.0) with the proposal's information update
``Sigma_x' = (H_x^T Q^-1 H_x + Sigma_x^-1)^-1``.

All functions here are compiled together (numba's cache does not track edits to jitted
functions of other modules).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.models.kinematics import wrap_angle_one

_LOG_2PI = math.log(2.0 * math.pi)


_wrap = wrap_angle_one
"""Angle wrapped to [-pi, pi): the one compiled definition, models.kinematics's."""


@numba.njit(cache=True)
def _init_landmark(
    px: float,
    py: float,
    pth: float,
    rng_: float,
    brg: float,
    r: FloatArray,
    out_mu: FloatArray,
    out_s: FloatArray,
) -> None:  # pragma: no cover (compiled)
    """Landmark mean and covariance from its first observation (writes out_mu, out_s)."""
    ang = pth + brg
    mx = px + rng_ * math.cos(ang)
    my = py + rng_ * math.sin(ang)
    dx, dy = mx - px, my - py
    q = dx * dx + dy * dy
    d = math.sqrt(q)
    a, b, c, e = dx / d, dy / d, -dy / q, dx / q  # H_m = [[a, b], [c, e]]
    det = a * e - b * c
    ia, ib, ic, ie = e / det, -b / det, -c / det, a / det
    # S = Hi R Hi^T
    t00 = ia * r[0, 0] + ib * r[1, 0]
    t01 = ia * r[0, 1] + ib * r[1, 1]
    t10 = ic * r[0, 0] + ie * r[1, 0]
    t11 = ic * r[0, 1] + ie * r[1, 1]
    s00 = t00 * ia + t01 * ib
    s01 = t00 * ic + t01 * ie
    s10 = t10 * ia + t11 * ib
    s11 = t10 * ic + t11 * ie
    out_mu[0], out_mu[1] = mx, my
    out_s[0, 0], out_s[1, 1] = s00, s11
    out_s[0, 1] = out_s[1, 0] = 0.5 * (s01 + s10)


@numba.njit(cache=True)
def _landmark_update(
    px: float,
    py: float,
    pth: float,
    z0: float,
    z1: float,
    r: FloatArray,
    mu: FloatArray,
    s: FloatArray,
) -> float:  # pragma: no cover (compiled)
    """EKF update of one landmark (mu (2,), s (2, 2) in place); returns log N(nu; 0, Q)."""
    dx, dy = mu[0] - px, mu[1] - py
    q = dx * dx + dy * dy
    d = math.sqrt(q)
    a, b, c, e = dx / d, dy / d, -dy / q, dx / q
    nu0 = z0 - d
    nu1 = _wrap(z1 - _wrap(math.atan2(dy, dx) - pth))
    # HS = H S, Q = HS H^T + R
    hs00 = a * s[0, 0] + b * s[1, 0]
    hs01 = a * s[0, 1] + b * s[1, 1]
    hs10 = c * s[0, 0] + e * s[1, 0]
    hs11 = c * s[0, 1] + e * s[1, 1]
    q00 = hs00 * a + hs01 * b + r[0, 0]
    q01 = hs00 * c + hs01 * e + r[0, 1]
    q10 = hs10 * a + hs11 * b + r[1, 0]
    q11 = hs10 * c + hs11 * e + r[1, 1]
    qd = q00 * q11 - q01 * q10
    i00, i01, i10, i11 = q11 / qd, -q01 / qd, -q10 / qd, q00 / qd
    m2 = i00 * nu0 * nu0 + (i01 + i10) * nu0 * nu1 + i11 * nu1 * nu1
    # K = S H^T Q^-1 = HS^T Q^-1
    k00 = hs00 * i00 + hs10 * i10
    k01 = hs00 * i01 + hs10 * i11
    k10 = hs01 * i00 + hs11 * i10
    k11 = hs01 * i01 + hs11 * i11
    mu[0] += k00 * nu0 + k01 * nu1
    mu[1] += k10 * nu0 + k11 * nu1
    # S - K Q K^T = S - K HS (since Q K^T = HS)
    n00 = s[0, 0] - (k00 * hs00 + k01 * hs10)
    n01 = s[0, 1] - (k00 * hs01 + k01 * hs11)
    n10 = s[1, 0] - (k10 * hs00 + k11 * hs10)
    n11 = s[1, 1] - (k10 * hs01 + k11 * hs11)
    s[0, 0], s[1, 1] = n00, n11
    s[0, 1] = s[1, 0] = 0.5 * (n01 + n10)
    return float(-0.5 * m2 - 0.5 * math.log(qd) - _LOG_2PI)


@numba.njit(cache=True)
def update_landmarks(
    poses: FloatArray,
    mu: FloatArray,
    sigma: FloatArray,
    slots: IntArray,
    new: BoolArray,
    z: FloatArray,
    r: FloatArray,
) -> None:  # pragma: no cover (compiled)
    """One observation's map update in every particle (unknown association), in place.

    Particle i initialises slot ``slots[i]`` from the observation when ``new[i]``, else
    makes the EKF update of the landmark there (:func:`_landmark_update`, the one
    definition both associations use); ``slots[i] < 0`` skips the particle.

    Parameters
    ----------
    poses : (P, 3) sampled poses; mu : (P, C, 2); sigma : (P, C, 2, 2)
    slots : (P,) the slot of the observation in each particle, -1 to skip
    new : (P,) whether it is a new landmark in that particle
    z : (2,) range [m], bearing [rad]; r : (2, 2) its covariance
    """
    for i in range(poses.shape[0]):
        j = slots[i]
        if j < 0:
            continue
        px, py, pth = poses[i, 0], poses[i, 1], poses[i, 2]
        if new[i]:
            _init_landmark(px, py, pth, z[0], z[1], r, mu[i, j], sigma[i, j])
        else:
            _landmark_update(px, py, pth, z[0], z[1], r, mu[i, j], sigma[i, j])


@numba.njit(cache=True)
def update_known_v1(
    poses: FloatArray,
    log_w: FloatArray,
    mu: FloatArray,
    sigma: FloatArray,
    active: BoolArray,
    evidence: IntArray,
    slots: IntArray,
    z: FloatArray,
    z_cov: FloatArray,
) -> None:  # pragma: no cover (compiled)
    """FastSLAM 1.0 observation update with given association, in place.

    Parameters
    ----------
    poses : (P, 3) sampled poses; log_w : (P,); mu : (P, C, 2); sigma : (P, C, 2, 2);
    active : (P, C); evidence : (P, C)
    slots : (K,) the slot of each observation, -1 to skip
    z : (K, 2) range [m], bearing [rad]; z_cov : (K, 2, 2)
    """
    for i in range(poses.shape[0]):
        px, py, pth = poses[i, 0], poses[i, 1], poses[i, 2]
        for k in range(slots.shape[0]):
            j = slots[k]
            if j < 0:
                continue
            if active[i, j]:
                log_w[i] += _landmark_update(
                    px, py, pth, z[k, 0], z[k, 1], z_cov[k], mu[i, j], sigma[i, j]
                )
            else:
                _init_landmark(px, py, pth, z[k, 0], z[k, 1], z_cov[k], mu[i, j], sigma[i, j])
                active[i, j] = True
            evidence[i, j] += 1


@numba.njit(cache=True)
def _inv3(a: FloatArray, out: FloatArray) -> None:  # pragma: no cover (compiled)
    """Inverse of a 3 x 3 matrix (adjugate over determinant)."""
    c00 = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    c01 = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    c02 = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    det = a[0, 0] * c00 + a[0, 1] * c01 + a[0, 2] * c02
    out[0, 0] = c00 / det
    out[1, 0] = c01 / det
    out[2, 0] = c02 / det
    out[0, 1] = (a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2]) / det
    out[1, 1] = (a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]) / det
    out[2, 1] = (a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1]) / det
    out[0, 2] = (a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]) / det
    out[1, 2] = (a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]) / det
    out[2, 2] = (a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]) / det


@numba.njit(cache=True)
def update_known_v2(
    poses: FloatArray,
    log_w: FloatArray,
    mu: FloatArray,
    sigma: FloatArray,
    active: BoolArray,
    evidence: IntArray,
    slots: IntArray,
    z: FloatArray,
    z_cov: FloatArray,
    delta: FloatArray,
    delta_cov: FloatArray,
    eps: FloatArray,
) -> None:  # pragma: no cover (compiled)
    """FastSLAM 2.0 step with given association (motion, proposal, sample, map), in place.

    Parameters
    ----------
    poses : (P, 3) the previous poses, replaced by the sampled ones
    log_w, mu, sigma, active, evidence, slots, z, z_cov : as :func:`update_known_v1`
    delta : (P, 3) odometry dx, dy [m], dtheta [rad] of each particle (the same measured
        motion, corrected by each particle's odometry calibration); delta_cov : (3, 3) its
        covariance
    eps : (P, 3) standard normal draws for the pose sample
    """
    cov = np.empty((3, 3))
    info = np.empty((3, 3))
    tmp = np.empty((3, 3))
    mean = np.empty(3)
    for i in range(poses.shape[0]):
        th = poses[i, 2]
        c, s = math.cos(th), math.sin(th)
        mean[0] = poses[i, 0] + c * delta[i, 0] - s * delta[i, 1]
        mean[1] = poses[i, 1] + s * delta[i, 0] + c * delta[i, 1]
        mean[2] = _wrap(th + delta[i, 2])
        # cov = J D J^T with J = rot(theta) (+) 1
        for a in range(3):
            tmp[0, a] = c * delta_cov[0, a] - s * delta_cov[1, a]
            tmp[1, a] = s * delta_cov[0, a] + c * delta_cov[1, a]
            tmp[2, a] = delta_cov[2, a]
        for a in range(3):
            cov[a, 0] = tmp[a, 0] * c - tmp[a, 1] * s
            cov[a, 1] = tmp[a, 0] * s + tmp[a, 1] * c
            cov[a, 2] = tmp[a, 2]
        # proposal: the observations of landmarks known at the step's start, in turn
        for k in range(slots.shape[0]):
            j = slots[k]
            if j < 0 or not active[i, j]:
                continue
            sm = sigma[i, j]
            dx, dy = mu[i, j, 0] - mean[0], mu[i, j, 1] - mean[1]
            q = dx * dx + dy * dy
            d = math.sqrt(q)
            ha, hb, hc, he = dx / d, dy / d, -dy / q, dx / q  # H_m; H_x = [-H_m | (0, -1)]
            nu0 = z[k, 0] - d
            nu1 = _wrap(z[k, 1] - _wrap(math.atan2(dy, dx) - mean[2]))
            hs00 = ha * sm[0, 0] + hb * sm[1, 0]
            hs01 = ha * sm[0, 1] + hb * sm[1, 1]
            hs10 = hc * sm[0, 0] + he * sm[1, 0]
            hs11 = hc * sm[0, 1] + he * sm[1, 1]
            q00 = hs00 * ha + hs01 * hb + z_cov[k, 0, 0]
            q01 = hs00 * hc + hs01 * he + z_cov[k, 0, 1]
            q10 = hs10 * ha + hs11 * hb + z_cov[k, 1, 0]
            q11 = hs10 * hc + hs11 * he + z_cov[k, 1, 1]
            # H_x rows
            x0, x1, x2 = -ha, -hb, 0.0
            y0, y1, y2 = -hc, -he, -1.0
            # Hx cov (2 x 3)
            r00 = x0 * cov[0, 0] + x1 * cov[1, 0] + x2 * cov[2, 0]
            r01 = x0 * cov[0, 1] + x1 * cov[1, 1] + x2 * cov[2, 1]
            r02 = x0 * cov[0, 2] + x1 * cov[1, 2] + x2 * cov[2, 2]
            r10 = y0 * cov[0, 0] + y1 * cov[1, 0] + y2 * cov[2, 0]
            r11 = y0 * cov[0, 1] + y1 * cov[1, 1] + y2 * cov[2, 1]
            r12 = y0 * cov[0, 2] + y1 * cov[1, 2] + y2 * cov[2, 2]
            l00 = r00 * x0 + r01 * x1 + r02 * x2 + q00
            l01 = r00 * y0 + r01 * y1 + r02 * y2 + q01
            l10 = r10 * x0 + r11 * x1 + r12 * x2 + q10
            l11 = r10 * y0 + r11 * y1 + r12 * y2 + q11
            ld = l00 * l11 - l01 * l10
            m2 = (l11 * nu0 * nu0 - (l01 + l10) * nu0 * nu1 + l00 * nu1 * nu1) / ld
            log_w[i] += -0.5 * m2 - 0.5 * math.log(ld) - _LOG_2PI
            qd = q00 * q11 - q01 * q10
            i00, i01, i10, i11 = q11 / qd, -q01 / qd, -q10 / qd, q00 / qd
            # G = Hx^T Q^-1 (3 x 2)
            g00 = x0 * i00 + y0 * i10
            g01 = x0 * i01 + y0 * i11
            g10 = x1 * i00 + y1 * i10
            g11 = x1 * i01 + y1 * i11
            g20 = x2 * i00 + y2 * i10
            g21 = x2 * i01 + y2 * i11
            _inv3(cov, tmp)
            info[0, 0] = g00 * x0 + g01 * y0 + tmp[0, 0]
            info[0, 1] = g00 * x1 + g01 * y1 + tmp[0, 1]
            info[0, 2] = g00 * x2 + g01 * y2 + tmp[0, 2]
            info[1, 0] = g10 * x0 + g11 * y0 + tmp[1, 0]
            info[1, 1] = g10 * x1 + g11 * y1 + tmp[1, 1]
            info[1, 2] = g10 * x2 + g11 * y2 + tmp[1, 2]
            info[2, 0] = g20 * x0 + g21 * y0 + tmp[2, 0]
            info[2, 1] = g20 * x1 + g21 * y1 + tmp[2, 1]
            info[2, 2] = g20 * x2 + g21 * y2 + tmp[2, 2]
            _inv3(info, tmp)
            for a in range(3):
                for b in range(3):
                    cov[a, b] = 0.5 * (tmp[a, b] + tmp[b, a])
            v0 = g00 * nu0 + g01 * nu1
            v1 = g10 * nu0 + g11 * nu1
            v2 = g20 * nu0 + g21 * nu1
            mean[0] += cov[0, 0] * v0 + cov[0, 1] * v1 + cov[0, 2] * v2
            mean[1] += cov[1, 0] * v0 + cov[1, 1] * v1 + cov[1, 2] * v2
            mean[2] = _wrap(mean[2] + cov[2, 0] * v0 + cov[2, 1] * v1 + cov[2, 2] * v2)
        # sample x ~ N(mean, cov): Cholesky factor of cov + 1e-12 I
        a00 = cov[0, 0] + 1e-12
        l00_ = math.sqrt(a00)
        l10_ = cov[1, 0] / l00_
        l20_ = cov[2, 0] / l00_
        l11_ = math.sqrt(cov[1, 1] + 1e-12 - l10_ * l10_)
        l21_ = (cov[2, 1] - l20_ * l10_) / l11_
        l22_ = math.sqrt(cov[2, 2] + 1e-12 - l20_ * l20_ - l21_ * l21_)
        e0, e1, e2 = eps[i, 0], eps[i, 1], eps[i, 2]
        px = mean[0] + l00_ * e0
        py = mean[1] + l10_ * e0 + l11_ * e1
        pth = _wrap(mean[2] + l20_ * e0 + l21_ * e1 + l22_ * e2)
        poses[i, 0], poses[i, 1], poses[i, 2] = px, py, pth
        # the map, from the sampled pose
        for k in range(slots.shape[0]):
            j = slots[k]
            if j < 0:
                continue
            if active[i, j]:
                _landmark_update(px, py, pth, z[k, 0], z[k, 1], z_cov[k], mu[i, j], sigma[i, j])
            else:
                _init_landmark(px, py, pth, z[k, 0], z[k, 1], z_cov[k], mu[i, j], sigma[i, j])
                active[i, j] = True
            evidence[i, j] += 1
