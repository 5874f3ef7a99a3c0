"""The scan matcher of grid SLAM: hill climbing on a particle's own map (GMapping's
``ScanMatcher::optimize``, Grisetti et al. 2007, sec. IV).

With ``d_b`` the distance from beam b's end point to the nearest occupied cell (log
odds > 0) within ``window`` cells of the end point's cell, a pose's *log likelihood* is
``sum_b log(z_hit exp(-d_b^2 / (2 sigma^2)) + z_rand)`` (``d_b`` capped at the window's
reach) and its *score* ``sum_b exp(-d_b^2 / (2 sigma^2))`` (beams with no wall near
adding 0; a match is accepted when the score is high enough).

The matcher climbs to the mode of the proposal of Grisetti et al. (2007, eq. 8): the
scan likelihood (tempered by the weight gain) times the odometry motion model, a
Gaussian about the noise-free odometry pose. Without the motion term a featureless
corridor lets the match slide along it, scan after scan. From the particle's odometry
sample it tries the six moves of ``step_m`` along x and y and ``step_rad`` in heading,
takes the best while it improves, and halves the steps when none does,
``refinements`` times.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from firefleet.estimation.grid._rays import cell_rc


@njit(cache=True)
def _beam_d2(
    log_odds: np.ndarray, x: float, y: float, ox: float, oy: float, res: float, window: int
) -> float:
    """Squared distance [m^2] from (x, y) to the nearest occupied cell centre in the
    window around its cell; -1 when there is none."""
    h, w = log_odds.shape
    r, c = cell_rc(x, y, ox, oy, res, h)
    best = -1.0
    for dr in range(-window, window + 1):
        rr = r + dr
        if rr < 0 or rr >= h:
            continue
        cy = oy + (h - 1 - rr + 0.5) * res
        for dc in range(-window, window + 1):
            cc = c + dc
            if cc < 0 or cc >= w or log_odds[rr, cc] <= 0.0:
                continue
            cx = ox + (cc + 0.5) * res
            d2 = (cx - x) * (cx - x) + (cy - y) * (cy - y)
            if best < 0.0 or d2 < best:
                best = d2
    return best


@njit(cache=True)
def match_score(
    log_odds: np.ndarray,
    x: float,
    y: float,
    th: float,
    ranges: np.ndarray,
    bearings: np.ndarray,
    ox: float,
    oy: float,
    res: float,
    window: int,
    inv2s2: float,
) -> float:
    """The matcher's score of pose (x, y, th) against one map (see the module notes)."""
    s = 0.0
    for b in range(ranges.shape[0]):
        z = ranges[b]
        a = th + bearings[b]
        d2 = _beam_d2(log_odds, x + z * math.cos(a), y + z * math.sin(a), ox, oy, res, window)
        if d2 >= 0.0:
            s += math.exp(-d2 * inv2s2)
    return s


@njit(cache=True)
def match_log_likelihood(
    log_odds: np.ndarray,
    x: float,
    y: float,
    th: float,
    ranges: np.ndarray,
    bearings: np.ndarray,
    ox: float,
    oy: float,
    res: float,
    window: int,
    inv2s2: float,
    z_hit: float,
    z_rand: float,
) -> float:
    """The scan's log likelihood at (x, y, th) on one map (see the module notes)."""
    cap = (window + 0.5) * res
    total = 0.0
    for b in range(ranges.shape[0]):
        z = ranges[b]
        a = th + bearings[b]
        d2 = _beam_d2(log_odds, x + z * math.cos(a), y + z * math.sin(a), ox, oy, res, window)
        if d2 < 0.0:
            d2 = cap * cap
        total += math.log(z_hit * math.exp(-d2 * inv2s2) + z_rand)
    return total


@njit(cache=True)
def _objective(
    log_odds: np.ndarray,
    x: float,
    y: float,
    th: float,
    prior: np.ndarray,
    ranges: np.ndarray,
    bearings: np.ndarray,
    ox: float,
    oy: float,
    res: float,
    window: int,
    inv2s2: float,
    z_hit: float,
    z_rand: float,
    inv_gain: float,
    inv_sxy2: float,
    inv_sth2: float,
) -> float:
    """Tempered scan log likelihood plus the motion prior's log density (up to a constant)."""
    ll: float = match_log_likelihood(
        log_odds, x, y, th, ranges, bearings, ox, oy, res, window, inv2s2, z_hit, z_rand
    )
    dx, dy = x - prior[0], y - prior[1]
    dth = math.atan2(math.sin(th - prior[2]), math.cos(th - prior[2]))
    return float(ll * inv_gain - 0.5 * ((dx * dx + dy * dy) * inv_sxy2 + dth * dth * inv_sth2))


