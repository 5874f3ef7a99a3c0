"""The team navigation controller the ``navigate`` task kind calls each tick.

Per robot, each control period::

    global     A* on the map inflated by robot radius + margin (wall cost), smoothed
               into a line-and-arc PlanarPath (planned at init, re-planned when needed)
    progress   the arc length s of the nearest path point, searched in a window
               around the last one (a path that doubles back is not skipped)
    follow     the deliverable's fuzzy controller (control.path_following, Table 1 +
               lambda) towards the point ``lookahead_m`` ahead on the path, with the
               path's heading there: (v_ref, omega_ref)
    give way   a robot yields (v_ref = 0, it may still turn) to any teammate of higher
               priority (lower index) whose next ``yield_distance_m`` of path comes
               within two radii + margin of its own next stretch; if it already stands
               in that teammate's way (a narrow passage, head on), it makes way: it
               drives to the nearest reachable spot at least two radii + margin from
               the teammate's whole remaining path, then plans to its goal again
    safety     DWA (``_dwa``) picks the admissible command of the dynamic window
               (Table 2 motors at 12 V) nearest (v_ref, omega_ref), with a clearance
               bonus, against the sensed range points, the known map's wall cells
               (discs of half a cell's diagonal) and the teammates' discs
    re-plan    when the robot strays more than ``replan_offset_m`` from its path, or
               makes less than ``stuck_progress_m`` of progress in ``stuck_time_s``
               while not yielding: A* again from where it is, the second time in a row
               with the teammates' discs on the map
    arrive     within half ``goal_tolerance_m`` of its goal (by its pose estimate, which
               may be off by a few centimetres) a robot stops for good

The fuzzy controller steers and DWA only bends or slows its command near obstacles:
in the open the robot drives as the deliverable's controller drives it. The stuck
detector and the path lookahead are the cure for DWA's known failures (PythonRobotics
issue 379: a robot facing an obstacle straight in line with its goal stops for ever;
oscillation in doorways): DWA never chases the raw goal.

Priorities by index are fixed, so the highest-priority robot still moving never waits
for anyone, and the team cannot deadlock by waiting in a cycle.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numba
import numpy as np
from numpy.typing import ArrayLike
from scipy import ndimage
from scipy.spatial import cKDTree

from firefleet._frozen import replace
from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.navigation._astar import astar
from firefleet.control.navigation._costmap import Costmap, build_costmap
from firefleet.control.navigation._dwa import DwaParams
from firefleet.control.navigation._smooth import smooth_path
from firefleet.control.path_following import PathFollowingController
from firefleet.errors import InputError, as_float_array, check_fields
from firefleet.planning.planar import PlanarPath
from firefleet.world import OccupancyGrid

__all__ = [
    "NavigationInputs",
    "NavigationParams",
    "NavigationState",
    "navigation_init",
    "navigation_retarget",
]

STATUSES = ("moving", "waiting", "arrived", "unreachable", "start_blocked", "goal_blocked")
"""What each robot is doing (``NavigationState.status``)."""

_SAMPLE_M = 0.05
"""Spacing of the path samples used for progress and conflicts [m]."""


@dataclass(frozen=True, eq=False)
class NavigationParams:
    """The constants of team navigation.

    Attributes
    ----------
    robot_radius_m : float
        Each robot's disc [m].
    margin_m : float
        Extra distance kept from walls by the planner, and between robots [m].
    goal_tolerance_m : float
        The tolerance the task judges arrival with [m]; a robot stops for good within
        half of it (by its estimate).
    lookahead_m : float
        How far ahead on its path a robot's desired point is [m] (the fuzzy
        controller's speed grows with it, about ``lookahead / 2`` m/s).
    corner_radius_m : float
        Largest radius of the smoothed path's corners [m].
    wall_weight, wall_decay_m : float
        The planner's wall cost (:func:`build_costmap`).
    dwa : DwaParams
        The dynamic window (Table 2 at 12 V by default).
    stuck_time_s, stuck_progress_m : float
        Re-plan after less than this progress along the path in this time.
    replan_offset_m : float
        Re-plan when the robot is this far from its path [m].
    yield_distance_m : float
        How much of their paths ahead two robots compare for a conflict [m].
    controller : PathFollowingController
        The deliverable's fuzzy path follower.
    make_way_reach_m : float
        How far from where it stands a robot looks for a spot out of a moving
        teammate's way [m] (``_makeway``; only robots the inputs mark ``movable``).
    """

    robot_radius_m: float = 0.15
    margin_m: float = 0.05
    goal_tolerance_m: float = 0.2
    lookahead_m: float = 0.6
    corner_radius_m: float = 0.5
    wall_weight: float = 2.0
    wall_decay_m: float = 0.1
    dwa: DwaParams = field(default_factory=DwaParams)
    stuck_time_s: float = 3.0
    stuck_progress_m: float = 0.1
    replan_offset_m: float = 0.5
    yield_distance_m: float = 2.0
    controller: PathFollowingController = field(default_factory=PathFollowingController.builtin)
    make_way_reach_m: float = 4.0

    def __post_init__(self) -> None:
        check_fields(
            self,
            "navigation",
            positive=(
                "robot_radius_m",
                "goal_tolerance_m",
                "lookahead_m",
                "wall_decay_m",
                "stuck_time_s",
                "replan_offset_m",
                "yield_distance_m",
                "make_way_reach_m",
            ),
        )
        if self.margin_m < 0 or self.corner_radius_m < 0 or self.wall_weight < 0:
            raise InputError("navigation.margin_m, corner_radius_m and wall_weight must be >= 0")

    @property
    def inflation_m(self) -> float:
        """Robot radius + margin: how far the planner keeps the robot's centre from walls."""
        return self.robot_radius_m + self.margin_m


