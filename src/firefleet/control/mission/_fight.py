"""Where the fighters stand: the fire's costmap (paths round the fires) and the ring's
slots with a shot at the fire (:mod:`._ring`)."""

from __future__ import annotations

import math

import numpy as np
import scipy.ndimage as ndi

from firefleet._frozen import replace
from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.mission._coverage import CoarseMap, clear_sight
from firefleet.control.mission._discs import disc_cells
from firefleet.control.mission._hot import live_hot
from firefleet.control.mission._knowledge import fires_of, seen_point
from firefleet.control.mission._near import any_within
from firefleet.control.mission._params import TacticsParams
from firefleet.control.mission._ring import has_shot, ring_slots
from firefleet.control.mission._scout import scout_goals
from firefleet.control.mission._team import TacticsState
from firefleet.control.mission._water import add_water, cone_cells, soaked_at, wets_flames
from firefleet.control.navigation import Costmap
from firefleet.world import OccupancyGrid

__all__ = [
    "coarse_on",
    "dry_flames",
    "fight_goals",
    "fight_through",
    "fire_costmap",
    "flame_guard",
    "flame_reach",
    "known_clear",
    "shot_limits_m",
]


def _reachable(blocked: BoolArray, grid: OccupancyGrid, xy_m: FloatArray) -> BoolArray:
    """Map cells connected (8-neighbours) through unblocked cells to any of the points
    (M, 2) [m]: where the robots there can plan to. A point on a blocked cell counts
    from the open cell nearest it (its way out: a robot near a fire can always leave).

    A robot's own way out opens nothing for the others: with every cell within 1 m of a
    robot let through, a fighter standing in a burning room's doorway opened the door,
    and its teammate in the corridor was sent to a slot in the room (mission-office
    seed 2, 127 s; damaged in the door at 149 s).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> walls = np.zeros((3, 9), dtype=bool)
    >>> grid = OccupancyGrid(walls, ~walls, resolution_m=1.0)
    >>> blocked = np.zeros((3, 9), dtype=bool)
    >>> blocked[:, 3:6] = True  # a burning door, 3 cells wide, between two rooms
    >>> reach = _reachable(blocked, grid, np.array([[3.5, 1.5], [0.5, 1.5]]))  # in it, west
    >>> reach[1].astype(int).tolist()  # the one in the door leaves west (nearest open cell)
    [1, 1, 1, 0, 0, 0, 0, 0, 0]
    """
    free = ~np.asarray(blocked)
    labels, n = ndi.label(free, structure=np.ones((3, 3), dtype=bool))
    rc = grid.cell_of(np.asarray(xy_m, dtype=float).reshape(-1, 2))
    h, w = free.shape
    rc = np.stack([np.clip(rc[:, 0], 0, h - 1), np.clip(rc[:, 1], 0, w - 1)], axis=-1)
    lab = labels[rc[:, 0], rc[:, 1]]
    if n and (lab == 0).any():
        _, (ri, ci) = ndi.distance_transform_edt(~free, return_indices=True)
        out_rc = rc[lab == 0]
        lab[lab == 0] = labels[ri[out_rc[:, 0], out_rc[:, 1]], ci[out_rc[:, 0], out_rc[:, 1]]]
    lab = lab[lab > 0]
    out: BoolArray = np.isin(labels, lab) if len(lab) else free
    return out


def flame_reach(state: TacticsState, xy_m: FloatArray, params: TacticsParams) -> BoolArray:
    """Map cells (H, W) the robots at ``xy_m`` (M, 2) [m] reach without crossing the
    cells within ``fire_block_m`` of a flame the team believes (a robot among them
    counts from its way out, :func:`_reachable`).

    Every believed flame counts, soaked ones too, until a look finds it out: a soaked
    door is no way in while the room behind it burns (mission-office seeds 0, 1, 3, 4:
    fighters sent through a door whose flames the ledger held soaked were damaged in it
    at 123-349 s; the house, seed 2: an explorer sent to search the room behind such a
    door was damaged in it at 280 s with a full tank, and its wreck shut the room's only
    door for the rest of the run).
    """
    blocked = np.array(state.nav.costmap.blocked)
    grid = state.nav.costmap.grid
    if params.fire_block_m > 0.0:
        k = state.knowledge
        blocked |= disc_cells(grid, k.spot_xy_m[k.spot_flame], params.fire_block_m)
    return _reachable(blocked, grid, xy_m)


