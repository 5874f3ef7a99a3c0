"""Where explorers look from: viewpoints chosen by what a turn there would cover.

The team knows the floor plan, so what a robot's camera would cover from a place is
known before it goes there. A robot that stops at a place and turns once covers the
floor ``near_m`` to ``range_m`` from it in line of sight (the camera names no person
nearer than ``near_m``: :func:`._coverage.in_view`). The *view table* holds, for a
lattice of standable coarse cells (the candidates), the coarse cells such a turn covers
(rays every half cell of arc at full range, samples every half cell, each ray up to and
including its first opaque cell, as :func:`._coverage.cone_coverage` samples the cone),
as a sparse matrix (candidates x cells) and its transpose, built once per map.

A candidate's *gain* is the uncovered floor it would cover [m^2]. Explorers choose
candidates one after another (Burgard et al. 2005, algorithm 1): each time the pair
(robot, candidate) of the highest coverage rate, ``gain / (travel / v + turn_s)``
[m^2/s] (the gain over the time to drive there and turn), and the floor the chosen
candidate covers is then claimed: it no longer counts in any other candidate's gain.
This is Burgard's utility discount with the discount computed, not modelled (their
``P(d) = 1 - d / range`` stands for the overlap of two robots' views; here the overlap
is known from the plan), so robots spread over the building's exits and rooms instead of
following each other. In a passage narrower than the camera's near limit this puts the
viewpoint on the passage's axis, 2-4 m back from the floor it covers; at a junction a
turn covers every branch's first metres.

Candidates: the standable cells whose goal point lies ``clear_m`` from the walls, or,
in a narrower place, as far as the place allows (a goal by a wall is one the navigation
may never reach: on the maze a robot stood 0.23 m from such a goal for 30 s). On large
maps one per ``s x s`` block of coarse cells (the block's clearest, ``s`` the least
making at most ``max_candidates``), so a passage one cell wide keeps a candidate every
``s`` cells.

References
----------
W. Burgard, M. Moors, C. Stachniss, F. E. Schneider, "Coordinated multi-robot
exploration", IEEE Transactions on Robotics 21(3), 2005. H. H. Gonzalez-Banos, J.-C.
Latombe, "Navigation strategies for exploring indoor environments", International
Journal of Robotics Research 21(10-11), 2002 (next-best view: the gain of a candidate
view discounted by the travel to it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
import scipy.ndimage as ndi

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.mission._coverage import CoarseMap

__all__ = ["ViewTable", "choose_views", "scan_heading", "view_gains", "view_table"]


@dataclass(frozen=True, eq=False)
class ViewTable:
    """What a turn at each candidate viewpoint covers (module notes).

    Attributes
    ----------
    cand : ndarray of int, shape (C,)
        Each candidate's flat coarse cell (``row * Wc + col``).
    xy_m : ndarray, shape (C, 2)
        Where a robot stands there (the cell's goal point) [m].
    index : ndarray of int, shape (Hc Wc,)
        The candidate of each flat coarse cell (-1: none).
    ptr, cells : ndarray of int (int64, int32)
        Sparse rows: candidate ``c`` covers the flat cells ``cells[ptr[c]:ptr[c + 1]]``.
    tptr, tcand : ndarray of int (int64, int32)
        The transpose: cell ``k`` is covered from the candidates
        ``tcand[tptr[k]:tptr[k + 1]]``.
    cell_m2 : float
        A coarse cell's area [m^2].
    """

    cand: IntArray
    xy_m: FloatArray
    index: IntArray
    ptr: IntArray
    cells: np.ndarray
    tptr: IntArray
    tcand: np.ndarray
    cell_m2: float

    def __len__(self) -> int:
        return int(self.cand.shape[0])

    def row(self, c: int) -> IntArray:
        """The flat cells candidate ``c`` covers."""
        out: IntArray = self.cells[self.ptr[c] : self.ptr[c + 1]]
        return out


def _clearance(cm: CoarseMap) -> FloatArray:
    """Distance [m] (Hc, Wc) from each coarse cell's goal point to the nearest occupied
    map cell (0 where not standable)."""
    occ = np.asarray(cm.grid.occupied, dtype=bool)
    edt: FloatArray = ndi.distance_transform_edt(~occ) * cm.grid.resolution_m
    out = np.zeros(cm.shape)
    ok = cm.standable
    g = cm.goal_cell[ok]
    out[ok] = edt[g[:, 0], g[:, 1]]
    return out


def _lattice(cm: CoarseMap, clear_m: float, max_candidates: int) -> IntArray:
    """Candidate cells (C, 2) (module notes): the standable cells whose goal point is
    ``clear_m`` from the walls, or as far as the cells within half a metre allow (a
    passage's middle: a goal by a wall is hard to reach); on large maps the clearest of
    each ``s x s`` block (nearest its centre among equals)."""
    clear = _clearance(cm)
    k = 2 * max(1, round(0.5 / cm.cell_m)) + 1
    local = ndi.maximum_filter(clear, size=k, mode="constant")
    ok = cm.standable & (clear >= np.minimum(clear_m, local - 0.5 * cm.grid.resolution_m))
    rc = np.argwhere(ok)
    s = max(1, math.ceil(math.sqrt(len(rc) / max(max_candidates, 1))))
    if s == 1:
        return rc.astype(np.int64)
    block = (rc[:, 0] // s) * (cm.shape[1] // s + 1) + rc[:, 1] // s
    centre = (rc // s) * s + (s - 1) / 2.0
    d2 = ((rc - centre) ** 2).sum(axis=1)
    order = np.lexsort((d2, -clear[rc[:, 0], rc[:, 1]], block))
    first = np.ones(len(order), dtype=bool)
    first[1:] = block[order][1:] != block[order][:-1]
    return rc[np.sort(order[first])].astype(np.int64)


@numba.njit(cache=True)
def _scan_rows(
    origin_xy: FloatArray,
    opaque: BoolArray,
    fine_h: int,
    fine_w: int,
    ox: float,
    oy: float,
    res: float,
    factor: int,
    ray_dx: FloatArray,
    ray_dy: FloatArray,
    dist: FloatArray,
    near_m: float,
    cell_m: float,
    out_ptr: IntArray,
    out_cells: IntArray,
    fill: bool,
) -> int:  # pragma: no cover - compiled
    """Count (``fill`` False: into ``out_ptr[c + 1]``) or write (``fill`` True: from
    ``out_ptr[c]``) the distinct coarse cells each origin's turn covers; returns the
    total count."""
    hc, wc = opaque.shape
    stamp = np.full(hc * wc, -1, dtype=np.int64)
    total = 0
    for c in range(origin_xy.shape[0]):
        x0 = origin_xy[c, 0]
        y0 = origin_xy[c, 1]
        pos = out_ptr[c] if fill else 0
        count = 0
        for r in range(ray_dx.shape[0]):
            for s in range(dist.shape[0]):
                d = dist[s]
                x = x0 + d * ray_dx[r]
                y = y0 + d * ray_dy[r]
                fc = math.floor((x - ox) / res)
                fr = fine_h - 1 - math.floor((y - oy) / res)
                if fr < 0 or fr >= fine_h or fc < 0 or fc >= fine_w:
                    break  # off the map: nothing beyond
                k = (fr // factor) * wc + fc // factor
                stop = opaque[fr // factor, fc // factor] and d >= cell_m
                if d >= near_m and stamp[k] != c:
                    stamp[k] = c
                    if fill:
                        out_cells[pos] = k
                        pos += 1
                    count += 1
                if stop:
                    break  # the first opaque cell is seen, nothing behind it
        if not fill:
            out_ptr[c + 1] = count
        total += count
    return total


def view_table(
    cm: CoarseMap,
    range_m: float,
    near_m: float,
    clear_m: float = 0.4,
    max_candidates: int = 12000,
) -> ViewTable:
    """The view table of a coarse map (module notes).

    Parameters
    ----------
    cm : CoarseMap
    range_m, near_m : float
        The camera's coverage from ``near_m`` to ``range_m`` [m].
    clear_m : float
        Wanted distance of a candidate from the walls [m] (less in narrower places:
        their middle).
    max_candidates : int
        Most candidates (the lattice thins on larger maps).

    Returns
    -------
    ViewTable

    Examples
    --------
    An empty 6 m x 6 m room: from its middle, a turn covers the floor 2 to 2.5 m away
    (the room's walls 3 m off), about the ring's area.

    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> occ = np.zeros((120, 120), bool)
    >>> cm = coarse_map(build_costmap(OccupancyGrid(occ, ~occ, 0.05), 0.2), 0.25)
    >>> t = view_table(cm, 2.5, 2.0)
    >>> c = int(t.index[12 * 24 + 12])
    >>> area = len(t.row(c)) * t.cell_m2
    >>> bool(np.pi * (2.5**2 - 2.0**2) < area < np.pi * (2.85**2 - 1.65**2))
    True
    """
    rc = _lattice(cm, clear_m, max_candidates)
    hc, wc = cm.shape
    xy = cm.goal_xy(rc) if len(rc) else np.zeros((0, 2))
    step = 0.5 * cm.cell_m
    n_rays = max(8, math.ceil(2.0 * math.pi * range_m / step))
    ang = np.arange(n_rays) * (2.0 * math.pi / n_rays)
    dist = (np.arange(1, math.floor(range_m / step) + 1) * step).astype(np.float64)
    grid = cm.grid
    fh, fw = grid.shape
    ptr = np.zeros(len(rc) + 1, dtype=np.int64)
    xy_c = np.ascontiguousarray(xy, dtype=np.float64)
    opaque = np.ascontiguousarray(cm.opaque)
    ox, oy, res = float(grid.origin_m[0]), float(grid.origin_m[1]), float(grid.resolution_m)
    dx, dy = np.cos(ang), np.sin(ang)

    def run(out_ptr: IntArray, out_cells: np.ndarray, fill: bool) -> None:
        _scan_rows(
            xy_c, opaque, int(fh), int(fw), ox, oy, res, int(cm.factor), dx, dy, dist,
            float(near_m), float(cm.cell_m), out_ptr, out_cells, fill,
        )  # fmt: skip

    run(ptr, np.zeros(0, dtype=np.int32), False)
    ptr = np.cumsum(ptr)
    cells = np.zeros(int(ptr[-1]), dtype=np.int32)
    run(ptr, cells, True)
    owner = np.repeat(np.arange(len(rc), dtype=np.int32), np.diff(ptr))
    order = np.argsort(cells, kind="stable")
    tcand = owner[order]
    tptr = np.zeros(hc * wc + 1, dtype=np.int64)
    np.cumsum(np.bincount(cells, minlength=hc * wc), out=tptr[1:])
    cand = rc[:, 0] * wc + rc[:, 1]
    index = np.full(hc * wc, -1, dtype=np.int64)
    index[cand] = np.arange(len(rc))
    return ViewTable(
        cand=cand.astype(np.int64),
        xy_m=np.asarray(xy, dtype=float).reshape(-1, 2),
        index=index,
        ptr=ptr,
        cells=cells,
        tptr=tptr,
        tcand=tcand,
        cell_m2=cm.cell_m**2,
    )


@numba.njit(cache=True)
def _gains(ptr: IntArray, cells: IntArray, weight: FloatArray) -> FloatArray:  # pragma: no cover
    out = np.zeros(ptr.shape[0] - 1)
    for c in range(out.shape[0]):
        s = 0.0
        for j in range(ptr[c], ptr[c + 1]):
            s += weight[cells[j]]
        out[c] = s
    return out


def view_gains(table: ViewTable, weight: FloatArray) -> FloatArray:
    """Each candidate's gain (C,): the summed ``weight`` (Hc Wc,) of the cells it
    covers times a cell's area [m^2] (``weight`` 1 on the uncovered floor, 0 elsewhere)."""
    out: FloatArray = _gains(table.ptr, table.cells, np.asarray(weight, dtype=np.float64))
    return out * table.cell_m2


@numba.njit(cache=True)
def _claim(
    c: int,
    ptr: IntArray,
    cells: IntArray,
    tptr: IntArray,
    tcand: IntArray,
    weight: FloatArray,
    gain: FloatArray,
    cell_m2: float,
) -> None:  # pragma: no cover - compiled
    """Candidate ``c``'s cells leave every candidate's gain (``weight`` and ``gain``
    updated in place)."""
    for j in range(ptr[c], ptr[c + 1]):
        k = cells[j]
        w = weight[k]
        if w != 0.0:
            for q in range(tptr[k], tptr[k + 1]):
                gain[tcand[q]] -= w * cell_m2
            weight[k] = 0.0


def choose_views(
    table: ViewTable,
    weight: FloatArray,
    travel_m: FloatArray,
    allowed: BoolArray,
    held: IntArray,
    speed_m_s: float,
    turn_s: float,
    min_gain_m2: float,
) -> IntArray:
    """Each choosing robot's candidate (R,) (-1: none worth it; module notes).

    Parameters
    ----------
    table : ViewTable
    weight : ndarray, shape (Hc Wc,)
        1 on the floor still to cover, 0 elsewhere (not changed).
    travel_m : ndarray, shape (R, C)
        Each choosing robot's travel to each candidate [m] (``inf``: none).
    allowed : ndarray of bool, shape (C,)
        Candidates a robot may choose.
    held : ndarray of int, shape (H,)
        Candidates kept by robots not choosing: their floor is claimed first.
    speed_m_s, turn_s : float
        A robot's cruising speed [m/s] and the time a turn takes [s].
    min_gain_m2 : float
        Least gain worth a trip [m^2].

    Returns
    -------
    ndarray of int, shape (R,)

    Examples
    --------
    Two robots, three candidates: the first two cover the same floor, the third other
    floor farther away; both robots are nearest the first, the second goes to the third.

    >>> import numpy as np
    >>> t = ViewTable(cand=np.arange(3), xy_m=np.zeros((3, 2)), index=np.arange(6),
    ...     ptr=np.array([0, 2, 4, 6]), cells=np.array([3, 4, 3, 4, 5, 5]),
    ...     tptr=np.array([0, 0, 0, 0, 2, 4, 6]), tcand=np.array([0, 1, 0, 1, 2, 2]),
    ...     cell_m2=1.0)
    >>> w = np.array([0, 0, 0, 1, 1, 1.0])
    >>> t.cells[4:6] = [5, 5]  # candidate 2 covers cell 5 only
    >>> choose_views(t, w, np.array([[1.0, 2.0, 6.0], [1.5, 2.5, 5.0]]),
    ...              np.ones(3, bool), np.zeros(0, int), 1.0, 1.0, 0.5).tolist()
    [0, 2]
    """
    w = np.array(weight, dtype=np.float64)
    gain = view_gains(table, w)
    for c in np.asarray(held, dtype=np.int64).tolist():
        if c >= 0:
            _claim(c, table.ptr, table.cells, table.tptr, table.tcand, w, gain, table.cell_m2)
    n_r = travel_m.shape[0]
    out = np.full(n_r, -1, dtype=np.int64)
    time_s = np.asarray(travel_m, dtype=float) / speed_m_s + turn_s
    left = np.ones(n_r, dtype=bool)
    while left.any():
        ok = allowed & (gain >= min_gain_m2)
        if not ok.any():
            break
        rows = np.flatnonzero(left)
        rate = np.where(ok[None, :], gain[None, :], 0.0) / time_s[rows]
        rate[~np.isfinite(time_s[rows])] = 0.0
        flat = int(np.argmax(rate))
        i, c = divmod(flat, rate.shape[1])
        if not rate[i, c] > 0.0:
            break
        out[rows[i]] = c
        left[rows[i]] = False
        _claim(c, table.ptr, table.cells, table.tptr, table.tcand, w, gain, table.cell_m2)
    return out


def scan_heading(
    cm: CoarseMap,
    table: ViewTable,
    cand: int,
    todo: BoolArray,
    pose: FloatArray,
    near_m: float,
    range_m: float,
) -> float | None:
    """The bearing offset [rad] in [-pi, pi) from a robot's heading to the nearest (by
    turn) of the floor its candidate still has to cover (``todo`` (Hc, Wc)) that lies
    ``near_m`` to ``range_m`` from the robot, or ``None`` when none is left: a robot at
    its viewpoint turns that way.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> occ = np.zeros((120, 120), bool)
    >>> cm = coarse_map(build_costmap(OccupancyGrid(occ, ~occ, 0.05), 0.2), 0.25)
    >>> t = view_table(cm, 4.0, 2.0)
    >>> c = int(t.index[12 * 24 + 12])
    >>> todo = np.zeros(cm.shape, bool); todo[12, 3] = True  # 2.25 m west of it
    >>> x, y = t.xy_m[c]
    >>> round(scan_heading(cm, t, c, todo, np.array([x, y, 0.0]), 2.0, 4.0), 2)
    -3.14
    >>> scan_heading(cm, t, c, todo, np.array([x - 0.5, y, 0.0]), 2.0, 4.0) is None
    True
    """
    cells = table.row(cand)
    left = cells[todo.ravel()[cells]]
    if len(left) == 0:
        return None
    rc = np.stack(np.divmod(left, cm.shape[1]), axis=-1)
    xy = cm.centre_xy(rc)
    d = np.hypot(xy[:, 0] - pose[0], xy[:, 1] - pose[1])
    ok = (d >= near_m) & (d <= range_m)
    if not ok.any():
        return None
    bearing = np.arctan2(xy[ok, 1] - pose[1], xy[ok, 0] - pose[0]) - pose[2]
    off = (bearing + np.pi) % (2.0 * np.pi) - np.pi
    return float(off[int(np.argmin(np.abs(off)))])