@dataclass(frozen=True, eq=False)
class NavigationInputs:
    """What the team knows at a tick.

    Attributes
    ----------
    pose : ndarray, shape (N, 3)
        Pose estimates x [m], y [m], heading [rad].
    ranges : mapping of str to (ranges, bearings)
        Range readings by sensor name (``"lidar"``, ``"ultrasonic"``, ``"stereo"``):
        ranges (N, B) [m] with ``inf`` (or NaN) for no return, and their bearings (B,)
        or (N, B) [rad] relative to each robot's heading.
    teammates_xy_m : ndarray, shape (N, 2)
        Every robot's position as the team received it [m].
    t_s : float
        Time [s].
    movable : ndarray of bool, shape (N,), or None
        Robots that may be asked to make way for a moving teammate while they stand
        (arrived; ``_makeway``); None: none (an arrived robot stops for good).
    """

    pose: FloatArray
    ranges: Mapping[str, tuple[ArrayLike, ArrayLike]]
    teammates_xy_m: FloatArray
    t_s: float
    movable: BoolArray | None = None


@dataclass(frozen=True, eq=False)
class NavigationState:
    """The team's navigation state (returned anew by every step).

    Attributes
    ----------
    costmap : Costmap
        The static map, inflated.
    goals_m : ndarray, shape (N, 2)
        Goals [m].
    paths : tuple of PlanarPath or None
        Each robot's smoothed path (None without one).
    samples : tuple of ndarray
        Each path sampled every 5 cm, (K, 3): x, y, heading.
    progress_m : ndarray, shape (N,)
        Arc length reached on each path [m].
    status : tuple of str
        Per robot, one of :data:`STATUSES`.
    command : ndarray, shape (N, 2)
        The last command (v [m/s], omega [rad/s]).
    best_progress_m, since_s : ndarray, shape (N,)
        The stuck detector: the progress at the last check and when it was.
    stuck_count : ndarray of int, shape (N,)
        Re-plans in a row for lack of progress.
    replans : ndarray of int, shape (N,)
        Paths planned so far per robot (the first included).
    wall_points_m : ndarray, shape (K, 2)
        Centres of the map's non-free cells that touch a free one [m]: the known walls
        DWA keeps clear of besides what the sensors see.
    target_m : ndarray, shape (N, 2)
        Where each robot's current path leads [m]: its goal, or a spot out of a
        teammate's way.
    aside_of : ndarray of int, shape (N,)
        The teammate a robot is making way for (-1: none).
    t_s : float
        Time of the last step [s].
    wall_tree : scipy.spatial.cKDTree or None
        A k-d tree of ``wall_points_m`` (built once; finds the walls near each robot in
        O(log K) instead of a scan of every wall cell), None to scan.
    parked : ndarray of bool, shape (N,), or None
        Robots that stood and make way for ``aside_of`` (they go back to their goal once
        it has passed; ``_makeway``); None: none.
    asked_s : ndarray, shape (N,), or None
        When each standing robot was last found no spot to make way to [s] (it is not
        asked again within ``stuck_time_s``); None: never.
    planned_on : Costmap or None
        The ``costmap`` of the last step: when the caller gives the state a new costmap
        with the same cost grid (the mission prices the fires anew at each plan), the
        plans A* kept in the old one are the new one's too (:func:`._astar.adopt_plans`).
    """

    costmap: Costmap
    goals_m: FloatArray
    paths: tuple[PlanarPath | None, ...]
    samples: tuple[FloatArray, ...]
    progress_m: FloatArray
    status: tuple[str, ...]
    command: FloatArray
    best_progress_m: FloatArray
    since_s: FloatArray
    stuck_count: IntArray
    replans: IntArray
    t_s: float
    wall_points_m: FloatArray
    target_m: FloatArray
    aside_of: IntArray
    wall_tree: cKDTree | None = None
    parked: BoolArray | None = None
    asked_s: FloatArray | None = None
    planned_on: Costmap | None = None

    @property
    def arrived(self) -> FloatArray:
        """Which robots have arrived, shape (N,) bool."""
        return np.array([s == "arrived" for s in self.status])