def coarse_on(cm: CoarseMap, mask: BoolArray) -> BoolArray:
    """Coarse cells (Hc, Wc) whose goal cell (the map cell a robot sent there aims at)
    lies on the map cells of ``mask`` (H, W); cells without one: no."""
    gc = cm.goal_cell
    out: BoolArray = (gc[..., 0] >= 0) & mask[np.maximum(gc[..., 0], 0), np.maximum(gc[..., 1], 0)]
    return out


def _aim_spots(state: TacticsState, fire: int, params: TacticsParams) -> tuple[FloatArray, bool]:
    """The spots of a fire its fighters aim at: its flames on cells the team has not
    soaked (:mod:`._water`) when it has any, else its flames, else all its spots; and
    whether they are flames not soaked."""
    k = state.knowledge
    mine = k.spot_fire == fire
    found = False
    if (mine & k.spot_flame).any():
        mine &= k.spot_flame
        dry = mine & ~soaked_at(k.wet_l_m2, state.coarse, k.spot_xy_m, params.soak_l_m2)
        if dry.any():
            mine = dry
            found = True
    out: FloatArray = k.spot_xy_m[mine]
    return out, found


def _on(mask: BoolArray | None, grid: OccupancyGrid, xy_m: FloatArray) -> BoolArray:
    """Whether points (M, 2) [m] fall on ``mask``'s map cells (None: everywhere; NaN and
    points off the map: no)."""
    pts = np.asarray(xy_m, dtype=float).reshape(-1, 2)
    ok = np.isfinite(pts).all(axis=1)
    if mask is None:
        out_all: BoolArray = ok
        return out_all
    inside = ok & grid.contains(np.nan_to_num(pts))
    rc = grid.cell_of(np.nan_to_num(pts))
    h, w = grid.shape
    out: BoolArray = inside & mask[np.clip(rc[:, 0], 0, h - 1), np.clip(rc[:, 1], 0, w - 1)]
    return out


def _nearest_cell(
    cm: CoarseMap, free: BoolArray, to_xy_m: FloatArray, fallback_xy_m: FloatArray
) -> FloatArray:
    """Goal points (M, 2) [m] of the standable coarse cells of ``free`` (Hc, Wc) nearest
    each point of ``to_xy_m`` (M, 2) (NaN: nearest the fallback); the fallback points
    where no cell is free."""
    cells = np.argwhere(free & cm.standable)
    if len(cells) == 0:
        out0: FloatArray = np.array(fallback_xy_m, dtype=float, copy=True)
        return out0
    xy = cm.goal_xy(cells)
    to = np.where(np.isfinite(to_xy_m), to_xy_m, fallback_xy_m)
    d = np.hypot(to[:, None, 0] - xy[None, :, 0], to[:, None, 1] - xy[None, :, 1])
    out: FloatArray = xy[np.argmin(d, axis=1)]
    return out


def _standable(costmap: Costmap, xy_m: FloatArray) -> BoolArray:
    """Points (M, 2) [m] on the map and open in the costmap."""
    grid = costmap.grid
    inside = grid.contains(xy_m)
    rc = grid.cell_of(xy_m)
    h, w = grid.shape
    ok: BoolArray = (
        inside & ~costmap.blocked[np.clip(rc[:, 0], 0, h - 1), np.clip(rc[:, 1], 0, w - 1)]
    )
    return ok