@njit(cache=True)
def hill_climb(
    log_odds: np.ndarray,
    pose: np.ndarray,
    prior: np.ndarray,
    ranges: np.ndarray,
    bearings: np.ndarray,
    ox: float,
    oy: float,
    res: float,
    window: int,
    inv2s2: float,
    z_hit: float,
    z_rand: float,
    inv_gain: float,
    sigma_xy: float,
    sigma_th: float,
    step_m: float,
    step_rad: float,
    refinements: int,
) -> tuple[float, float, float, float]:
    """The matched pose (x, y, th) from ``pose`` (3,) and its objective: the mode of the
    tempered scan likelihood times the motion prior ``N(prior, diag(sigma_xy^2,
    sigma_xy^2, sigma_th^2))``."""
    ixy, ith = 1.0 / (sigma_xy * sigma_xy), 1.0 / (sigma_th * sigma_th)
    x, y, th = pose[0], pose[1], pose[2]
    best = _objective(
        log_odds,
        x,
        y,
        th,
        prior,
        ranges,
        bearings,
        ox,
        oy,
        res,
        window,
        inv2s2,
        z_hit,
        z_rand,
        inv_gain,
        ixy,
        ith,
    )
    lin, ang = step_m, step_rad
    level = 0
    while level <= refinements:
        bx, by, bth, bs = x, y, th, best
        for move in range(6):
            cx, cy, cth = x, y, th
            if move == 0:
                cx += lin
            elif move == 1:
                cx -= lin
            elif move == 2:
                cy += lin
            elif move == 3:
                cy -= lin
            elif move == 4:
                cth += ang
            else:
                cth -= ang
            s = _objective(
                log_odds,
                cx,
                cy,
                cth,
                prior,
                ranges,
                bearings,
                ox,
                oy,
                res,
                window,
                inv2s2,
                z_hit,
                z_rand,
                inv_gain,
                ixy,
                ith,
            )
            if s > bs:
                bx, by, bth, bs = cx, cy, cth, s
        if bs > best:
            x, y, th, best = bx, by, bth, bs
        else:
            lin *= 0.5
            ang *= 0.5
            level += 1
    return x, y, th, best


@njit(cache=True)
def match_particles(
    maps: np.ndarray,
    poses: np.ndarray,
    priors: np.ndarray,
    ranges: np.ndarray,
    bearings: np.ndarray,
    ox: float,
    oy: float,
    res: float,
    window: int,
    sigma: float,
    step_m: float,
    step_rad: float,
    refinements: int,
    min_score: float,
    z_hit: float,
    z_rand: float,
    inv_gain: float,
    sigma_xy: float,
    sigma_th: float,
    out_poses: np.ndarray,
    out_loglik: np.ndarray,
) -> None:
    """Every particle's scan-matched pose (P, 3) on its own map (P, H, W), from its
    odometry sample ``poses`` with the motion prior centred on ``priors`` (P, 3), kept
    where the match scores at least ``min_score`` (else the sample), and the scan's log
    likelihood there (P,)."""
    inv2s2 = 0.5 / (sigma * sigma)
    for p in range(poses.shape[0]):
        x, y, th, _ = hill_climb(
            maps[p],
            poses[p],
            priors[p],
            ranges,
            bearings,
            ox,
            oy,
            res,
            window,
            inv2s2,
            z_hit,
            z_rand,
            inv_gain,
            sigma_xy,
            sigma_th,
            step_m,
            step_rad,
            refinements,
        )
        s = match_score(maps[p], x, y, th, ranges, bearings, ox, oy, res, window, inv2s2)
        if s < min_score:
            x, y, th = poses[p, 0], poses[p, 1], poses[p, 2]
        out_poses[p, 0] = x
        out_poses[p, 1] = y
        out_poses[p, 2] = math.atan2(math.sin(th), math.cos(th))
        out_loglik[p] = match_log_likelihood(
            maps[p], x, y, th, ranges, bearings, ox, oy, res, window, inv2s2, z_hit, z_rand
        )