def _plan(
    costmap: Costmap, start: FloatArray, goal: FloatArray, params: NavigationParams
) -> tuple[str, PlanarPath | None]:
    res = astar(costmap, start, goal)
    prefix = None
    if res.status == "start_blocked" and costmap.grid.contains(start[None])[0]:
        # pushed into the inflated band (or a teammate's disc): start from the nearest
        # open cell within half a metre
        grid = costmap.grid
        rc = grid.cell_of(start)
        k = math.ceil(0.5 / grid.resolution_m)
        h, w = grid.shape
        r0, r1 = max(rc[0] - k, 0), min(rc[0] + k + 1, h)
        c0, c1 = max(rc[1] - k, 0), min(rc[1] + k + 1, w)
        open_cells = np.argwhere(~costmap.blocked[r0:r1, c0:c1]) + np.array([r0, c0])
        if len(open_cells):
            centres = grid.center_of(open_cells)
            near = centres[np.argmin(np.hypot(*(centres - start).T))]
            res = astar(costmap, near, goal)
            prefix = start
    if not res.found or res.xy_m is None:
        return res.status, None
    xy = res.xy_m if prefix is None else np.vstack([prefix, res.xy_m])
    if len(xy) < 2 or np.hypot(*(xy[-1] - xy[0])) < 1e-9:
        xy = np.vstack([start, goal + 1e-6])
    return "moving", smooth_path(costmap, xy, radius_m=params.corner_radius_m)


def _samples(path: PlanarPath | None) -> FloatArray:
    if path is None:
        return np.zeros((0, 3))
    n = max(math.ceil(path.length_m / _SAMPLE_M), 1)
    return path.pose_at(np.linspace(0.0, path.length_m, n + 1))