def dry_flames(state: TacticsState, params: TacticsParams) -> FloatArray:
    """The believed flames (F, 2) [m] a robot keeps out of: those on cells the team's
    ledger does not hold soaked, and the soaked ones within ``standoff_m`` of them.

    A soaked flame with no dry one near is out and its gas cools, so a door whose
    flames the team soaked is the way in to the fire behind it; a soaked cell beside
    cells still burning lies in their gas (mission-office seeds 0 and 4, with every
    soaked flame let through: three fighters entered the fire room's door while the
    flames beside it burned, and were damaged within 2 s of their probes reading 36-80
    C). The robots' probes and cameras still mark hot places (``_upkeep.too_hot``).
    The flame guard and the aim use these; a fighter's slot is still reached only
    without passing any believed flame, soaked or not, until a look finds it out
    (:func:`fight_goals`: the room behind a soaked door may burn unseen).
    """
    k = state.knowledge
    # the last answer is kept in the map's cache with the knowledge it was for (the
    # team's knowledge is replaced, never changed in place): asked several times a tick,
    # and with a few thousand flames believed (mission-large) each answer costs tens of ms
    key = ("dry_flames", params.soak_l_m2, params.standoff_m)
    kept = state.coarse.cache.get(key)
    if isinstance(kept, tuple) and kept[0] is k:
        last: FloatArray = kept[1]
        return last
    fl = k.spot_xy_m[k.spot_flame]
    wet = soaked_at(k.wet_l_m2, state.coarse, fl, params.soak_l_m2)
    dry = fl[~wet]
    if len(dry) and wet.any():
        w = np.flatnonzero(wet)
        wet[w] = ~any_within(fl[w], dry, params.standoff_m, inclusive=True)
    out: FloatArray = fl[~wet]
    out.flags.writeable = False
    state.coarse.cache[key] = (k, out)
    return out


def known_clear(state: TacticsState, pose: FloatArray, params: TacticsParams) -> BoolArray:
    """Coarse cells (Hc, Wc) the team knows to be clear of fire now: in a thermal
    camera's view within ``scout_stale_s`` (a fire there would have been detected; the
    flames it did detect keep the slots off by themselves), within ``standoff_m`` of a
    robot (its probe reads the air there), or farther than ``spray_range_m`` from every
    fire spot the team believes.

    A fighter's slot and a scout's viewpoint lie on such cells only. The flames the team
    places are a few points of what burns: a room the fire fills is seen through its
    door as a wedge, and a ring about the flames seen in it put slots in the room's
    corners, where the fire burned unseen (mission-office seed 0 at 163 s: a fighter
    sent to a slot 1.7 m from the nearest believed flame was damaged in the door 7 s
    later).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> from firefleet.control.mission._team import tactics_init
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.world import OccupancyGrid
    >>> walls = np.zeros((20, 40), dtype=bool)
    >>> grid = OccupancyGrid(walls, ~walls, resolution_m=0.25)
    >>> p = TacticsParams()
    >>> pose = np.array([[1.0, 2.5, 0.0]])
    >>> state = tactics_init(grid, pose, p)
    >>> bool(known_clear(state, pose, p).all())  # no fire known: all clear
    True
    >>> from dataclasses import replace
    >>> k = replace(state.knowledge, spot_xy_m=np.array([[6.0, 2.5]]), spot_fire=np.array([0]),
    ...             spot_flame=np.array([True]), spot_misses=np.array([0]))
    >>> clear = known_clear(replace(state, knowledge=k), pose, p)  # nothing seen yet
    >>> bool(clear[10, 4]), bool(clear[10, 20]), bool(clear[10, 39])  # robot, fire, far
    (True, False, True)
    """
    cm = state.coarse
    seen = state.fire_seen_s
    if seen.shape == cm.shape:
        out: BoolArray = seen >= state.t_s - params.scout_stale_s
    else:
        out = np.zeros(cm.shape, dtype=bool)
    # farther than a jet's reach from every spot the team believes, nothing is known to
    # burn (a team 14 m off, with nothing near the fire in view yet, must get closer:
    # mission-smoke)
    far = ~_near_mask(cm, state.knowledge.spot_xy_m, params.spray_range_m)
    return out | far | _near_mask(cm, pose[:, :2], params.standoff_m)


