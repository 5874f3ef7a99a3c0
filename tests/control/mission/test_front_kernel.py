"""front_aim's candidate cells in one compiled pass (``_water._front_cells``) give the
aim the array form gave, to the last bit."""

from __future__ import annotations

import math

import numpy as np

from firefleet.control.mission._coverage import CoarseMap, coarse_map, line_of_sight
from firefleet.control.mission._water import front_aim
from firefleet.control.navigation import build_costmap
from firefleet.world import OccupancyGrid, load_map


def _before(
    wet_l_m2: np.ndarray,
    cm: CoarseMap,
    pose: np.ndarray,
    flames_xy_m: np.ndarray,
    reach_m: float,
    half_angle_rad: float,
    soak_l_m2: float,
    front_m: float,
) -> np.ndarray | None:
    """front_aim as it was (the reference)."""
    f = np.asarray(flames_xy_m, dtype=float).reshape(-1, 2)
    if len(f) == 0:
        return None
    f = f[np.hypot(f[:, 0] - pose[0], f[:, 1] - pose[1]) <= reach_m + front_m]
    if len(f) == 0:
        return None
    h, w = cm.shape
    n = math.ceil(reach_m / cm.cell_m) + 1
    r0, c0 = (int(v) for v in cm.cell_of(np.asarray(pose[:2], dtype=float)))
    rr, cc = np.mgrid[max(r0 - n, 0) : min(r0 + n + 1, h), max(c0 - n, 0) : min(c0 + n + 1, w)]
    rows, cols = rr.ravel(), cc.ravel()
    keep = cm.floor[rows, cols]
    if wet_l_m2.shape == cm.shape:
        keep &= wet_l_m2[rows, cols] < soak_l_m2
    rows, cols = rows[keep], cols[keep]
    xy = cm.centre_xy(np.stack([rows, cols], axis=-1))
    rel = xy - pose[:2]
    dist = np.hypot(rel[:, 0], rel[:, 1])
    near = np.hypot(xy[:, None, 0] - f[None, :, 0], xy[:, None, 1] - f[None, :, 1]) <= front_m
    sel = (dist <= reach_m) & (dist >= cm.cell_m) & near.any(axis=1)
    xy, near = xy[sel], near[sel]
    if len(xy) == 0:
        return None
    ok = line_of_sight(cm, np.repeat(pose[None, :2], len(xy), 0), xy)
    xy, near = xy[ok], near[ok]
    if len(xy) == 0:
        return None
    bearing = np.arctan2(xy[:, 1] - pose[1], xy[:, 0] - pose[0])
    off = np.abs((bearing[:, None] - bearing[None, :] + np.pi) % (2 * np.pi) - np.pi)
    inside = (off <= half_angle_rad).astype(np.float64)
    held = inside.sum(axis=1)
    served = ((inside @ near.astype(np.float64)) > 0.0).sum(axis=1)
    out: np.ndarray = xy[int(np.argmax(served * (len(xy) + 1) + held))]
    return out


def test_front_aim_equals_the_array_form() -> None:
    """Nozzles anywhere on the office and an offset grid (by walls, by and off the
    edges), 0-6 flames about them, a dry ledger, a soaked one and a patchy one."""
    rng = np.random.default_rng(13)
    small = np.zeros((60, 90), dtype=bool)
    small[25:45, 40] = True
    grids = [load_map("office"), OccupancyGrid(small, ~small, 0.05, (1.15, -0.4))]
    aimed = 0
    for grid in grids:
        cm = coarse_map(build_costmap(grid, 0.2), 0.25)
        x0, x1, y0, y1 = grid.extent_m
        for _ in range(80):
            pose = np.array([rng.uniform(x0 - 0.5, x1 + 0.5), rng.uniform(y0 - 0.5, y1 + 0.5), 0.0])
            flames = pose[:2] + rng.normal(0.0, 2.0, (int(rng.integers(0, 7)), 2))
            wets = [np.zeros((0, 0)), np.zeros(cm.shape), rng.uniform(0.0, 2.6, cm.shape)]
            wet = wets[int(rng.integers(0, 3))]
            args = (3.0, math.radians(15.0), 1.3, float(rng.choice([0.5, 1.0])))
            got = front_aim(wet, cm, pose, flames, *args)
            want = _before(wet, cm, pose, flames, *args)
            if want is None:
                assert got is None
                continue
            assert got is not None
            assert got.tobytes() == want.tobytes()
            aimed += 1
    assert aimed > 40
