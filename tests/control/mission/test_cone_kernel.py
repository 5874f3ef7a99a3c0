"""cone_coverage's compiled samples equal its array form (the samples, the grid's cells,
the first opaque sample, the view) cell for cell and in order."""

from __future__ import annotations

import math

import numpy as np

from firefleet.control.mission._coverage import CoarseMap, coarse_map, cone_coverage, in_view
from firefleet.control.navigation import build_costmap
from firefleet.world import OccupancyGrid, load_map


def _array_form(
    cm: CoarseMap,
    pose: np.ndarray,
    range_m: float,
    hfov_rad: float,
    near_m: float = 0.0,
    half_width_m: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """cone_coverage as it was (the reference)."""
    step = 0.5 * cm.cell_m
    n_rays = max(2, math.ceil(hfov_rad * range_m / step) + 1)
    rel = np.linspace(-0.5 * hfov_rad, 0.5 * hfov_rad, n_rays)
    ang = pose[:, 2:3] + rel[None]
    dist = np.arange(1, math.floor(range_m / step) + 1) * step
    x = pose[:, 0, None, None] + dist * np.cos(ang)[..., None]
    y = pose[:, 1, None, None] + dist * np.sin(ang)[..., None]
    xy = np.stack([x, y], axis=-1)
    on = cm.grid.contains(xy)
    rc = cm.cell_of(xy)
    blocked = ~on | cm.opaque[rc[..., 0], rc[..., 1]]
    blocked[..., dist < cm.cell_m] = False
    before = np.zeros_like(blocked)
    before[..., 1:] = np.logical_or.accumulate(blocked, axis=-1)[..., :-1]
    margin = 0.5 * cm.cell_m
    view = in_view(dist[None, :], rel[:, None], range_m, hfov_rad, near_m, half_width_m + margin)
    seen = on & ~before & view[None]
    return rc[..., 0][seen], rc[..., 1][seen]


def test_cone_coverage_equals_the_array_form() -> None:
    """The office and a grid off the origin whose coarse blocks do not divide it: robots
    anywhere (by walls, by and beyond the map's edges), 0-7 at a time, the camera's
    and the detector's cones (near_m, half_width_m)."""
    rng = np.random.default_rng(11)
    small = np.zeros((63, 91), dtype=bool)
    small[20:40, 45] = True
    small[30, 10:60] = True
    grids = [load_map("office"), OccupancyGrid(small, ~small, 0.05, (-2.1, 0.35))]
    checked = 0
    for grid in grids:
        cm = coarse_map(build_costmap(grid, 0.2), 0.25)
        x0, x1, y0, y1 = grid.extent_m
        for _ in range(30):
            n = int(rng.integers(0, 8))
            pose = np.c_[
                rng.uniform(x0 - 1.0, x1 + 1.0, n),
                rng.uniform(y0 - 1.0, y1 + 1.0, n),
                rng.uniform(-4.0, 4.0, n),
            ]
            for args in ((4.0, math.radians(51.0)), (3.0, math.radians(51.0), 0.8, 0.3)):
                got = cone_coverage(cm, pose, *args)
                want = _array_form(cm, pose, *args)
                assert got[0].dtype == want[0].dtype == np.int64
                assert got[0].tobytes() == want[0].tobytes()
                assert got[1].tobytes() == want[1].tobytes()
                checked += len(want[0])
    assert checked > 10_000
    # a pose not finite: the array form itself
    cm = coarse_map(build_costmap(grids[0], 0.2), 0.25)
    pose = np.array([[2.0, 2.0, 0.0], [np.nan, 1.0, 0.0]])
    with np.errstate(invalid="ignore"):
        got = cone_coverage(cm, pose, 4.0, 1.0)
        want = _array_form(cm, pose, 4.0, 1.0)
    assert got[0].tobytes() == want[0].tobytes()
    assert got[1].tobytes() == want[1].tobytes()
