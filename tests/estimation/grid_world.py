"""A small building and an exact lidar for the grid estimators' tests.

``office()`` is a 12 m x 8 m floor: a corridor, three rooms below it and two above,
doors 0.9 m wide, and furniture placed so that no two places look alike (global
localisation needs an asymmetric map). ``cast`` is an exact ray caster on the grid
(Amanatides and Woo's traversal of the cells, the range to the first occupied cell's
boundary, the map's edge counting as a wall), written here independently of the
package's kernels. ``drive`` gives a trajectory through the building and its odometry.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from firefleet.estimation.particle_filter import compose, relative_pose
from firefleet.models.kinematics import wrap_angle
from firefleet.world import OccupancyGrid

WIDTH_M, HEIGHT_M = 12.0, 8.0


def office(resolution_m: float = 0.05) -> OccupancyGrid:
    """The test office (walls 0.1 m thick), on cells of ``resolution_m``."""
    h, w = round(HEIGHT_M / resolution_m), round(WIDTH_M / resolution_m)
    grid0 = OccupancyGrid(np.zeros((h, w), bool), np.ones((h, w), bool), resolution_m)
    centres = grid0.center_of(np.stack(np.meshgrid(np.arange(h), np.arange(w), indexing="ij"), -1))
    x, y = centres[..., 0], centres[..., 1]
    occ = np.zeros((h, w), bool)

    def box(x0: float, x1: float, y0: float, y1: float) -> None:
        occ[(x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)] = True

    t = 0.1
    box(0, WIDTH_M, 0, t)
    box(0, WIDTH_M, HEIGHT_M - t, HEIGHT_M)
    box(0, t, 0, HEIGHT_M)
    box(WIDTH_M - t, WIDTH_M, 0, HEIGHT_M)
    box(0, 1.55, 3.45, 3.55)
    box(2.45, 5.55, 3.45, 3.55)
    box(6.45, 9.55, 3.45, 3.55)
    box(10.45, WIDTH_M, 3.45, 3.55)
    box(3.95, 4.05, 0, 3.5)  # rooms below: walls at x = 4 and 8
    box(7.95, 8.05, 0, 3.5)
    box(0, 2.05, 4.45, 4.55)  # the corridor's north wall, doors at x = 2.5 and 9
    box(2.95, 8.55, 4.45, 4.55)
    box(9.45, WIDTH_M, 4.45, 4.55)
    box(4.95, 5.05, 4.5, HEIGHT_M)  # rooms above: wall at x = 5
    box(0.6, 1.6, 0.6, 1.4)  # a desk in the south-west room
    box(9.0, 9.4, 6.2, 6.6)  # a pillar in the north-east room
    box(8.6, 11.2, 0.4, 0.7)  # a shelf along the south-east room's wall
    box(5.6, 6.4, 6.8, 7.4)  # a cabinet in the north-east room
    box(1.0, 3.0, 6.6, 7.0)  # a bench in the north-west room
    return OccupancyGrid(occ, ~occ, resolution_m, name="test-office")


@njit(cache=False)
def _cast(occ, ox, oy, res, poses, bearings, max_range):  # type: ignore[no-untyped-def]
    h, w = occ.shape
    out = np.full((poses.shape[0], bearings.shape[0]), np.inf)
    for i in range(poses.shape[0]):
        u0 = (poses[i, 0] - ox) / res
        v0 = (poses[i, 1] - oy) / res
        for b in range(bearings.shape[0]):
            a = poses[i, 2] + bearings[b]
            du, dv = math.cos(a), math.sin(a)
            cu, cv = math.floor(u0), math.floor(v0)
            su = 1 if du > 0 else -1
            sv = 1 if dv > 0 else -1
            tdu = abs(1.0 / du) if du != 0 else 1e300
            tdv = abs(1.0 / dv) if dv != 0 else 1e300
            tu = ((cu + 1 - u0) if du > 0 else (u0 - cu)) * tdu if du != 0 else 1e300
            tv = ((cv + 1 - v0) if dv > 0 else (v0 - cv)) * tdv if dv != 0 else 1e300
            t = 0.0
            while t * res < max_range:
                if cu < 0 or cu >= w or cv < 0 or cv >= h or occ[h - 1 - cv, cu]:
                    out[i, b] = t * res
                    break
                if tu < tv:
                    t = tu
                    tu += tdu
                    cu += su
                else:
                    t = tv
                    tv += tdv
                    cv += sv
            if out[i, b] >= max_range:
                out[i, b] = np.inf
    return out


def cast(
    grid: OccupancyGrid,
    poses: np.ndarray,
    bearings: np.ndarray,
    max_range_m: float,
    noise_m: float = 0.0,
    rng: np.random.Generator | None = None,
) -> np.ndarray:
    """Exact ranges (N, B) [m] to the first occupied cell; ``inf`` beyond ``max_range_m``."""
    ox, oy = grid.origin_m
    r = _cast(grid.occupied, ox, oy, grid.resolution_m, np.atleast_2d(poses), bearings, max_range_m)
    if noise_m > 0.0 and rng is not None:
        r = r + noise_m * rng.standard_normal(r.shape)
    return np.where(r >= max_range_m, np.inf, np.maximum(r, 0.0))


WAYPOINTS = np.array(
    [
        [2.0, 1.8],
        [2.0, 4.0],
        [6.0, 4.0],
        [6.0, 1.8],
        [6.0, 4.0],
        [9.2, 4.0],
        [9.2, 5.6],
        [7.0, 5.8],
        [9.2, 5.6],
        [9.2, 4.0],
        [2.5, 4.0],
        [2.5, 5.8],
    ]
)


def drive(
    duration_s: float,
    rate_hz: float = 10.0,
    speed_m_s: float = 0.5,
    turn_rad_s: float = 1.5,
    start: int = 0,
    waypoints: np.ndarray = WAYPOINTS,
) -> np.ndarray:
    """True poses (T, 3) at ``rate_hz`` along the waypoints (M, 2) [m] from
    ``waypoints[start]``: straight legs at ``speed_m_s``, turns on the spot; stops at the
    last waypoint."""
    dt = 1.0 / rate_hz
    pts = waypoints[start:]
    d0 = pts[1] - pts[0]
    pose = np.array([pts[0, 0], pts[0, 1], math.atan2(d0[1], d0[0])])
    out = [pose.copy()]
    leg = 1
    n = round(duration_s * rate_hz)
    while len(out) <= n:
        if leg < len(pts):
            d = pts[leg] - pose[:2]
            dist = float(np.hypot(*d))
            err = float(wrap_angle(math.atan2(d[1], d[0]) - pose[2])) if dist > 1e-9 else 0.0
            if dist < 1e-9:
                leg += 1
                continue
            if abs(err) > 1e-9:
                pose[2] = wrap_angle(pose[2] + np.clip(err, -turn_rad_s * dt, turn_rad_s * dt))
            else:
                step = min(speed_m_s * dt, dist)
                pose[:2] += step * np.array([math.cos(pose[2]), math.sin(pose[2])])
        out.append(pose.copy())
    return np.array(out[: n + 1])


def odometry(
    poses: np.ndarray,
    rng: np.random.Generator,
    scale: float = 1.02,
    turn_scale: float = 1.03,
    sigma_m: float = 0.005,
    sigma_rad: float = 0.005,
) -> tuple[np.ndarray, np.ndarray]:
    """Measured increments (T-1, 3) with a scale error, a turn scale error and white
    noise, and the dead-reckoned poses (T, 3) they integrate to."""
    delta = relative_pose(poses[:-1], poses[1:])
    delta[:, :2] *= scale
    delta[:, 2] *= turn_scale
    delta[:, :2] += sigma_m * rng.standard_normal((len(delta), 2))
    delta[:, 2] += sigma_rad * rng.standard_normal(len(delta))
    dead = [poses[0]]
    for d in delta:
        dead.append(compose(dead[-1], d))
    return delta, np.array(dead)
