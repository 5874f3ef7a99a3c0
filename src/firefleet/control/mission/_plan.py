"""Who does what: the allocation of fires and victims.

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

Exploration: :mod:`._explore` and :mod:`._views` (viewpoints chosen by the floor a turn
there covers).

References
----------
H. W. Kuhn, "The Hungarian method for the assignment problem", Naval Research Logistics
Quarterly 2, 1955. B. Yamauchi, "A frontier-based approach for autonomous exploration",
IEEE CIRA 1997. W. Burgard, M. Moors, C. Stachniss, F. E. Schneider, "Coordinated
multi-robot exploration", IEEE Transactions on Robotics 21(3), 2005.
"""

from __future__ import annotations

import math

import numpy as np

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.mission._coverage import CoarseMap
from firefleet.control.mission._params import TacticsParams
from firefleet.planning.allocation import allocate_tasks

__all__ = ["allocate", "cut_demand", "fire_demand", "task_distances"]


_CACHE_MAX = 64
"""Most distance fields kept in the memo (by source node)."""


def fire_demand(extent_m: FloatArray, params: TacticsParams) -> IntArray:
    """Robots each fire needs (module notes), shape (F,)."""
    k = params.fire_robots_min + np.floor(np.asarray(extent_m) / params.robot_per_fire_m)
    out: IntArray = np.clip(k, params.fire_robots_min, params.fire_robots_max).astype(np.int64)
    return out


def cut_demand(
    need: IntArray, n_victims: int, n_work: int, params: TacticsParams, refilling: int = 0
) -> IntArray:
    """The fires' demands (F,) cut so that ``explore_frac`` of the ``n_work`` working
    robots at hand (rounded up) stay free to explore while floor is left to search.

    The open victims (one robot each) count against the same budget; the fires keep
    ``fire_robots_min`` each at least, or one each when the team is smaller than that,
    but none while the robots at hand are all explorers and others (``refilling``) are
    out at a refill point: those come back to the fires, and the explorers search on.
    The largest demand is cut first (no crowding at one fire).

    Without the refillers' exception, a team of three whose two fighters went to refill
    sent its explorer to the fire (the school, seed 4, at 180 s: it left the rooms it had
    not looked into, and the people there were never found).

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
    >>> cut_demand(np.array([2]), 0, 1, p).tolist()  # one robot: it fights
    [1]
    >>> cut_demand(np.array([2]), 0, 1, p, refilling=2).tolist()  # 2 out: it explores
    [0]
    """
    out = np.array(need, dtype=np.int64)
    n_fires = len(out)
    spare = n_work - math.ceil(params.explore_frac * n_work)
    budget = spare - n_victims
    floor = n_fires * params.fire_robots_min
    if floor > spare:
        floor = 0 if spare <= 0 and refilling > 0 else n_fires
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


def _empty_l(params: TacticsParams) -> float:
    """A tank holding less than a second of flow counts as empty [L]."""
    return min(params.flow_l_s * 1.0, 0.05 * params.tank_l)