def _with_teammates(
    state: NavigationState, params: NavigationParams, others_xy: FloatArray
) -> Costmap:
    """The static costmap with the teammates' discs on it as walls.

    Exactly :func:`build_costmap` of the map with the discs' cells occupied, plus the
    price the static costmap adds to its cells beyond their walls' (the fires' and the
    hot places' on the mission: a re-plan round a teammate must not lose it), computed
    only in a window about each disc (a disc lowers the clearance of the cells near it
    and nowhere else; the window reaches ``inflation + 20 wall_decay_m`` past the disc,
    where the disc's wall cost is below ``wall_weight * 2e-9``): O(window) per teammate
    instead of O(map).
    """
    static = state.costmap
    grid = static.grid
    res = grid.resolution_m
    h, w = grid.shape
    occ = np.array(~grid.free)
    clearance = np.array(static.clearance_m)
    cost = np.array(static.cost)
    reach = params.robot_radius_m + params.inflation_m + 20.0 * params.wall_decay_m
    k = math.ceil(reach / res) + 1
    windows = []
    ox, oy = (float(v) for v in grid.origin_m)
    box = np.zeros(4, dtype=np.int64)
    disc = np.zeros((2 * k + 1, 2 * k + 1), dtype=bool)
    for xy in np.asarray(others_xy, dtype=float).reshape(-1, 2):
        # the window about its cell and the disc's cells in it (compiled, _disc_window)
        if not _disc_window(xy, ox, oy, res, h, w, k, params.robot_radius_m, box, disc):
            continue  # off the map, or no cell centre in its disc
        r0, r1, c0, c1 = (int(v) for v in box)
        occ[r0:r1, c0:c1] |= disc[: r1 - r0, : c1 - c0]
        near = np.asarray(ndimage.distance_transform_edt(~disc[: r1 - r0, : c1 - c0])) * res
        np.minimum(clearance[r0:r1, c0:c1], near, out=clearance[r0:r1, c0:c1])
        windows.append((r0, r1, c0, c1))
    blocked = clearance <= params.inflation_m
    for r0, r1, c0, c1 in windows:
        cw = clearance[r0:r1, c0:c1]
        # the window's wall cost anew; any cost the static map adds besides its walls
        # (the fires' and hot places' price, ``heat_costmap``) is kept
        base = static.cost[r0:r1, c0:c1]
        add = base - 1.0 - _wall_extra(static.clearance_m[r0:r1, c0:c1], params)
        add = np.where(np.isfinite(base) & (add > 1e-9), add, 0.0)
        cost[r0:r1, c0:c1] = np.where(
            blocked[r0:r1, c0:c1] | ~np.isfinite(base),
            np.inf,
            1.0 + _wall_extra(cw, params) + add,
        )
    teamed = OccupancyGrid(occ, grid.free & ~occ, grid.resolution_m, grid.origin_m, grid.name)
    for arr in (clearance, blocked, cost):
        arr.setflags(write=False)
    return Costmap(teamed, clearance, blocked, cost, float(params.inflation_m))


@numba.njit(cache=True)
def _disc_window(
    xy: FloatArray,
    ox: float,
    oy: float,
    res: float,
    h: int,
    w: int,
    k: int,
    radius_m: float,
    box: IntArray,
    disc: BoolArray,
) -> bool:  # pragma: no cover - compiled
    """A teammate's window in :func:`_with_teammates`: ``box`` gets the rows and
    columns ``[r0, r1) x [c0, c1)`` within ``k`` cells of the cell holding ``xy`` (2,)
    [m] (:meth:`OccupancyGrid.cell_of`'s arithmetic), ``disc[: r1 - r0, : c1 - c0]``
    the window's cells whose centre (:meth:`OccupancyGrid.center_of`'s) lies within
    ``radius_m`` of it (``np.hypot``); whether the window is on the map and holds one.
    A centre farther than ``radius_m`` along x or y is out without its ``hypot`` (which
    is at least that difference)."""
    c = math.floor((xy[0] - ox) / res)
    r = h - 1 - math.floor((xy[1] - oy) / res)
    r0, r1, c0, c1 = max(r - k, 0), min(r + k + 1, h), max(c - k, 0), min(c + k + 1, w)
    if r0 >= r1 or c0 >= c1:
        return False  # off the map
    box[0], box[1], box[2], box[3] = r0, r1, c0, c1
    found = False
    for i in range(r1 - r0):
        cy = oy + (np.float64(h - 1) - np.float64(r0 + i) + 0.5) * res
        dy = cy - xy[1]
        for j in range(c1 - c0):
            cx = ox + (np.float64(c0 + j) + 0.5) * res
            dx = cx - xy[0]
            inside = False
            if abs(dx) <= radius_m and abs(dy) <= radius_m:
                inside = bool(np.hypot(dx, dy) <= radius_m)
            disc[i, j] = inside
            found = found or inside
    return found