def _fine(coarse: BoolArray, cm: CoarseMap, shape: tuple[int, ...]) -> BoolArray:
    """A coarse mask on the map's cells (each coarse cell is ``factor`` map cells a side)."""
    f = cm.factor
    out: BoolArray = np.repeat(np.repeat(coarse, f, axis=0), f, axis=1)[: shape[0], : shape[1]]
    return out


def _near_mask(cm: CoarseMap, xy_m: FloatArray, radius_m: float) -> BoolArray:
    """Coarse cells within ``radius_m`` of any point (K, 2) [m] (Hc, Wc)."""
    out = np.zeros(cm.shape, dtype=bool)
    pts = np.asarray(xy_m, dtype=float).reshape(-1, 2)
    if len(pts) == 0:
        return out
    rc = cm.cell_of(pts)
    out[rc[:, 0], rc[:, 1]] = True
    near: BoolArray = ndi.distance_transform_edt(~out) * cm.cell_m <= radius_m
    return near


def shot_limits_m(params: TacticsParams) -> tuple[float, float]:
    """Nearest and farthest a fighter's shot may be [m]: a quarter metre outside the
    cells paths never enter (``fire_block_m``), and half a metre inside the nozzle's
    reach (a spot is where a detection put the flames, within the detector's error)."""
    return params.fire_block_m + 0.25, max(params.spray_range_m - 0.5, 0.5 * params.spray_range_m)


def fight_goals(
    state: TacticsState,
    pose: FloatArray,
    task_fire: IntArray,
    old_fire: IntArray,
    goals: FloatArray,
    params: TacticsParams,
) -> None:
    """Ring slots of every fought fire into ``goals`` (kept while its team is unchanged
    and every slot is set)."""
    ids, _, _ = fires_of(state.knowledge)
    reach: BoolArray | None = None
    clear: BoolArray | None = None  # known_clear, once per call (with reach)
    # every flame the team believes, soaked ones too
    flames_all = state.knowledge.spot_xy_m[state.knowledge.spot_flame]
    near_m, shot_m = shot_limits_m(params)
    for fid in ids:
        team = np.flatnonzero(task_fire == fid)
        if len(team) == 0:
            continue
        same = np.all(old_fire[team] == fid) and np.sum(old_fire == fid) == len(team)
        if same and np.isfinite(goals[team, 0]).all():
            continue
        if reach is None:
            reach = flame_reach(state, pose[:, :2], params)
            clear = known_clear(state, pose, params)
            reach &= _fine(clear, state.coarse, reach.shape)
        # the ring about the spots aimed at (the flames; not the hot gas, which a fire
        # pushes metres out of its room: mission-office seed 1, a ring about the gas in
        # the corridor put a fighter in the next room, without a shot, for 50 s)
        aim, dry = _aim_spots(state, fid, params)
        avoid = live_hot(state.hot_xy_m, state.hot_s, state.t_s, params.hot_forget_s)

        if dry:
            flames = state.knowledge.spot_xy_m[state.knowledge.spot_flame]
            goals[team] = _ring(state, pose[team, :2], aim, avoid, reach, params, flames)
            # a slot left in a wall, out of reach or of the known clear floor, or
            # without a shot (none was found): look instead
            slots = goals[team]
            lost = (
                ~_standable(state.nav.costmap, slots)
                | ~_on(reach, state.nav.costmap.grid, slots)
                | ~has_shot(state.coarse, slots, aim, near_m, shot_m)
            )
        else:
            lost = np.ones(len(team), dtype=bool)  # every flame believed soaked: look
        if lost.any():
            cm = state.coarse
            mine = state.knowledge.spot_xy_m[state.knowledge.spot_fire == fid]
            # every flame of the team's, soaked ones too: the gas by a soaked door may
            # still be deadly (mission-office seed 0, 153 s: the door's flames soaked,
            # the room behind it burning, a fighter sent to look from the doorway was
            # damaged there)
            keep_off = _near_mask(cm, flames_all, params.scout_near_m)
            if clear is not None and reach is not None:  # known clear, and reachable
                keep_off |= ~clear | ~coarse_on(cm, reach)
            keep_off |= _near_mask(cm, avoid, params.standoff_m)
            look = scout_goals(
                cm,
                state.fire_seen_s,
                state.t_s,
                mine,
                pose[team[lost], :2],
                keep_off,
                params.scout_m,
                params.scout_stale_s,
                params.scout_near_m,
                params.scout_far_m,
            )
            ok = np.isfinite(look[:, 0])
            idx = team[lost]
            goals[idx[ok]] = look[ok]
            rest = idx[~ok]
            if not dry and len(rest):
                # nothing left to look at: the ring about the (soaked) flames, as before
                goals[rest] = _ring(state, pose[rest, :2], aim, avoid, reach, params)
            if len(rest):
                # no valid slot and nothing to look from: the nearest place to its slot
                # it can reach, known clear and standoff_m from every believed flame
                # (standing where it was let the fire reach two fighters on
                # mission-warehouse seed 0; a slot kept in a room the fire filled sent
                # fighters through its door on mission-office)
                bad = ~_standable(state.nav.costmap, goals[rest]) | ~_on(
                    reach, state.nav.costmap.grid, goals[rest]
                )
                if bad.any():
                    free = ~keep_off & ~_near_mask(cm, flames_all, params.standoff_m)
                    goals[rest[bad]] = _nearest_cell(
                        cm, free, goals[rest[bad]], pose[rest[bad], :2]
                    )


