"""Which ``person`` detections can be a person: the team's check against its floor plan.

:func:`firefleet.perception.thermal.detect` names a person any warm region of a person's
size whose mean lies in the band of clothed skin (28-40 C). In a burning building the
walls the hot gas heats fall in that band too: on mission-office seed 1 (the code at
22b5e8e) 1,653 of the run's 1,655 person detections were the corridor's wall opposite
the fire room's door (33-63 C at their hottest pixel), and a robot stood 360 s
confirming them. The team knows what the detector does not: the floor plan (the plans
a fire brigade carries). A detection is kept only when

- its position on the map lies at least ``person_wall_m`` (0.15 m) from every wall of
  the team's coarse plan (``_coverage.CoarseMap.opaque``; off the map counts as wall):
  a standing person's centre is half a body's depth (chest depth about 0.25-0.3 m,
  ISO 7250-1) from the wall they lean on, while a warm wall's region, placed at the
  depth the stereo rig measures, lies on the wall's face or just off it (mission-office
  seeds 0-4 at 22b5e8e: the median false detection 0.03-0.05 m from the face, 90-98 %
  of them nearer than 0.1 m, the rest up to 0.15 m when seen along a corridor from
  5 m, where the region's median depth falls short of the wall; the true ones, people
  in the rooms, placed within 0.06 m of the person); mission-smoke's person in the
  corridor stands 0.35 m from the wall's face;
- the line from the robot to it crosses no wall (a camera does not see through one).

A region's hottest pixel is no test: a person standing before a hot wall is one region
with it (mission-smoke seed 3: the people in the corridor by the burning room read
50-51 C at their hottest pixel, their mean in the detector's band), so a bound on the
peak (tried: 40 C, skin's limit) dropped 50 of 296 true detections of one of them and
delayed their finding from 217 s to 315 s.

References
----------
ISO 7250-1:2017, Basic human body measurements for technological design.
"""

from __future__ import annotations

import math

import numpy as np

from firefleet._typing import BoolArray, FloatArray
from firefleet.control.mission._coverage import CoarseMap, clear_sight
from firefleet.control.mission._params import TacticsParams
from firefleet.errors import InputError

__all__ = ["confirm_sight", "person_plausible", "wall_distance"]


def wall_distance(cm: CoarseMap, xy_m: FloatArray, reach_m: float) -> FloatArray:
    """Distance [m] from each point (K, 2) to the nearest opaque coarse cell (a square of
    side ``cm.cell_m``; a cell off the map counts as opaque), searched within ``reach_m``
    (farther: ``inf``); 0 inside one.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> occ = np.zeros((40, 80), bool); occ[:, 40:45] = True   # a wall x 2.0-2.25 m
    >>> cm = coarse_map(build_costmap(OccupancyGrid(occ, ~occ, 0.05), 0.2), 0.25)
    >>> pts = np.array([[1.95, 1.0], [2.1, 1.0], [2.5, 1.0], [1.0, 1.0]])
    >>> wall_distance(cm, pts, 0.5).round(3).tolist()
    [0.05, 0.0, 0.25, inf]
    """
    p = np.asarray(xy_m, dtype=float).reshape(-1, 2)
    out = np.full(len(p), np.inf)
    if len(p) == 0:
        return out
    k = max(1, math.ceil(reach_m / cm.cell_m))
    hc, wc = cm.shape
    rc = cm.grid.cell_of(p) // cm.factor  # unclipped: off the map is off the grid
    dr, dc = np.mgrid[-k : k + 1, -k : k + 1]
    r = rc[:, 0, None] + dr.ravel()[None]
    c = rc[:, 1, None] + dc.ravel()[None]
    inside = (r >= 0) & (r < hc) & (c >= 0) & (c < wc)
    opaque = np.ones(r.shape, dtype=bool)
    opaque[inside] = cm.opaque[r[inside], c[inside]]
    centre = cm.centre_xy(np.stack([r, c], axis=-1))
    half = 0.5 * cm.cell_m
    gx = np.maximum(np.abs(p[:, None, 0] - centre[..., 0]) - half, 0.0)
    gy = np.maximum(np.abs(p[:, None, 1] - centre[..., 1]) - half, 0.0)
    d = np.where(opaque, np.hypot(gx, gy), np.inf).min(axis=1)
    out = np.where(d <= reach_m, d, np.inf)
    return out


