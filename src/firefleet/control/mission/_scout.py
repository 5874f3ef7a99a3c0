"""Looking for the fire the team does not see: the floor about a fire its cameras have
not looked at lately is a frontier of the fire.

The team knows a fire by the spots its cameras put on the map, and a fire burns on where
no camera looks: on mission-office seed 2 at 450 s the team's sixteen spots lay by the
fire room's door and in the corridor, all but one soaked, while 130 cells burned inside
the room behind the wall; the fighters stood in the corridor without a shot for 200 s.
So the team keeps, per coarse cell, when a thermal camera last had it in view
(:func:`seen_update`: the cone to ``range_m``, in line of sight), and a fighter with no
flame left to aim at, or no slot with a shot, goes to look at the floor about its fire
(within ``scout_m`` of a spot, through open floor: the room behind a door) that no
camera has seen for ``stale_s``: to a standable cell in clear sight of it, clear of the
flames, nearest by travel (:func:`scout_goals`). What its camera sees there joins the
team's knowledge as detections, and the ring forms about them.
"""

from __future__ import annotations

import numpy as np
import scipy.ndimage as ndi

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.mission._coverage import CoarseMap, cone_coverage, viewpoints

__all__ = ["fire_region", "scout_goals", "seen_update"]


def seen_update(
    seen_s: FloatArray,
    cm: CoarseMap,
    pose: FloatArray,
    t_s: float,
    range_m: float,
    hfov_rad: float,
) -> FloatArray:
    """When each coarse cell was last in a camera's view, after the robots at ``pose``
    (N, 3) looked at ``t_s`` (a new array; ``seen_s`` of another shape: never seen).

    Examples
    --------
    >>> import math
    >>> import numpy as np
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.world import OccupancyGrid
    >>> walls = np.zeros((20, 40), dtype=bool)
    >>> cm = coarse_map(build_costmap(OccupancyGrid(walls, ~walls, resolution_m=0.25), 0.1), 0.25)
    >>> s = seen_update(np.zeros((0, 0)), cm, np.array([[1.0, 2.5, 0.0]]), 7.0, 3.0,
    ...                 math.radians(51.0))
    >>> float(s[10, 8]), float(s[10, 0])  # 1 m ahead seen at 7 s; behind it never
    (7.0, -inf)
    """
    out = np.full(cm.shape, -np.inf) if seen_s.shape != cm.shape else seen_s.copy()
    if len(pose):
        rows, cols = cone_coverage(cm, pose, range_m, hfov_rad)
        out[rows, cols] = t_s
    return out


def fire_region(cm: CoarseMap, spots_xy_m: FloatArray, scout_m: float) -> IntArray:
    """Floor cells within ``scout_m`` of a fire's spots (S, 2) through open floor: the
    band number (Hc, Wc) of each (0: a spot's cell, k: k cells out by 8-neighbour
    steps through floor; -1: outside).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.world import OccupancyGrid
    >>> occ = np.zeros((8, 16), dtype=bool); occ[:, 8] = True  # a wall at x = 2 m
    >>> cm = coarse_map(build_costmap(OccupancyGrid(occ, ~occ, resolution_m=0.25), 0.1), 0.25)
    >>> band = fire_region(cm, np.array([[1.125, 1.125]]), 1.5)
    >>> band[3, 4], band[3, 6], band[3, 7], band[3, 9]  # the wall stops it
    (np.int64(0), np.int64(2), np.int64(3), np.int64(-1))
    """
    band = np.full(cm.shape, -1, dtype=np.int64)
    s = np.asarray(spots_xy_m, dtype=float).reshape(-1, 2)
    if len(s) == 0:
        return band
    rc = cm.cell_of(s)
    cur = np.zeros(cm.shape, dtype=bool)
    cur[rc[:, 0], rc[:, 1]] = True
    cur &= cm.floor | cur
    band[cur] = 0
    box = np.ones((3, 3), dtype=bool)
    for k in range(1, max(1, round(scout_m / cm.cell_m)) + 1):
        nxt = ndi.binary_dilation(cur, structure=box) & cm.floor & ~cm.opaque
        new = nxt & (band < 0)
        if not new.any():
            break
        band[new] = k
        cur = nxt
    return band


def scout_goals(
    cm: CoarseMap,
    seen_s: FloatArray,
    t_s: float,
    spots_xy_m: FloatArray,
    robots_xy_m: FloatArray,
    avoid: BoolArray,
    scout_m: float,
    stale_s: float,
    near_m: float,
    far_m: float,
) -> FloatArray:
    """Where each robot (M, 2) should stand to look at the fire it does not see.

    The place to look at: a floor cell of :func:`fire_region` no camera has seen for
    ``stale_s`` (before ``t_s``), in the nearest band to the spots, the nearest such to
    the robot; each robot takes another place (farther than ``far_m`` from the places
    the robots before it took). The goal: a standable cell ``near_m`` to ``far_m`` from
    it, in clear sight, not in ``avoid`` (Hc, Wc), nearest by travel to the robot
    (:func:`._coverage.viewpoints`).

    Returns
    -------
    ndarray, shape (M, 2)
        Goal points [m]; NaN rows: nothing left to look at, or no cell to look from.
    """
    robots = np.asarray(robots_xy_m, dtype=float).reshape(-1, 2)
    out = np.full((len(robots), 2), np.nan)
    band = fire_region(cm, spots_xy_m, scout_m)
    seen = np.full(cm.shape, -np.inf) if seen_s.shape != cm.shape else seen_s
    stale = (band >= 0) & (t_s - seen >= stale_s) & cm.floor
    for i in range(len(robots)):
        if not stale.any():
            break
        b = band[stale].min()
        cand = np.argwhere(stale & (band == b))
        rc = cm.cell_of(robots[i : i + 1])
        pick = cand[int(np.argmin(np.hypot(*(cand - rc).T)))]
        view = viewpoints(
            cm,
            ~stale,
            pick[None],
            0.0,
            near_m,
            far_m,
            toward=rc,
            avoid=avoid,
        )[0]
        if not np.array_equal(view, pick) and cm.standable[view[0], view[1]]:
            out[i] = cm.goal_xy(view[None])[0]
        # the next robot looks elsewhere
        xy = cm.centre_xy(np.argwhere(stale))
        p = cm.centre_xy(pick[None])[0]
        far = np.hypot(xy[:, 0] - p[0], xy[:, 1] - p[1]) > far_m
        idx = np.argwhere(stale)
        stale = np.zeros_like(stale)
        stale[idx[far, 0], idx[far, 1]] = True
    return out