def _ring(
    state: TacticsState,
    robots_xy_m: FloatArray,
    aim: FloatArray,
    avoid: FloatArray,
    reach: BoolArray | None,
    params: TacticsParams,
    clear_xy_m: FloatArray | None = None,
) -> FloatArray:
    """Slots (R, 2) for robots at ``robots_xy_m`` on the ring about the spots aimed at
    (:func:`._ring.ring_slots`: ``standoff_m`` beyond the spots' extent, clear of the hot
    places ``avoid`` and of ``clear_xy_m``)."""
    near_m, shot_m = shot_limits_m(params)
    centre = aim.mean(axis=0)
    radius = float(np.hypot(*(aim - centre).T).max()) + params.standoff_m
    return ring_slots(
        state.coarse,
        state.nav.costmap,
        centre,
        radius,
        robots_xy_m,
        spots_xy_m=aim,
        reachable=reach,
        near_m=near_m,
        shot_m=shot_m,
        gap_m=2.0 * params.nav.robot_radius_m + params.nav.margin_m + 0.15,
        avoid_xy_m=avoid,
        avoid_m=params.standoff_m,
        clear_xy_m=clear_xy_m,
    )


def fire_costmap(state: TacticsState, pose: FloatArray, params: TacticsParams) -> TacticsState:
    """The navigation costmap round the fires: ``fire_cost`` more per metre within
    ``fire_keepout_m`` of every burning spot (A* goes round a fire where it can), and
    ten times that within ``fire_block_m`` of one (paths cross there only where there
    is no other way: a hard block trapped robots behind the spots a fire put at a door,
    mission-office seed 2; the slots never lie there, :func:`fight_goals`)."""
    base = state.base_costmap
    spots = state.knowledge.spot_xy_m
    if len(spots) == 0:
        if state.nav.costmap is base:
            return state
        return replace(state, nav=replace(state.nav, costmap=base))
    grid = base.grid
    near = disc_cells(grid, spots, params.fire_keepout_m)
    cost = np.where(near, base.cost + params.fire_cost, base.cost)
    if params.fire_block_m > 0.0:
        hot = disc_cells(grid, spots, params.fire_block_m) & ~base.blocked
        cost[hot] += 10.0 * params.fire_cost
    cost.setflags(write=False)
    costmap = Costmap(base.grid, base.clearance_m, base.blocked, cost, base.inflation_m)
    return replace(state, nav=replace(state.nav, costmap=costmap))