def person_plausible(
    cm: CoarseMap,
    robot_xy_m: FloatArray,
    person_xy_m: FloatArray,
    wall_m: float,
) -> BoolArray:
    """Which person detections can be a person (module notes), shape (K,).

    Parameters
    ----------
    cm : CoarseMap
        The team's plan.
    robot_xy_m : ndarray, shape (K, 2)
        Where the robot that made each detection stood (its estimate) [m].
    person_xy_m : ndarray, shape (K, 2)
        The detections on the map [m].
    wall_m : float
        Nearest a person's centre stands to a wall [m].

    Returns
    -------
    ndarray of bool, shape (K,)

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import load_map
    >>> from firefleet.control.mission import TacticsParams, tactics_init
    >>> cm = tactics_init(load_map("office"), [[16.0, 4.7, 0.0]], TacticsParams()).coarse
    >>> robot = np.array([[17.9, 4.6]] * 3)
    >>> people = np.array([[17.6, 4.6], [16.4, 4.28], [12.0, 2.0]])
    >>> person_plausible(cm, robot, people, 0.15).tolist()
    [True, False, False]
    """
    xy = np.asarray(person_xy_m, dtype=float).reshape(-1, 2)
    robot = np.asarray(robot_xy_m, dtype=float).reshape(-1, 2)
    if robot.shape != xy.shape:
        raise InputError(f"robot_xy_m must match person_xy_m {xy.shape}, got {robot.shape}")
    ok = np.ones(len(xy), dtype=bool)
    if len(xy) == 0:
        return ok
    ok &= wall_distance(cm, xy, max(wall_m, cm.cell_m)) >= wall_m
    if ok.any():
        idx = np.flatnonzero(ok)
        ok[idx] = clear_sight(cm, robot[idx], xy[idx])
    return ok


def confirm_sight(
    cm: CoarseMap, robot_xy_m: FloatArray, victim_xy_m: FloatArray, params: TacticsParams
) -> BoolArray:
    """Whether a confirmer standing at each robot position (M, 2) can confirm its victim
    (M, 2): from the camera's nearest range for a whole person (``sensing_near_m``, or
    half a metre inside the confirmation radius when that is nearer: the plan's
    viewpoints lie from ``min(sensing_near_m + 0.25, confirm_radius_m - 0.25)`` on) to
    ``confirm_radius_m`` away, with no wall between (the confirmer turns to face the
    victim where it stands).

    A confirmer held up on its way (a teammate in a door, a detour) used to settle
    where it stood wherever that was; on mission-office seed 1 one settled 6 m from its
    victim, behind a wall, and stood there for the last 350 s.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import load_map
    >>> from firefleet.control.mission import TacticsParams, tactics_init
    >>> p = TacticsParams(confirm_radius_m=3.0)
    >>> cm = tactics_init(load_map("office"), [[1.0, 1.5, 0.0]], p).coarse
    >>> robot = np.array([[12.5, 4.5], [10.0, 4.5], [12.2, 3.0], [17.9, 4.6]])
    >>> confirm_sight(cm, robot, np.array([[12.0, 2.0]] * 4), p).tolist()
    [True, False, False, False]
    """
    near_m = min(params.sensing_near_m, params.confirm_radius_m - 0.5)
    a = np.asarray(robot_xy_m, dtype=float).reshape(-1, 2)
    b = np.asarray(victim_xy_m, dtype=float).reshape(-1, 2)
    d = np.hypot(*(b - a).T)
    out: BoolArray = (d >= near_m) & (d <= params.confirm_radius_m)
    if out.any():
        idx = np.flatnonzero(out)
        out[idx] = clear_sight(cm, a[idx], b[idx])
    return out