def _wall_extra(clearance_m: FloatArray, params: NavigationParams) -> FloatArray:
    """The wall cost per metre above 1 at a clearance (:func:`build_costmap`'s)."""
    with np.errstate(over="ignore"):
        out: FloatArray = params.wall_weight * np.exp(
            -(np.minimum(clearance_m, 1e9) - params.inflation_m) / params.wall_decay_m
        )
    return out


def _wall_points(grid: OccupancyGrid) -> FloatArray:
    """Centres of the non-free cells with a free 4-neighbour, (K, 2) [m], the map's
    outside counting as non-free (the costmap and the collision metric count it so: a
    door in the map's edge is no way out; mission-house: a fighter drove 3 cm past the
    front door's edge, off the map)."""
    free = np.pad(np.asarray(grid.free), 1, constant_values=False)
    padded = np.pad(free, 1, constant_values=False)
    touches = padded[:-2, 1:-1] | padded[2:, 1:-1] | padded[1:-1, :-2] | padded[1:-1, 2:]
    return np.asarray(grid.center_of(np.argwhere(~free & touches) - 1))


def navigation_init(
    grid: OccupancyGrid, poses: ArrayLike, goals_m: ArrayLike, params: NavigationParams
) -> NavigationState:
    """Plan every robot's path to its goal.

    Parameters
    ----------
    grid : OccupancyGrid
        The map.
    poses : array_like, shape (N, 3)
        Start poses x [m], y [m], heading [rad].
    goals_m : array_like, shape (N, 2)
        One goal per robot [m].
    params : NavigationParams

    Returns
    -------
    NavigationState
        ``status`` says, per robot, ``"moving"`` or why it will not move:
        ``"goal_blocked"`` (the goal lies in the inflated map or off it),
        ``"start_blocked"`` (no open cell within 0.5 m of the start), ``"unreachable"``.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> occ = np.zeros((40, 60), dtype=bool)
    >>> occ[:, 30] = True
    >>> occ[18:24, 30] = False  # a 0.6 m door in a wall
    >>> grid = OccupancyGrid(occ, ~occ, 0.1)
    >>> state = navigation_init(grid, [[1.0, 2.0, 0.0]], [[5.0, 2.0]], NavigationParams())
    >>> state.status, round(state.paths[0].length_m, 1)
    (('moving',), 4.0)
    """
    p = as_float_array(poses, "poses", (None, 3))
    n = p.shape[0]
    g = np.asarray(goals_m, dtype=float)
    if g.shape != (n, 2) or not np.isfinite(g).all():
        raise InputError(
            f"goals_m must be one finite (x, y) per robot, shape ({n}, 2), got {g.shape}"
        )
    costmap = build_costmap(
        grid, params.inflation_m, wall_weight=params.wall_weight, wall_decay_m=params.wall_decay_m
    )
    plans = [_plan(costmap, p[i, :2], g[i], params) for i in range(n)]
    walls = _wall_points(grid)
    paths = tuple(path for _, path in plans)
    return NavigationState(
        costmap=costmap,
        goals_m=g.copy(),
        paths=paths,
        samples=tuple(_samples(path) for path in paths),
        progress_m=np.zeros(n),
        status=tuple(status for status, _ in plans),
        command=np.zeros((n, 2)),
        best_progress_m=np.zeros(n),
        since_s=np.zeros(n),
        stuck_count=np.zeros(n, dtype=np.int64),
        replans=np.ones(n, dtype=np.int64),
        t_s=0.0,
        wall_points_m=walls,
        target_m=g.copy(),
        aside_of=np.full(n, -1, dtype=np.int64),
        wall_tree=cKDTree(walls) if len(walls) else None,
        parked=np.zeros(n, dtype=bool),
        asked_s=np.full(n, -math.inf),
    )


