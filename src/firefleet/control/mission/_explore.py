"""The explorers' plan and their turn at a viewpoint (the choice is :mod:`._views`').

An explorer keeps its viewpoint while the floor it was sent to cover is not covered:
on its way, while the candidate's gain is at least ``view_min_m2``; once there, while
some of that floor lies within the camera's reach (``sensing_near_m`` to
``sensing_range_m`` from where it stands), turning towards the nearest of it. The
others choose anew (:func:`._views.choose_views`, the kept viewpoints' floor claimed
first), at their travel distance on the map (Dijkstra from the robot, cut at
``travel_limit_m``; a robot with nothing worth a trip within it searches the whole map),
no path passing a teammate closer than ``2 robot_radius_m + margin_m`` (in a passage
too narrow to pass, the floor beyond a teammate is not a robot's to choose: on the maze
three robots that chose across each other in a 1 m passage stood locked for 200 s, and
with such paths priced 10 m more, two followed the third into the passage and stood
locked behind it for 40 s). A teammate that stands and makes way (a fighter, a
refiller, one idle or watching a victim: ``passable``) does not block the way: on the
maze two fighters stood in the 1 m passage that is the only way into the south half, and
the explorer, who never chose beyond them, covered 25 % of the floor.
A viewpoint never lies in ``avoid`` (cells found unreachable, the surroundings of a
known fire).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse
from scipy.sparse.csgraph import dijkstra

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.mission._coverage import CoarseMap
from firefleet.control.mission._near import any_within
from firefleet.control.mission._params import TacticsParams
from firefleet.control.mission._views import ViewTable, choose_views, scan_heading, view_table

__all__ = ["explore_views", "scan_turn", "views_of"]


def views_of(cm: CoarseMap, params: TacticsParams) -> ViewTable:
    """The map's view table for the camera's coverage (built once, kept in ``cm.cache``)."""
    clear = params.nav.robot_radius_m + params.nav.margin_m + params.view_clear_m
    near, far, most = params.sensing_near_m, params.sensing_range_m, params.view_max_candidates
    key = ("views", far, near, clear, most)
    table = cm.cache.get(key)
    if not isinstance(table, ViewTable):
        table = view_table(cm, far, near, clear, most)
        cm.cache[key] = table
    return table


def _blocked_nodes(cm: CoarseMap, xy_m: FloatArray, radius_m: float) -> IntArray:
    """Graph nodes (flat coarse cells) whose centre lies within ``radius_m`` of any of
    the points (K, 2) [m]."""
    if len(xy_m) == 0:
        return np.zeros(0, dtype=np.int64)
    k = math.ceil(radius_m / cm.cell_m) + 1
    dr, dc = np.mgrid[-k : k + 1, -k : k + 1]
    rc = cm.cell_of(xy_m)[:, None, :] + np.stack([dr.ravel(), dc.ravel()], axis=-1)[None]
    rc = rc.reshape(-1, 2)
    hc, wc = cm.shape
    rc = rc[(rc[:, 0] >= 0) & (rc[:, 0] < hc) & (rc[:, 1] >= 0) & (rc[:, 1] < wc)]
    centre = cm.centre_xy(rc)
    # hypot <= radius_m to any point, decided exactly (_near: a k-d tree, hypot at the edge)
    near = any_within(centre, xy_m, radius_m, inclusive=True)
    out: IntArray = np.unique(rc[near, 0] * wc + rc[near, 1])
    return out


def _travel(
    cm: CoarseMap,
    table: ViewTable,
    xy_m: FloatArray,
    mates_xy_m: FloatArray,
    who: IntArray,
    block_m: float,
    limit_m: float,
    blockers: BoolArray | None = None,
) -> FloatArray:
    """Travel [m] of robots ``who`` (R,) from their points (R, 2) to every candidate,
    (R, C) (``inf``: past the limit or unreachable), on the graph where no path passes
    through a cell within ``block_m`` of a teammate (``mates_xy_m`` (N, 2), the robot
    itself excepted): in a passage too narrow to pass, the floor beyond a teammate is
    not a robot's to choose (it chooses elsewhere, or waits until the teammate has
    gone on). Only the teammates marked in ``blockers`` (N,) count (None: all)."""
    graph = cm.graph
    n_mates = len(mates_xy_m)
    counts = np.ones(n_mates, dtype=bool) if blockers is None else np.asarray(blockers, bool)
    nodes = cm.node_of(xy_m)
    out = np.empty((len(nodes), len(table)))
    ptr = graph.indptr
    for j, i in enumerate(np.asarray(who).tolist()):
        others = mates_xy_m[counts & (np.arange(n_mates) != i)]
        blocked = _blocked_nodes(cm, others, block_m)
        blocked = blocked[blocked != nodes[j]]
        g = graph
        if len(blocked):
            data = graph.data.copy()
            # no edge leaves a blocked node: reached, never passed through
            # (the edges of each blocked node in turn: its run ptr[b]:ptr[b + 1])
            first, many = ptr[blocked], ptr[blocked + 1] - ptr[blocked]
            rows = np.repeat(first - (np.cumsum(many) - many), many) + np.arange(many.sum())
            data[rows] = np.inf
            g = scipy.sparse.csr_matrix((data, graph.indices, ptr), shape=graph.shape)
        d = dijkstra(g, directed=True, indices=int(nodes[j]), limit=limit_m)
        out[j] = np.asarray(d, dtype=float)[table.cand]
    return out


def explore_views(
    cm: CoarseMap,
    covered: BoolArray,
    pose: FloatArray,
    explorers: BoolArray,
    cell: IntArray,
    going: BoolArray,
    there: BoolArray,
    avoid: BoolArray,
    params: TacticsParams,
    passable: BoolArray | None = None,
) -> IntArray:
    """Each explorer's viewpoint cell (N, 2) (-1: none worth a trip; module notes).

    Parameters
    ----------
    cm : CoarseMap
    covered : ndarray of bool, shape (Hc, Wc)
        Coverage so far.
    pose : ndarray, shape (N, 3)
    explorers : ndarray of bool, shape (N,)
        Robots that explore.
    cell : ndarray of int, shape (N, 2)
        Their viewpoints so far (-1: none).
    going, there : ndarray of bool, shape (N,)
        Explorers on their way to it, and arrived at it.
    avoid : ndarray of bool, shape (Hc, Wc)
        Cells no viewpoint may be.
    params : TacticsParams
    passable : ndarray of bool, shape (N,), or None
        Teammates a path may pass: they stand and make way for a robot that needs
        the place (the navigation's ``movable``, ``_makeway``); None: none.
    """
    n = len(pose)
    out = np.full((n, 2), -1, dtype=np.int64)
    if not explorers.any():
        return out
    table = views_of(cm, params)
    todo = cm.floor & ~covered
    weight = todo.ravel().astype(np.float64)
    allowed = ~avoid.ravel()[table.cand]
    held: list[int] = []
    choose: list[int] = []
    for i in map(int, np.flatnonzero(explorers)):
        r, c = cell[i]
        k = int(table.index[r * cm.shape[1] + c]) if r >= 0 else -1
        ok = k >= 0 and bool(allowed[k]) and k not in held
        if ok and going[i]:
            ok = float(weight[table.row(k)].sum()) * table.cell_m2 >= params.view_min_m2
        elif ok and there[i]:
            reach = (params.sensing_near_m, params.sensing_range_m)
            ok = scan_heading(cm, table, k, todo, pose[i], *reach) is not None
        else:
            ok = False
        if ok:
            held.append(k)
            out[i] = cell[i]
        else:
            choose.append(i)
    if not choose:
        return out
    who = np.asarray(choose, dtype=np.int64)
    block = 2.0 * params.nav.robot_radius_m + params.nav.margin_m
    mates = pose[:, :2]
    blockers = None if passable is None else ~np.asarray(passable, dtype=bool)
    travel = _travel(cm, table, pose[who, :2], mates, who, block, params.travel_limit_m, blockers)
    speed = params.nav.dwa.v_max_m_s
    turn_s = np.pi / params.scan_omega_rad_s
    args = (table, weight, travel, allowed, np.asarray(held, dtype=np.int64), speed, turn_s)
    pick = choose_views(*args, params.view_min_m2)
    lost = np.flatnonzero(pick < 0)
    if len(lost):  # nothing worth a trip nearby: search the whole map for them
        whole = travel.copy()
        whole[lost] = _travel(
            cm, table, pose[who[lost], :2], mates, who[lost], block, np.inf, blockers
        )
        pick = choose_views(table, weight, whole, allowed, *args[4:], params.view_min_m2)
    got = pick >= 0
    rc = np.stack(np.divmod(table.cand[pick[got]], cm.shape[1]), axis=-1)
    out[who[got]] = rc
    return out


def scan_turn(
    cm: CoarseMap,
    covered: BoolArray,
    pose: FloatArray,
    cell: IntArray,
    scanning: BoolArray,
    params: TacticsParams,
) -> FloatArray:
    """Turn rates [rad/s] (N,) of the explorers arrived at their viewpoint
    (``scanning``): towards the nearest floor the viewpoint still has to cover, at
    ``scan_omega_rad_s`` (slower within the last ``1 / face_gain`` radians, down to a
    quarter of it); 0 when none is left (and for the others)."""
    out = np.zeros(len(pose))
    if not scanning.any():
        return out
    table = views_of(cm, params)
    todo = cm.floor & ~covered
    for i in map(int, np.flatnonzero(scanning)):
        r, c = cell[i]
        k = int(table.index[r * cm.shape[1] + c]) if r >= 0 else -1
        if k < 0:
            continue
        off = scan_heading(
            cm, table, k, todo, pose[i], params.sensing_near_m, params.sensing_range_m
        )
        if off is not None:
            w = min(max(params.face_gain * abs(off), 0.25), 1.0) * params.scan_omega_rad_s
            out[i] = float(np.copysign(w, off))
    return out
