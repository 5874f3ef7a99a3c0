"""The team's state and its start: :class:`TacticsState`, :func:`tactics_init`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.mission._coverage import CoarseMap, coarse_map
from firefleet.control.mission._knowledge import Knowledge, empty_knowledge, fires_of
from firefleet.control.mission._params import EXPLORE, Orders, TacticsParams, team_refill_points
from firefleet.control.navigation import Costmap, NavigationState, navigation_init
from firefleet.errors import InputError, as_float_array
from firefleet.world import OccupancyGrid

__all__ = ["TacticsState", "tactics_init"]


@dataclass(frozen=True, eq=False)
class TacticsState:
    """The team's state (returned anew by every step).

    Attributes
    ----------
    coarse : CoarseMap
        The coarse grid the team decides on.
    nav : NavigationState
        The navigation controller's state (every robot's goal and path).
    knowledge : Knowledge
        Fires (as burning spots) and victims believed.
    covered_coarse : ndarray of bool, shape (Hc, Wc)
        Coarse cells a thermal camera has covered.
    excluded : ndarray of bool, shape (Hc, Wc)
        Frontier cells found unreachable.
    mode : ndarray of int8, shape (N,)
        Index in :data:`MODES`.
    task_fire : ndarray of int, shape (N,)
        Fire id each robot fights (-1: none).
    task_victim : ndarray of int, shape (N,)
        Victim index each robot confirms (-1: none).
    goal_xy_m : ndarray, shape (N, 2)
        Each robot's goal [m] (NaN: none).
    explore_cell : ndarray of int, shape (N, 2)
        Each explorer's frontier target (coarse row, col; -1: none).
    refill_spot : ndarray of int, shape (N,)
        Index in ``refill_spots_m`` of each refilling robot's spot (-1: none).
    refill_spots_m : ndarray, shape (K, 2)
        Spots around the refill points [m] (each point's, nearest it first).
    refilling : ndarray of bool, shape (N,)
        Robots standing at their refill spot: the kind fills their tanks at
        ``refill_l_s`` (up to ``tank_l``) while this holds.
    known_damaged : ndarray of bool, shape (N,)
        Robots the team has dropped (damaged or dead).
    closest_m, closest_s : ndarray, shape (N,)
        The stall watchdog: each robot's least distance to its goal so far [m], and
        when it last came 0.2 m closer [s]. An explorer that has not for ``stall_s``
        gives its frontier up (it joins ``excluded``) and the team re-plans.
    shot_s : ndarray, shape (N,)
        When each fighter last had a shot at its fire, or last moved [s]: one that
        stands ``reslot_s`` without one gets a new slot.
    hot_xy_m : ndarray, shape (K, 2)
        Places where a robot's air reached ``retreat_c`` [m]: slots keep ``standoff_m``
        from them.
    pending : bool
        A detection or a robot's state changed since the last allocation.
    last_plan_s, next_coverage_s, next_nav_s : float
        When the team last planned, and when it next updates coverage and commands [s].
    orders : Orders
        The orders held until the next navigation period.
    messages_sent : int
        Messages the team's knowledge took (every detection shared, every robot's
        assignment after each allocation).
    memo : dict of int to ndarray
        A cache of travel-distance fields by source cell (changes no result).
    base_costmap : Costmap
        The map's navigation costmap without the fires (``nav.costmap`` adds
        ``fire_cost`` per metre within ``fire_keepout_m`` of every burning spot, so that
        paths go round fires where there is another way).
    t_s : float
        Time of the last step that changed anything [s] (a quiet tick returns the state
        as it was).
    hot_s : ndarray, shape (K,)
        When each of ``hot_xy_m`` was last marked [s] (slots keep from a hot place
        only for ``hot_forget_s`` after; empty: none marked yet).
    fire_seen_s : ndarray, shape (Hc, Wc) or (0, 0)
        When a thermal camera last had each coarse cell in view [s] (the fire's
        frontier, :mod:`._scout`; (0, 0): none yet).
    air_prev_c : ndarray, shape (N,) or (0,)
        The probes' readings the air's slope is taken from [C], and ``air_prev_s``
        their time [s] (:func:`._hot.probe_estimate`).
    """

    coarse: CoarseMap
    nav: NavigationState
    knowledge: Knowledge
    covered_coarse: BoolArray
    excluded: BoolArray
    mode: np.ndarray
    task_fire: IntArray
    task_victim: IntArray
    goal_xy_m: FloatArray
    explore_cell: IntArray
    refill_spot: IntArray
    refill_spots_m: FloatArray
    refilling: BoolArray
    known_damaged: BoolArray
    closest_m: FloatArray
    closest_s: FloatArray
    shot_s: FloatArray
    hot_xy_m: FloatArray
    pending: bool
    last_plan_s: float
    next_coverage_s: float
    next_nav_s: float
    orders: Orders
    messages_sent: int
    memo: dict[int, FloatArray]
    base_costmap: Costmap
    t_s: float
    hot_s: FloatArray = field(default_factory=lambda: np.zeros(0))
    fire_seen_s: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))
    air_prev_c: FloatArray = field(default_factory=lambda: np.zeros(0))
    air_prev_s: float = -np.inf
    refill_group: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    """The refill point of each spot of ``refill_spots_m`` (K,) (empty: all one point)."""

    @property
    def covered(self) -> BoolArray:
        """Map cells covered by a thermal camera, shape (H, W) (computed on access)."""
        f = self.coarse.factor
        h, w = self.coarse.grid.shape
        out: BoolArray = np.repeat(np.repeat(self.covered_coarse, f, axis=0), f, axis=1)[:h, :w]
        return out

    @property
    def explored_frac(self) -> float:
        """Fraction of the map's free cells covered (0 to 1): the free map cells of the
        covered coarse cells (equal to ``(covered & grid.free).sum() / grid.free.sum()``,
        without building the map-sized array)."""
        count = self.coarse.free_count
        return float(count[self.covered_coarse].sum() / max(int(count.sum()), 1))

    @property
    def fires_xy_m(self) -> FloatArray:
        """Believed fires [m], shape (F, 2) (the mean of each fire's spots)."""
        return fires_of(self.knowledge)[1]

    @property
    def fire_extent_m(self) -> FloatArray:
        """Each believed fire's extent: largest distance of a spot from its position [m]."""
        return fires_of(self.knowledge)[2]

    @property
    def victims_xy_m(self) -> FloatArray:
        """Victims detected [m], shape (V, 2)."""
        return self.knowledge.victim_xy_m

    @property
    def victims_confirmed(self) -> BoolArray:
        """Whether each victim is confirmed (found), shape (V,)."""
        return self.knowledge.victim_confirmed

    @property
    def victims_confirmed_s(self) -> FloatArray:
        """When each victim was confirmed [s] (NaN: not yet), shape (V,)."""
        return self.knowledge.victim_confirmed_s

    @property
    def assignment(self) -> IntArray:
        """Each robot's task, shape (N,): ``f`` < F the believed fire ``f`` (in
        :attr:`fires_xy_m`' order), ``F + v`` the victim ``v`` (:attr:`victims_xy_m`),
        -1 none (exploring, refilling, idle, damaged)."""
        ids = fires_of(self.knowledge)[0]
        out = np.full(len(self.mode), -1, dtype=np.int64)
        fire = self.task_fire >= 0
        if fire.any() and len(ids):
            pos = np.clip(np.searchsorted(ids, self.task_fire[fire]), 0, len(ids) - 1)
            ok = ids[pos] == self.task_fire[fire]
            out[np.flatnonzero(fire)[ok]] = pos[ok]
        vic = self.task_victim >= 0
        out[vic] = len(ids) + self.task_victim[vic]
        return out


def _refill_spots(cm: CoarseMap, point: FloatArray, radius_m: float, gap_m: float) -> FloatArray:
    """Standable goal points within ``radius_m`` of the refill point, nearest first,
    greedily kept ``gap_m`` apart; at least the nearest standable point."""
    rc = np.argwhere(cm.standable)
    xy = cm.goal_xy(rc)
    d = np.hypot(xy[:, 0] - point[0], xy[:, 1] - point[1])
    order = np.argsort(d, kind="stable")
    spots: list[FloatArray] = []
    for k in order:
        if d[k] > radius_m and spots:
            break
        if all(np.hypot(*(xy[k] - s)) >= gap_m for s in spots):
            spots.append(xy[k])
        if d[k] > radius_m:
            break
    return np.asarray(spots, dtype=float).reshape(-1, 2)


def tactics_init(grid: OccupancyGrid, poses: ArrayLike, params: TacticsParams) -> TacticsState:
    """The team before its first step: nothing covered, nothing known, every robot
    exploring from where it stands.

    Parameters
    ----------
    grid : OccupancyGrid
        The building's map (known to the team: the plans a fire brigade carries).
    poses : array_like, shape (N, 3)
        Start poses x [m], y [m], heading [rad].
    params : TacticsParams

    Returns
    -------
    TacticsState

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import load_map
    >>> from firefleet.control.mission import TacticsParams, tactics_init
    >>> state = tactics_init(load_map("office"), [[1.0, 1.0, 0.0], [1.0, 2.0, 0.0]],
    ...                      TacticsParams())
    >>> state.covered.shape, bool(state.covered.any()), state.coarse.cell_m
    ((200, 400), False, 0.25)
    """
    p = as_float_array(poses, "poses", (None, 3))
    n = p.shape[0]
    if n == 0:
        raise InputError("poses: the team needs at least one robot, got none")
    off = ~grid.contains(p[:, :2])
    if off.any():
        i = int(np.flatnonzero(off)[0])
        raise InputError(f"poses[{i}] = {p[i, :2].tolist()} lies off the map {grid.name!r}")
    nav = navigation_init(grid, p, p[:, :2], params.nav)
    cm = coarse_map(nav.costmap, params.plan_cell_m)
    points = team_refill_points(params.refill_xy_m, p)
    off_map = ~grid.contains(points)
    if off_map.any():  # given points only: the poses' centroid lies on the map with them
        bad = points[int(np.flatnonzero(off_map)[0])].tolist()
        raise InputError(f"tactics.refill_xy_m: {bad} lies off the map {grid.name!r}")
    gap = 2.0 * params.nav.robot_radius_m + params.nav.margin_m + 0.15
    per_point = [_refill_spots(cm, point, params.refill_radius_m, gap) for point in points]
    spots = np.concatenate(per_point)
    group = np.repeat(np.arange(len(points)), [len(k) for k in per_point])
    hc, wc = cm.shape
    zero_n = np.zeros(n)
    orders = Orders(
        v_m_s=zero_n.copy(),
        omega_rad_s=zero_n.copy(),
        spray=np.zeros(n, dtype=bool),
        mode=np.full(n, EXPLORE, dtype=np.int8),
        goal_xy_m=np.full((n, 2), np.nan),
    )
    return TacticsState(
        coarse=cm,
        nav=nav,
        knowledge=empty_knowledge(),
        covered_coarse=np.zeros((hc, wc), dtype=bool),
        excluded=np.zeros((hc, wc), dtype=bool),
        mode=np.full(n, EXPLORE, dtype=np.int8),
        task_fire=np.full(n, -1, dtype=np.int64),
        task_victim=np.full(n, -1, dtype=np.int64),
        goal_xy_m=np.full((n, 2), np.nan),
        explore_cell=np.full((n, 2), -1, dtype=np.int64),
        refill_spot=np.full(n, -1, dtype=np.int64),
        refill_spots_m=spots,
        refilling=np.zeros(n, dtype=bool),
        known_damaged=np.zeros(n, dtype=bool),
        closest_m=np.full(n, np.inf),
        closest_s=np.zeros(n),
        shot_s=np.zeros(n),
        hot_xy_m=np.zeros((0, 2)),
        pending=True,
        last_plan_s=-np.inf,
        next_coverage_s=-np.inf,
        next_nav_s=-np.inf,
        orders=orders,
        messages_sent=0,
        memo={},
        base_costmap=nav.costmap,
        t_s=-np.inf,
        refill_group=group,
    )
