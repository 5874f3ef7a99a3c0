"""The team's ledger of the water it has put down: which floor cells its sprays soaked.

A robot knows where it stood (its pose estimate), where its nozzle pointed, how long it
sprayed and at what flow; the ledger spreads each spray's litres equally over the open
cells of the cone in front of it (centre within the nozzle's reach and half-angle, in
line of sight), as the water falls (:func:`firefleet.world.spray_step`'s model, on the
team's coarse grid). A cell whose water per area reached ``critical_l_m2`` is *soaked*:
its fire is out and its fuel no longer ignites, so more water there is wasted. The
fighters aim at flames on cells not yet soaked (:mod:`._step`), and a flame seen on a
soaked cell is pushed along the camera's ray to the first cell not soaked: the flames
are behind the water line (:mod:`._knowledge`).

References
----------
D. Drysdale, An Introduction to Fire Dynamics, 3rd ed., Wiley 2011, ch. 9-10 (the
critical water per area, the constant ``world.SprayParams.critical_l_m2`` holds).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.mission._coverage import CoarseMap, line_of_sight

__all__ = [
    "add_water",
    "aim_wets",
    "cone_cells",
    "front_aim",
    "soaked_at",
    "spray_ledger",
    "wets_flames",
]


def cone_cells(
    cm: CoarseMap, pose: FloatArray, range_m: float, half_angle_rad: float
) -> tuple[IntArray, IntArray]:
    """The coarse floor cells a nozzle at ``pose`` (x [m], y [m], heading [rad]) wets.

    Parameters
    ----------
    cm : CoarseMap
    pose : ndarray, shape (3,)
    range_m, half_angle_rad : float
        The jet's reach [m] and the cone's half-angle [rad].

    Returns
    -------
    rows, cols : ndarray of int, shape (K,)
        Cells whose centre lies within reach and angle, in line of sight.

    Examples
    --------
    >>> import math
    >>> import numpy as np
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.world import OccupancyGrid
    >>> walls = np.zeros((20, 40), dtype=bool)
    >>> cm = coarse_map(build_costmap(OccupancyGrid(walls, ~walls, resolution_m=0.25), 0.1), 0.25)
    >>> r, c = cone_cells(cm, np.array([1.0, 2.5, 0.0]), 3.0, math.radians(15.0))
    >>> int(len(r)), int(c.min()), int(c.max())  # 38 cells of 1/16 m^2: the cone's 2.36 m^2
    (38, 6, 15)
    """
    h, w = cm.shape
    reach = math.ceil(range_m / cm.cell_m) + 1
    r0, c0 = (int(v) for v in cm.cell_of(np.asarray(pose[:2], dtype=float)))
    rr, cc = np.mgrid[
        max(r0 - reach, 0) : min(r0 + reach + 1, h), max(c0 - reach, 0) : min(c0 + reach + 1, w)
    ]
    rows, cols = rr.ravel(), cc.ravel()
    keep = cm.floor[rows, cols]
    rows, cols = rows[keep], cols[keep]
    xy = cm.centre_xy(np.stack([rows, cols], axis=-1))
    d = xy - pose[:2]
    dist = np.hypot(d[:, 0], d[:, 1])
    off = np.abs((np.arctan2(d[:, 1], d[:, 0]) - pose[2] + np.pi) % (2 * np.pi) - np.pi)
    sel = (dist <= range_m) & (off <= half_angle_rad) & (dist > 0.0)
    rows, cols, xy = rows[sel], cols[sel], xy[sel]
    if len(rows):
        ok = line_of_sight(cm, np.repeat(pose[None, :2], len(rows), 0), xy)
        rows, cols = rows[ok], cols[ok]
    return rows, cols


def spray_ledger(
    wet_l_m2: FloatArray,
    cm: CoarseMap,
    pose: FloatArray,
    spraying: BoolArray,
    litres: float,
    range_m: float,
    half_angle_rad: float,
) -> FloatArray:
    """The ledger after each spraying robot put ``litres`` on its cone (module notes).

    Parameters
    ----------
    wet_l_m2 : ndarray, shape (Hc, Wc) or (0, 0)
        Water per area so far [L/m^2] ((0, 0): none yet).
    cm : CoarseMap
    pose : ndarray, shape (N, 3)
        Estimated poses.
    spraying : ndarray of bool, shape (N,)
    litres : float
        Water each sprays meanwhile [L] (flow times the time the order holds).
    range_m, half_angle_rad : float

    Returns
    -------
    ndarray, shape (Hc, Wc)
        A new array (the input is not changed).
    """
    wet = np.zeros(cm.shape) if wet_l_m2.shape != cm.shape else wet_l_m2.copy()
    area = cm.cell_m**2
    for i in map(int, np.flatnonzero(spraying)):
        rows, cols = cone_cells(cm, pose[i], range_m, half_angle_rad)
        if len(rows):
            np.add.at(wet, (rows, cols), litres / (len(rows) * area))
    return wet


def soaked_at(wet_l_m2: FloatArray, cm: CoarseMap, xy_m: FloatArray, soak_l_m2: float) -> BoolArray:
    """Whether the cells under the points (K, 2) [m] got ``soak_l_m2`` or more."""
    xy = np.asarray(xy_m, dtype=float).reshape(-1, 2)
    if wet_l_m2.shape != cm.shape or len(xy) == 0:
        return np.zeros(len(xy), dtype=bool)
    rc = cm.cell_of(xy)
    out: BoolArray = wet_l_m2[rc[:, 0], rc[:, 1]] >= soak_l_m2
    return out


def add_water(
    wet_l_m2: FloatArray, cm: CoarseMap, rows: IntArray, cols: IntArray, litres: float
) -> FloatArray:
    """The ledger after ``litres`` fell, split equally, on the cells (K,) of one cone
    (a new array; (0, 0): a new ledger)."""
    wet = np.zeros(cm.shape) if wet_l_m2.shape != cm.shape else wet_l_m2.copy()
    if len(rows):
        np.add.at(wet, (rows, cols), litres / (len(rows) * cm.cell_m**2))
    return wet


def wets_flames(
    wet_l_m2: FloatArray,
    cm: CoarseMap,
    rows: IntArray,
    cols: IntArray,
    flames_xy_m: FloatArray,
    soak_l_m2: float,
    radius_m: float,
) -> bool:
    """Whether a cone's cells (K,) hold a cell not yet soaked within ``radius_m`` of a
    believed flame (F, 2) [m]: the spray would do some good (a flame behind a wall
    the cone stops at, or on cells already soaked, is no reason to spray)."""
    f = np.asarray(flames_xy_m, dtype=float).reshape(-1, 2)
    if len(rows) == 0 or len(f) == 0:
        return False
    if wet_l_m2.shape == cm.shape:
        dry = wet_l_m2[rows, cols] < soak_l_m2
        rows, cols = rows[dry], cols[dry]
    xy = cm.centre_xy(np.stack([rows, cols], axis=-1))
    d = np.hypot(xy[:, None, 0] - f[None, :, 0], xy[:, None, 1] - f[None, :, 1])
    return bool((d <= radius_m).any())


def aim_wets(
    wet_l_m2: FloatArray,
    cm: CoarseMap,
    xy_m: FloatArray,
    aim_xy_m: FloatArray,
    flames_xy_m: FloatArray,
    reach_m: float,
    half_angle_rad: float,
    soak_l_m2: float,
    front_m: float,
) -> bool:
    """Whether a nozzle at ``xy_m`` (2,) [m] turned to ``aim_xy_m`` (2,) would wet a cell
    the ledger does not hold soaked within ``front_m`` of a believed flame (F, 2): a
    fighter's shot (:func:`wets_flames` on that cone, the test its spray makes).

    A flame merely within reach is no shot: the cells about it may be soaked, or out
    of the jet's sight past a corner (mission-warehouse seed 3: a fighter stood from
    280 s to the end at a rack's corner, 2.4 m from a soaked flame, the dry front 3.3 m
    off past the corner, counted as having a shot, never re-slotted, never spraying).

    Examples
    --------
    >>> import math
    >>> import numpy as np
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.world import OccupancyGrid
    >>> walls = np.zeros((20, 40), dtype=bool)
    >>> cm = coarse_map(build_costmap(OccupancyGrid(walls, ~walls, resolution_m=0.25), 0.1), 0.25)
    >>> flame, me = np.array([[4.0, 2.5]]), np.array([2.0, 2.5])
    >>> args = (3.0, math.radians(15.0), 1.3, 0.5)
    >>> aim_wets(np.zeros((0, 0)), cm, me, flame[0], flame, *args)  # a dry flame 2 m off
    True
    >>> soaked = np.full(cm.shape, 2.0)
    >>> aim_wets(soaked, cm, me, flame[0], flame, *args)  # in reach, but all soaked
    False
    """
    heading = math.atan2(float(aim_xy_m[1] - xy_m[1]), float(aim_xy_m[0] - xy_m[0]))
    pose = np.array([float(xy_m[0]), float(xy_m[1]), heading])
    rows, cols = cone_cells(cm, pose, reach_m, half_angle_rad)
    return wets_flames(wet_l_m2, cm, rows, cols, flames_xy_m, soak_l_m2, front_m)


def front_aim(
    wet_l_m2: FloatArray,
    cm: CoarseMap,
    pose: FloatArray,
    flames_xy_m: FloatArray,
    reach_m: float,
    half_angle_rad: float,
    soak_l_m2: float,
    front_m: float,
) -> FloatArray | None:
    """Where a nozzle at ``pose`` should point: the front cell whose bearing puts the
    fronts of the most believed flames in the cone (then the most front cells), or None
    when no front cell is in reach and in sight.

    A front cell is an open cell within ``front_m`` of a believed flame (F, 2) that the
    ledger does not hold soaked: a burning cell at the flames, or unburnt fuel the
    front reaches next (wetting it makes a firebreak: a soaked cell no longer ignites).

    The flames come first because a count of cells rewards open floor, not fire: a
    flame spot a detection placed short, on a wall or in the corridor before a door
    (where the camera's range falls), has the corridor's open cells about it, more than
    the wedge of the room the door lets the jet into (mission-office seed 0, 400-450 s:
    a fighter at the door aimed down the corridor, 1.0 m from any burning cell, while a
    bearing through the door held 14 burning cells, the nearer ones by the flames the
    team had put there).

    Parameters
    ----------
    wet_l_m2 : ndarray, shape (Hc, Wc) or (0, 0)
    cm : CoarseMap
    pose : ndarray, shape (3,)
    flames_xy_m : ndarray, shape (F, 2)
    reach_m, half_angle_rad : float
        The jet's reach [m] and the cone's half-angle [rad].
    soak_l_m2, front_m : float

    Returns
    -------
    ndarray, shape (2,) or None
        The aim point [m]: the front cell on whose bearing the cone is best.

    Examples
    --------
    >>> import math
    >>> import numpy as np
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.world import OccupancyGrid
    >>> walls = np.zeros((40, 40), dtype=bool)
    >>> cm = coarse_map(build_costmap(OccupancyGrid(walls, ~walls, resolution_m=0.25), 0.1), 0.25)
    >>> flames = np.array([[4.0, 6.0], [4.0, 4.0], [4.5, 4.5]])  # one north, two east
    >>> aim = front_aim(np.zeros((0, 0)), cm, np.array([2.0, 4.0, 0.0]), flames, 3.0,
    ...     math.radians(15.0), 1.3, 0.5)
    >>> round(math.degrees(math.atan2(aim[1] - 4.0, aim[0] - 2.0)))  # both east flames' fronts
    10
    """
    f = np.asarray(flames_xy_m, dtype=float).reshape(-1, 2)
    if len(f) == 0:
        return None
    # the flames whose front can lie in reach
    f = f[np.hypot(f[:, 0] - pose[0], f[:, 1] - pose[1]) <= reach_m + front_m]
    if len(f) == 0:
        return None
    h, w = cm.shape
    n = math.ceil(reach_m / cm.cell_m) + 1
    r0, c0 = (int(v) for v in cm.cell_of(np.asarray(pose[:2], dtype=float)))
    # the window's dry floor cells in reach with a flame within front_m (_front_cells)
    r_lo, r_hi, c_lo, c_hi = max(r0 - n, 0), min(r0 + n + 1, h), max(c0 - n, 0), min(c0 + n + 1, w)
    size = max(r_hi - r_lo, 0) * max(c_hi - c_lo, 0)
    xy = np.empty((size, 2))
    near = np.empty((size, len(f)), dtype=bool)
    has_wet = wet_l_m2.shape == cm.shape
    grid = cm.grid
    k = _front_cells(
        float(pose[0]), float(pose[1]), r_lo, r_hi, c_lo, c_hi, cm.floor,
        wet_l_m2 if has_wet else np.zeros((1, 1)), has_wet, soak_l_m2,
        np.ascontiguousarray(f), front_m, reach_m, float(cm.cell_m), float(grid.origin_m[0]),
        float(grid.origin_m[1]), float(grid.resolution_m), int(grid.shape[0]), int(cm.factor),
        xy, near,
    )  # fmt: skip
    xy, near = xy[:k], near[:k]
    if len(xy) == 0:
        return None
    ok = line_of_sight(cm, np.repeat(pose[None, :2], len(xy), 0), xy)
    xy, near = xy[ok], near[ok]
    if len(xy) == 0:
        return None
    bearing = np.arctan2(xy[:, 1] - pose[1], xy[:, 0] - pose[0])
    off = np.abs((bearing[:, None] - bearing[None, :] + np.pi) % (2 * np.pi) - np.pi)
    inside = (off <= half_angle_rad).astype(np.float64)  # (cone on a cell's bearing, cell)
    held = inside.sum(axis=1)
    served = ((inside @ near.astype(np.float64)) > 0.0).sum(axis=1)  # flames whose front
    out: FloatArray = xy[int(np.argmax(served * (len(xy) + 1) + held))]
    return out


@numba.njit(cache=True)
def _front_cells(
    px: float,
    py: float,
    r_lo: int,
    r_hi: int,
    c_lo: int,
    c_hi: int,
    floor: BoolArray,
    wet: FloatArray,
    has_wet: bool,
    soak_l_m2: float,
    flames: FloatArray,
    front_m: float,
    reach_m: float,
    cell_m: float,
    ox: float,
    oy: float,
    res: float,
    rows: int,
    factor: int,
    out_xy: FloatArray,
    out_near: BoolArray,
) -> int:  # pragma: no cover - compiled
    """:func:`front_aim`'s candidate cells in one pass, the array form's arithmetic
    (:meth:`CoarseMap.centre_xy`, ``np.hypot``) in its order (row-major): the floor
    cells of rows ``[r_lo, r_hi)`` and columns ``[c_lo, c_hi)`` not soaked (``has_wet``),
    within ``reach_m`` of the nozzle (``px``, ``py``) and no nearer than ``cell_m``,
    with a flame within ``front_m``: their centres into ``out_xy``, which flames into
    ``out_near``; how many."""
    k = 0
    for r in range(r_lo, r_hi):
        for c in range(c_lo, c_hi):
            if not floor[r, c] or (has_wet and not wet[r, c] < soak_l_m2):
                continue
            fr = (np.float64(r) + 0.5) * factor - 0.5
            fc = (np.float64(c) + 0.5) * factor - 0.5
            x = ox + (fc + 0.5) * res
            y = oy + (np.float64(rows - 1) - fr + 0.5) * res
            dist = np.hypot(x - px, y - py)
            if not (dist <= reach_m and dist >= cell_m):
                continue
            anyf = False
            for j in range(flames.shape[0]):
                hit = np.hypot(x - flames[j, 0], y - flames[j, 1]) <= front_m
                out_near[k, j] = hit
                anyf = anyf or hit
            if anyf:
                out_xy[k, 0] = x
                out_xy[k, 1] = y
                k += 1
    return k