def flame_guard(
    v_m_s: FloatArray,
    omega_rad_s: FloatArray,
    pose: FloatArray,
    flames_xy_m: FloatArray,
    guard_m: float,
    half_angle_rad: float,
    omega_max_rad_s: float,
    cm: CoarseMap | None = None,
) -> tuple[FloatArray, FloatArray]:
    """The commands with every robot stopped that would drive at flames nearer than
    ``guard_m`` within ``half_angle_rad`` of its heading (it turns away instead).

    Given the plan's coarse map, only flames in the robot's sight hold it
    (:func:`flames_in_sight`): a wall between keeps the heat out. Held by a flame
    behind the wall of the hallway it stood in, a fighter stood turning to and fro for
    200 s while the fire burned on in the room (the house, seed 2, 700-900 s: the flame
    long out, the team's belief of it never looked at again).

    The air within half a metre of a burning cell is hotter than a robot's rating
    (mission-office, seed 1: 90 % of the cells hotter than 720 C, the field whose
    lower layer reaches 300 C, burn; the others lie at most 0.5 m from one), and a path
    through a burning door is the shortest way to a slot in the room behind it. The
    navigation plans round the flames where it can (:func:`fire_costmap`); this keeps
    the robot out where it cannot.

    Parameters
    ----------
    v_m_s, omega_rad_s : ndarray, shape (N,)
        The navigation's commands.
    pose : ndarray, shape (N, 3)
    flames_xy_m : ndarray, shape (F, 2)
        Where the team believes flames burn [m].
    guard_m, half_angle_rad : float
    omega_max_rad_s : float
    cm : CoarseMap, optional
        The plan's coarse map: flames out of sight do not hold (None: every flame).

    Returns
    -------
    v_m_s, omega_rad_s : ndarray, shape (N,)
        New arrays.

    Examples
    --------
    >>> import numpy as np
    >>> v, w = flame_guard(np.array([0.3, 0.3]), np.zeros(2), np.array([[0.0, 0.0, 0.0],
    ...     [0.0, 1.0, np.pi]]), np.array([[0.5, 0.1]]), 0.8, np.radians(60.0), 1.0)
    >>> v.tolist(), w.tolist()  # the first drives at it and turns away; the second away
    ([0.0, 0.3], [-0.5, 0.0])
    """
    v = np.array(v_m_s, dtype=float, copy=True)
    w = np.array(omega_rad_s, dtype=float, copy=True)
    f = np.asarray(flames_xy_m, dtype=float).reshape(-1, 2)
    if len(f) == 0:
        return v, w
    dx = f[None, :, 0] - pose[:, None, 0]
    dy = f[None, :, 1] - pose[:, None, 1]
    off = (np.arctan2(dy, dx) - pose[:, None, 2] + np.pi) % (2 * np.pi) - np.pi
    ahead = (np.hypot(dx, dy) <= guard_m) & (np.abs(off) <= half_angle_rad)
    for i in map(int, np.flatnonzero(ahead.any(axis=1) & (v > 0.0))):
        if cm is not None:
            j = np.flatnonzero(ahead[i])
            ahead[i, j] = flames_in_sight(cm, pose[i, :2], f[j])
            if not ahead[i].any():
                continue
        v[i] = 0.0
        if abs(w[i]) < 0.2 * omega_max_rad_s:
            nearest = int(np.argmin(np.where(ahead[i], np.hypot(dx[i], dy[i]), np.inf)))
            w[i] = -math.copysign(0.5 * omega_max_rad_s, float(off[i, nearest]))
    return v, w


def flames_in_sight(cm: CoarseMap, xy_m: FloatArray, flames_xy_m: FloatArray) -> BoolArray:
    """Which flames (F, 2) [m] a robot at ``xy_m`` (2,) has in sight: no opaque coarse
    cell between it and the flame's point, or the face of the wall the point lies in
    (:func:`._knowledge.seen_point`; a detection a little deep puts a flame by a wall
    inside it), the two ends' cells excepted (:func:`._coverage.clear_sight`).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> from firefleet.control.navigation import build_costmap
    >>> occ = np.zeros((40, 80), bool); occ[:, 38:42] = True   # a wall at x = 1.9-2.1 m
    >>> cm = coarse_map(build_costmap(OccupancyGrid(occ, ~occ, 0.05), 0.2), 0.25)
    >>> flames = np.array([[2.4, 1.0], [1.5, 1.3], [1.95, 1.0], [2.05, 1.0]])
    >>> flames_in_sight(cm, np.array([1.5, 1.0]), flames).tolist()  # in the wall: its side
    [False, True, True, False]
    """
    f = np.asarray(flames_xy_m, dtype=float).reshape(-1, 2)
    a = np.broadcast_to(np.asarray(xy_m, dtype=float)[:2], f.shape)
    out: BoolArray = clear_sight(cm, a, f)
    face = seen_point(cm, f)
    moved = np.flatnonzero((face != f).any(axis=1) & ~out)  # in a wall, not yet in sight
    out[moved] = clear_sight(cm, a[moved], face[moved])
    return out