def navigation_retarget(
    state: NavigationState, goals_m: ArrayLike, which: ArrayLike
) -> NavigationState:
    """Give some robots new goals without re-initialising the team.

    The robots in ``which`` drop their path (and any spot they were making way to) and
    plan from where they are to their new goal at the next :func:`navigation_step`
    (which knows their poses); the others keep their goals, paths and progress.

    Parameters
    ----------
    state : NavigationState
        From :func:`navigation_init` or a step.
    goals_m : array_like, shape (N, 2)
        Goals [m]; only the rows of ``which`` are read (they must be finite).
    which : array_like of bool, shape (N,)
        The robots to retarget.

    Returns
    -------
    NavigationState
        With ``status`` ``"moving"`` and no path for the retargeted robots.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> from firefleet.control.navigation import (
    ...     NavigationInputs, NavigationParams, navigation_init, navigation_retarget,
    ...     navigation_step)
    >>> grid = OccupancyGrid(np.zeros((40, 60), bool), np.ones((40, 60), bool), 0.1)
    >>> params = NavigationParams()
    >>> pose = np.array([[1.0, 2.0, 0.0], [1.0, 3.0, 0.0]])
    >>> state = navigation_init(grid, pose, [[5.0, 2.0], [5.0, 3.0]], params)
    >>> state = navigation_retarget(state, [[0.0, 0.0], [3.0, 3.0]], [False, True])
    >>> state.goals_m.tolist(), state.paths[1] is None
    ([[5.0, 2.0], [3.0, 3.0]], True)
    >>> state, v, w = navigation_step(state, NavigationInputs(pose, {}, pose[:, :2], 0.0),
    ...                               params, 0.1)
    >>> round(state.paths[1].length_m, 1), state.status  # planned from its pose
    (2.0, ('moving', 'moving'))
    """
    n = state.goals_m.shape[0]
    mask = np.asarray(which, dtype=bool).reshape(-1)
    if mask.shape != (n,):
        raise InputError(f"which must be {n} booleans (one per robot), got shape {mask.shape}")
    g = np.asarray(goals_m, dtype=float)
    if g.shape != (n, 2) or not np.isfinite(g[mask]).all():
        raise InputError(f"goals_m must be ({n}, 2) and finite for the retargeted robots")
    if not mask.any():
        return state
    goals = state.goals_m.copy()
    goals[mask] = g[mask]
    target = state.target_m.copy()
    target[mask] = g[mask]
    status = list(state.status)
    paths = list(state.paths)
    samples = list(state.samples)
    for i in map(int, np.flatnonzero(mask)):
        status[i] = "moving"
        paths[i] = None
        samples[i] = _samples(None)
    progress = state.progress_m.copy()
    progress[mask] = 0.0
    best = state.best_progress_m.copy()
    best[mask] = 0.0
    since = state.since_s.copy()
    since[mask] = -math.inf  # the next step plans at once
    stuck = state.stuck_count.copy()
    stuck[mask] = 0
    aside = state.aside_of.copy()
    aside[mask] = -1
    parked = np.zeros(n, dtype=bool) if state.parked is None else state.parked.copy()
    parked[mask] = False
    return replace(
        state,
        parked=parked,
        goals_m=goals,
        target_m=target,
        status=tuple(status),
        paths=tuple(paths),
        samples=tuple(samples),
        progress_m=progress,
        best_progress_m=best,
        since_s=since,
        stuck_count=stuck,
        aside_of=aside,
    )
