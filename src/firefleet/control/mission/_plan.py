"""Who does what: the allocation of fires and victims, and the exploration's frontiers.

Allocation (Kuhn 1955; :func:`firefleet.planning.allocation.allocate_tasks`): the tasks
are the believed fires (fire ``f`` needs ``k_f = clip(fire_robots_min + floor(extent_f /
robot_per_fire_m), fire_robots_min, fire_robots_max)`` robots) and the victims not yet
confirmed (one robot each). Robot ``i``'s cost of task ``j`` is its travel distance on
the map to the task (Dijkstra on the coarse grid from the task, :mod:`._coverage`),
plus ``low_tank_penalty_m`` for a fire other than its own when its tank is below
``low_tank_frac`` (a fighter empties its tank on its fire), minus
``keep_bonus_m`` for the task it already has (so that a robot does not swap tasks for a
metre's gain); a fire is impossible (``inf``) for an empty tank, every task for a robot
damaged, dead or refilling. The assignment minimises the summed cost.

Exploration (Yamauchi 1997; Burgard et al. 2005): the robots left free explore. The
frontiers are the boundary between the covered standable cells and the uncovered floor
(:func:`firefleet.planning.exploration.find_frontiers`); an explorer whose target is
still on a frontier keeps it, the others choose theirs by Burgard's utility with the
kept targets' utility reduction applied first and no target taken twice
(:func:`firefleet.planning.exploration.assign_frontiers`), at their travel distance
(Dijkstra from the robot, cut at ``travel_limit_m``; farther targets cost their
straight-line distance times ``detour_factor``).

References
----------
H. W. Kuhn, "The Hungarian method for the assignment problem", Naval Research Logistics
Quarterly 2, 1955. B. Yamauchi, "A frontier-based approach for autonomous exploration",
IEEE CIRA 1997. W. Burgard, M. Moors, C. Stachniss, F. E. Schneider, "Coordinated
multi-robot exploration", IEEE Transactions on Robotics 21(3), 2005.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import scipy.ndimage as ndi

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.mission._coverage import CoarseMap
from firefleet.control.mission._params import TacticsParams
from firefleet.planning.allocation import allocate_tasks
from firefleet.planning.exploration import assign_frontiers, find_frontiers

__all__ = ["allocate", "cut_demand", "explore", "fire_demand", "task_distances"]

_EIGHT = ndi.generate_binary_structure(2, 2)

_CACHE_MAX = 64
"""Most distance fields kept in the memo (by source node)."""


def fire_demand(extent_m: FloatArray, params: TacticsParams) -> IntArray:
    """Robots each fire needs (module notes), shape (F,)."""
    k = params.fire_robots_min + np.floor(np.asarray(extent_m) / params.robot_per_fire_m)
    out: IntArray = np.clip(k, params.fire_robots_min, params.fire_robots_max).astype(np.int64)
    return out


def cut_demand(need: IntArray, n_victims: int, n_work: int, params: TacticsParams) -> IntArray:
    """The fires' demands (F,) cut so that ``explore_frac`` of the ``n_work`` working
    robots (rounded up) stay free to explore while floor is left to search.

    The open victims (one robot each) count against the same budget; the fires keep
    ``fire_robots_min`` each at least (one each when the team is smaller than that).
    The largest demand is cut first (no crowding at one fire).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.mission import TacticsParams
    >>> p = TacticsParams(explore_frac=0.3, fire_robots_min=2)
    >>> cut_demand(np.array([6, 6, 4]), 5, 40, p).tolist()  # 40 - 12 - 5 = 23 for fires
    [6, 6, 4]
    >>> cut_demand(np.array([6, 6, 6, 6]), 10, 40, p).tolist()  # 40 - 12 - 10 = 18
    [4, 4, 5, 5]
    >>> cut_demand(np.array([2]), 1, 3, p).tolist()  # 3 robots: the fire keeps its 2
    [2]
    """
    out = np.array(need, dtype=np.int64)
    n_fires = len(out)
    budget = n_work - math.ceil(params.explore_frac * n_work) - n_victims
    floor = n_fires * params.fire_robots_min
    if floor > n_work - math.ceil(params.explore_frac * n_work):
        floor = n_fires
    budget = max(budget, floor)
    while out.sum() > budget:
        out[int(np.argmax(out))] -= 1
    return out


def task_distances(
    cm: CoarseMap, memo: dict[int, FloatArray], task_xy: FloatArray, robot_xy: FloatArray
) -> FloatArray:
    """Travel distance [m] of each robot (N, 2) to each task (T, 2): (N, T).

    The distance fields from each task's cell are kept in ``memo`` (a cache by source
    node; it changes no result).
    """
    nodes = cm.node_of(task_xy)
    todo = [int(n) for n in np.unique(nodes) if int(n) not in memo]
    if todo:
        fields = cm.distances(np.asarray(todo, dtype=np.int64))
        for n, f in zip(todo, fields, strict=True):
            memo[n] = f
        needed = {int(n) for n in np.unique(nodes)}
        stale = [k for k in memo if k not in needed]  # oldest first; never this call's
        for k in stale[: max(0, len(memo) - _CACHE_MAX)]:
            memo.pop(k)
    robot_nodes = cm.node_of(robot_xy)
    out = np.empty((len(robot_xy), len(task_xy)))
    for j, n in enumerate(nodes):
        out[:, j] = memo[int(n)][robot_nodes]
    return out


def allocate(
    dist_m: FloatArray,
    demand: IntArray,
    is_fire: BoolArray,
    current: IntArray,
    available: BoolArray,
    tank_l: FloatArray,
    params: TacticsParams,
) -> IntArray:
    """The task of each robot (module notes), shape (N,) (-1: none).

    Parameters
    ----------
    dist_m : ndarray, shape (N, T)
        Travel distances [m].
    demand : ndarray of int, shape (T,)
        Robots each task needs.
    is_fire : ndarray of bool, shape (T,)
        Which tasks are fires.
    current : ndarray of int, shape (N,)
        Each robot's task now (-1: none).
    available : ndarray of bool, shape (N,)
        Robots that may take a task.
    tank_l : ndarray, shape (N,)
        Agent in each tank [L].
    params : TacticsParams
    """
    cost = np.array(dist_m, dtype=float)
    low = tank_l < params.low_tank_frac * params.tank_l
    empty = tank_l <= _empty_l(params)
    has = current >= 0
    rows = np.flatnonzero(has)
    keep = np.zeros(cost.shape, dtype=bool)
    keep[rows, current[has]] = True  # a fighter empties its tank on its fire
    cost[low[:, None] & is_fire[None, :] & ~keep] += params.low_tank_penalty_m
    cost[np.ix_(empty, is_fire)] = np.inf
    cost[rows, current[has]] = np.maximum(cost[rows, current[has]] - params.keep_bonus_m, 0.0)
    cost[~available] = np.inf
    return allocate_tasks(cost, demand=demand)


def _segments(labels: IntArray, seg_len: int) -> tuple[IntArray, IntArray]:
    """Frontiers cut into segments of at most about ``seg_len`` cells along their
    principal axis (a long frontier is several places to look from): each segment's
    target (its cell nearest its centroid), (S, 2), and the segment of each cell
    (Hc, Wc) (-1: none)."""
    seg = np.full(labels.shape, -1, dtype=np.int64)
    flat = np.flatnonzero(labels.ravel() > 0)
    order = np.argsort(labels.ravel()[flat], kind="stable")
    flat = flat[order]
    lab = labels.ravel()[flat]
    starts = np.flatnonzero(np.diff(np.concatenate([[0], lab])) != 0)
    bounds = np.append(starts, len(flat))
    targets: list[IntArray] = []
    for a, b in itertools.pairwise(bounds.tolist()):
        rc = np.stack(np.divmod(flat[a:b], labels.shape[1]), axis=1).astype(float)
        centred = rc - rc.mean(axis=0)
        if len(rc) > seg_len:
            axis = np.linalg.svd(centred, full_matrices=False)[2][0]
            chunks = np.array_split(np.argsort(centred @ axis), -(-len(rc) // seg_len))
        else:
            chunks = [np.arange(len(rc))]
        for chunk in chunks:
            cells = rc[chunk]
            mid = cells.mean(axis=0)
            targets.append(cells[np.argmin(((cells - mid) ** 2).sum(axis=1))].astype(np.int64))
            seg.ravel()[flat[a:b][chunk]] = len(targets) - 1
    return np.asarray(targets, dtype=np.int64).reshape(-1, 2), seg


def _empty_l(params: TacticsParams) -> float:
    """A tank holding less than a second of flow counts as empty [L]."""
    return min(params.flow_l_s * 1.0, 0.05 * params.tank_l)


def explore(
    cm: CoarseMap,
    covered: BoolArray,
    pose: FloatArray,
    explorers: BoolArray,
    target_cell: IntArray,
    keep: BoolArray,
    goal_open: BoolArray,
    excluded: BoolArray,
    params: TacticsParams,
) -> IntArray:
    """Each explorer's frontier target cell (N, 2) (-1: none; module notes).

    Parameters
    ----------
    cm : CoarseMap
    covered : ndarray of bool, shape (Hc, Wc)
        Coverage so far.
    pose : ndarray, shape (N, 3)
    explorers : ndarray of bool, shape (N,)
        Robots that explore.
    target_cell : ndarray of int, shape (N, 2)
        Their targets so far (-1: none).
    keep : ndarray of bool, shape (N,)
        Explorers still on their way: they keep a target still on a frontier, or any
        target while ``goal_open`` (their goal not yet covered).
    goal_open : ndarray of bool, shape (N,)
        Explorers whose goal cell is not covered yet.
    excluded : ndarray of bool, shape (Hc, Wc)
        Cells never to be chosen (found unreachable).
    params : TacticsParams
    """
    n = len(pose)
    out = np.full((n, 2), -1, dtype=np.int64)
    if not explorers.any():
        return out
    fr = find_frontiers(
        covered & cm.standable & ~excluded,
        cm.floor & ~covered,
        min_cells=params.frontier_min_cells,
    )
    seg_len = max(params.frontier_min_cells, round(params.sensing_range_m / cm.cell_m))
    targets, seg = _segments(fr.labels, seg_len)
    held: list[int] = []
    choose = []
    for i in map(int, np.flatnonzero(explorers)):
        r, c = target_cell[i]
        keep_i = bool(keep[i]) and r >= 0 and not excluded[r, c]
        lab = int(seg[r, c]) if keep_i else -1
        if lab >= 0 and lab not in held:
            held.append(lab)
            out[i] = targets[lab]
        elif keep_i and goal_open[i] and lab < 0:
            out[i] = target_cell[i]  # off the frontier now, its goal still unseen
        else:
            choose.append(i)
    who = np.asarray(choose, dtype=np.int64)
    if len(who) and len(targets):
        pick = _choose(cm, pose[who], targets, np.asarray(held, dtype=np.int64), params)
        out[who[pick >= 0]] = targets[pick[pick >= 0]]
        who = who[pick < 0]
    if len(who):  # more explorers than frontiers: the uncovered rooms themselves
        holes, _ = ndi.label(cm.floor & cm.standable & ~covered & ~excluded, structure=_EIGHT)
        sizes = np.bincount(holes.ravel())
        small = sizes < params.frontier_min_cells
        small[0] = True
        holes[small[holes]] = 0
        inner, inner_seg = _segments(holes, seg_len * seg_len // 2)
        kept: list[int] = []
        for i in who:
            r, c = target_cell[i]
            lab = int(inner_seg[r, c]) if r >= 0 and keep[i] and not excluded[r, c] else -1
            if lab >= 0 and lab not in kept:
                kept.append(lab)
                out[i] = inner[lab]
        who = who[out[who, 0] < 0]
        if len(inner) and len(who):
            pick = _choose(cm, pose[who], inner, np.asarray(kept, dtype=np.int64), params)
            out[who[pick >= 0]] = inner[pick[pick >= 0]]
    return out


def _choose(
    cm: CoarseMap, pose: FloatArray, targets: IntArray, held: IntArray, params: TacticsParams
) -> IntArray:
    """Burgard's choice (exclusive) of targets (T, 2) for robots at ``pose`` (R, 3)."""
    txy = cm.goal_xy(targets)
    t_nodes = targets[:, 0] * cm.shape[1] + targets[:, 1]
    r_nodes = cm.node_of(pose[:, :2])
    if len(t_nodes) < len(r_nodes):  # the graph is undirected: search from the fewer
        d = cm.distances(t_nodes, params.travel_limit_m)[:, r_nodes].T
    else:
        d = cm.distances(r_nodes, params.travel_limit_m)[:, t_nodes]
    straight = np.hypot(pose[:, None, 0] - txy[None, :, 0], pose[:, None, 1] - txy[None, :, 1])
    d = np.where(np.isfinite(d), d, params.detour_factor * straight)
    return assign_frontiers(
        d,
        txy,
        sensor_range_m=params.sensing_range_m,
        beta=params.burgard_beta,
        taken=held,
        exclusive=True,
    )