def fight_through(
    pose: FloatArray,
    flames_xy_m: FloatArray,
    wet_l_m2: FloatArray,
    cm: CoarseMap,
    params: TacticsParams,
) -> tuple[float, bool, FloatArray]:
    """A fighter the flame guard holds (:func:`flame_guard`) with water in its tank:
    it faces the nearest flame that holds it and sprays it when the cone wets a dry
    cell by the flames, so that the way opens as the ledger soaks them (one held
    turning away from the flames about it, its way out through them, stood in the fire
    room for 80 s and was damaged: mission-office seed 4).

    Parameters
    ----------
    pose : ndarray, shape (3,)
        The fighter's estimated pose.
    flames_xy_m : ndarray, shape (F, 2)
        The flames the guard keeps it from [m] (:func:`dry_flames`).
    wet_l_m2 : ndarray, shape (Hc, Wc) or (0, 0)
        The team's ledger [L/m^2].
    cm : CoarseMap
    params : TacticsParams

    Returns
    -------
    omega_rad_s : float
        Its turn rate.
    spray : bool
        Whether it sprays.
    wet_l_m2 : ndarray
        The ledger after the spray (the input when it does not spray).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> from firefleet.control.mission._params import TacticsParams
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.world import OccupancyGrid
    >>> walls = np.zeros((40, 40), dtype=bool)
    >>> cm = coarse_map(build_costmap(OccupancyGrid(walls, ~walls, resolution_m=0.25), 0.1), 0.25)
    >>> p = TacticsParams()
    >>> flame = np.array([[5.0, 5.5]])  # 0.5 m ahead, 30 deg to the left
    >>> w, on, wet = fight_through(np.array([4.57, 5.25, 0.0]), flame, np.zeros((0, 0)), cm, p)
    >>> bool(w > 0.0), on  # turns to it; not yet facing it
    (True, False)
    >>> w, on, wet = fight_through(np.array([4.57, 5.25, np.pi / 6]), flame, wet, cm, p)
    >>> on, bool(wet.max() > 0.0)
    (True, True)
    """
    f = np.asarray(flames_xy_m, dtype=float).reshape(-1, 2)
    w_max = params.nav.dwa.omega_max_rad_s
    d = np.hypot(f[:, 0] - pose[0], f[:, 1] - pose[1])
    if len(f) and d.min() <= params.flame_guard_m:  # the flames that hold it: in sight
        d = np.where(flames_in_sight(cm, pose[:2], f), d, np.inf)
    if len(f) == 0 or d.min() > params.flame_guard_m:
        return 0.0, False, wet_l_m2
    near = f[int(np.argmin(d))]
    err = float(
        (math.atan2(near[1] - pose[1], near[0] - pose[0]) - pose[2] + math.pi) % (2 * math.pi)
        - math.pi
    )
    omega = float(np.clip(params.face_gain * err, -w_max, w_max))
    half = params.spray_half_angle_rad
    if abs(err) > half:
        return omega, False, wet_l_m2
    rows, cols = cone_cells(cm, pose, params.spray_range_m, half)
    if not wets_flames(wet_l_m2, cm, rows, cols, f, params.soak_l_m2, params.front_m):
        return omega, False, wet_l_m2
    return omega, True, add_water(wet_l_m2, cm, rows, cols, params.flow_l_s * params.nav_period_s)
