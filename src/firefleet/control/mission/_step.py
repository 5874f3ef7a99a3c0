"""One tick of the team: :func:`tactics_step` (the stages are in the package notes)."""

from __future__ import annotations

import math

import numpy as np
import scipy.ndimage as ndi

from firefleet._frozen import replace
from firefleet._typing import BoolArray, FloatArray
from firefleet.control.mission._coverage import (
    CoarseMap,
    cone_coverage,
    viewpoints,
)
from firefleet.control.mission._explore import explore_views, scan_turn
from firefleet.control.mission._fight import (
    coarse_on,
    dry_flames,
    fight_goals,
    fight_through,
    fire_costmap,
    flame_guard,
    flame_reach,
)
from firefleet.control.mission._hot import probe_estimate
from firefleet.control.mission._keepout import heat_costmap
from firefleet.control.mission._knowledge import fires_of, update_knowledge, watch_victims
from firefleet.control.mission._params import (
    CONFIRM,
    DAMAGED,
    EXPLORE,
    FIGHT,
    IDLE,
    REFILL,
    Orders,
    TacticsObservation,
    TacticsParams,
)
from firefleet.control.mission._people import confirm_sight
from firefleet.control.mission._plan import (
    allocate,
    cut_demand,
    fire_demand,
    task_distances,
)
from firefleet.control.mission._quiet import EPS_S as _EPS_S
from firefleet.control.mission._quiet import is_quiet
from firefleet.control.mission._scout import seen_update
from firefleet.control.mission._spare import spare_demand
from firefleet.control.mission._team import TacticsState
from firefleet.control.mission._upkeep import (
    dropped,
    refill_wait,
    retarget,
    tank_changes,
    too_hot,
    watchdog,
)
from firefleet.control.mission._water import (
    add_water,
    aim_wets,
    cone_cells,
    front_aim,
    wets_flames,
)
from firefleet.control.navigation import (
    NavigationInputs,
    navigation_retarget,
    navigation_step,
)
from firefleet.errors import InputError, as_float_array

__all__ = ["tactics_step"]


def _next(due_s: float, period_s: float, t_s: float) -> float:
    """The next due time after ``t_s``: on the period's grid, or a period from now when
    the step fell behind (or at the start)."""
    nxt = due_s + period_s
    return nxt if nxt > t_s + _EPS_S else t_s + period_s


def _wrap(a: FloatArray) -> FloatArray:
    out: FloatArray = (a + np.pi) % (2.0 * np.pi) - np.pi
    return out


def _near_fire(cm: CoarseMap, spots_xy_m: FloatArray, radius_m: float) -> BoolArray:
    """Coarse cells within ``radius_m`` of a burning spot, shape (Hc, Wc): no explorer's
    target (the hot gas by a fire damages a robot; the fire's robots go there)."""
    out = np.zeros(cm.shape, dtype=bool)
    if len(spots_xy_m) == 0 or radius_m <= 0.0:
        return out
    rc = cm.cell_of(spots_xy_m)
    out[rc[:, 0], rc[:, 1]] = True
    dist: FloatArray = ndi.distance_transform_edt(~out) * cm.cell_m
    near: BoolArray = dist <= radius_m
    return near


def _plan(
    state: TacticsState,
    pose: FloatArray,
    tank: FloatArray,
    working: BoolArray,
    params: TacticsParams,
) -> TacticsState:
    """Allocate fires and victims, then frontiers to the robots left (``_plan`` notes)."""
    state = heat_costmap(fire_costmap(state, pose, params), params)
    n = len(pose)
    k = state.knowledge
    ids, fxy, fext = fires_of(k)
    n_fires = len(ids)
    open_v = np.flatnonzero(~k.victim_confirmed & ~k.dismissed(params))
    task_xy = np.vstack([fxy, k.victim_xy_m[open_v]])
    need = fire_demand(fext, params)
    cm = state.coarse
    floor = int(cm.floor.sum())
    if (cm.floor & ~state.covered_coarse).sum() > 0.02 * floor and n_fires:
        # floor left to search: keep explore_frac of the team exploring
        n_work = int((working & (state.mode != REFILL)).sum())
        refilling = int((working & (state.mode == REFILL)).sum())
        need = cut_demand(need, len(open_v), n_work, params, refilling)
    if params.spare_fight:  # robots with nothing left to search join the fires (_spare)
        spare = working & (state.mode == IDLE) & (tank > 0.05 * params.tank_l)
        need = spare_demand(need, fext, ids, state.task_fire, spare, params)
    demand = np.concatenate([need, np.ones(len(open_v), dtype=np.int64)])
    is_fire = np.arange(len(task_xy)) < n_fires
    current = np.full(n, -1, dtype=np.int64)
    for i in range(n):
        if state.task_fire[i] >= 0 and np.any(ids == state.task_fire[i]):
            current[i] = int(np.flatnonzero(ids == state.task_fire[i])[0])
        elif state.task_victim[i] >= 0 and np.any(open_v == state.task_victim[i]):
            current[i] = n_fires + int(np.flatnonzero(open_v == state.task_victim[i])[0])
    mode = state.mode.copy()
    available = working & (mode != REFILL)
    alloc = np.full(n, -1, dtype=np.int64)
    if len(task_xy):
        dist = task_distances(state.coarse, state.memo, task_xy, pose[:, :2])
        alloc = allocate(dist, demand, is_fire, current, available, tank, params)
    task_fire = np.full(n, -1, dtype=np.int64)
    sel = (alloc >= 0) & (alloc < n_fires)
    task_fire[sel] = ids[alloc[sel]]
    task_victim = np.full(n, -1, dtype=np.int64)
    sel = alloc >= n_fires
    task_victim[sel] = open_v[alloc[sel] - n_fires]
    goals = state.goal_xy_m.copy()
    goals[~working] = np.nan
    # fires: the ring
    fight = task_fire >= 0
    goals[fight & (state.task_fire != task_fire)] = np.nan
    fight_goals(state, pose, task_fire, state.task_fire, goals, params)
    mode[fight] = FIGHT
    # victims: a cell in sight of them, from the camera's nearest range to the
    # confirmation radius, the nearest to the robot
    lo_m = min(params.sensing_near_m + 0.25, params.confirm_radius_m - 0.25)
    hi_m = max(lo_m + 0.15, min(params.confirm_radius_m - 0.2, params.sensing_near_m + 0.5))
    for i in map(int, np.flatnonzero(task_victim >= 0)):
        if task_victim[i] == state.task_victim[i] and np.isfinite(goals[i, 0]):
            continue
        v_xy = k.victim_xy_m[task_victim[i]][None]
        spot = viewpoints(
            cm,
            np.zeros(cm.shape, dtype=bool),
            cm.cell_of(v_xy),
            0.0,
            lo_m,
            hi_m,
            toward=cm.cell_of(pose[i : i + 1, :2]),
            look_xy_m=v_xy,
            limit_m=4.0 * params.travel_limit_m,
        )
        goals[i] = cm.goal_xy(spot)[0]
        mode[i] = CONFIRM
    mode[task_victim >= 0] = CONFIRM
    # the rest explore
    free = available & (task_fire < 0) & (task_victim < 0)
    # explorers: viewpoints chosen by the floor a turn there covers (_explore, _views)
    status = state.nav.status
    going = np.array([s in ("moving", "waiting") for s in status]) & (state.mode == EXPLORE)
    there = np.array([s == "arrived" for s in status]) & (state.mode == EXPLORE)
    hot = _near_fire(cm, k.spot_xy_m, params.explore_fire_m)
    if free.any() and k.spot_flame.any():
        # no viewpoint the explorers reach only through a believed flame, soaked or not
        # (``flame_reach``: the house, seed 2, an explorer sent through a door whose
        # flames the ledger held soaked, the room behind it burning, was damaged there)
        hot |= ~coarse_on(cm, flame_reach(state, pose[free, :2], params))
    standing = np.array([s == "arrived" for s in status]) & working & (mode != EXPLORE)
    cells = explore_views(
        cm, state.covered_coarse, pose, free, state.explore_cell, going, there,
        state.excluded | hot, params, standing & (mode != DAMAGED),
    )  # fmt: skip
    has = free & (cells[:, 0] >= 0)
    same = has & np.all(cells == state.explore_cell, axis=1) & (going | there)
    fresh = has & ~same
    goals[fresh] = cm.goal_xy(cells[fresh])
    mode[has] = EXPLORE
    idle = free & ~has
    goals[idle] = np.nan
    mode[idle] = IDLE
    new = replace(
        state,
        mode=mode,
        task_fire=task_fire.astype(np.int64),
        task_victim=task_victim.astype(np.int64),
        explore_cell=cells,
        pending=False,
        messages_sent=state.messages_sent + int(working.sum()),
    )
    return retarget(new, goals, pose)


def _orders(
    state: TacticsState, obs: TacticsObservation, pose: FloatArray, params: TacticsParams
) -> TacticsState:
    """Run the navigation controller and turn its commands into the team's orders."""
    n = len(pose)
    movable = np.asarray(obs.alive, dtype=bool) & ~np.asarray(obs.damaged, dtype=bool)
    inputs = NavigationInputs(
        pose, obs.ranges, pose[:, :2], obs.t_s, movable & (state.mode != DAMAGED)
    )
    nav, v, w = navigation_step(state.nav, inputs, params.nav, params.nav_period_s)
    mode = state.mode
    aside = nav.parked if nav.parked is not None else np.zeros(n, dtype=bool)  # making way
    # arrived, or stopped short for good (its goal blocked or out of reach)
    at_goal = np.array([s != "moving" and s != "waiting" for s in nav.status])
    arrived = at_goal
    # a fighter or confirmer that has come no closer to its spot in stall_s settles
    # where it is (navigation told it has arrived, so that no teammate waits for it)
    # (a refiller too, if that is within refill_radius_m of its spot)
    d_goal = np.hypot(pose[:, 0] - state.goal_xy_m[:, 0], pose[:, 1] - state.goal_xy_m[:, 1])
    settle = (
        (
            (mode == FIGHT)
            | (mode == CONFIRM)
            | ((mode == REFILL) & (d_goal <= params.refill_radius_m))
        )
        & ~at_goal
        & ~aside
        & (obs.t_s - state.closest_s >= params.stall_s)
    )
    w_max = params.nav.dwa.omega_max_rad_s
    pending = state.pending
    spray = np.zeros(n, dtype=bool)
    ids, fxy, _ = fires_of(state.knowledge)
    k = state.knowledge
    shot_s = np.where((mode == FIGHT) & at_goal, state.shot_s, obs.t_s)
    goals = state.goal_xy_m
    half = params.spray_half_angle_rad
    wet = k.wet_l_m2
    for i in map(int, np.flatnonzero(mode == FIGHT)):
        j = np.flatnonzero(ids == state.task_fire[i])
        if len(j) == 0:
            continue
        # aim where the cone holds the most front cells (the ledger's dry cells within
        # front_m of the flames: the flames and the fuel they reach next, a firebreak);
        # water on the hot gas a fire pushes out, or on cells already soaked, is wasted;
        # without a front cell in reach and in sight, face the fire's centre
        spots = k.spot_xy_m[(k.spot_fire == state.task_fire[i]) & k.spot_flame]
        aim = front_aim(
            wet,
            state.coarse,
            pose[i],
            spots,
            params.spray_range_m,
            half,
            params.soak_l_m2,
            params.front_m,
        )
        if aim is not None:
            target = aim
            # a shot: a flame in the jet's reach, and the cone on the aim's bearing
            # wets a dry cell at the flames (``aim_wets``: the spray's own test)
            d = np.hypot(spots[:, 0] - pose[i, 0], spots[:, 1] - pose[i, 1])
            if (d <= params.spray_range_m).any() and aim_wets(
                wet,
                state.coarse,
                pose[i, :2],
                aim,
                spots,
                params.spray_range_m,
                half,
                params.soak_l_m2,
                params.front_m,
            ):
                shot_s[i] = obs.t_s
                # held up on its way (no closer in the navigation's stuck time) with a
                # shot already: it stops there and sprays
                stood = obs.t_s - state.closest_s[i] >= params.nav.stuck_time_s
                if not at_goal[i] and not aside[i] and stood:
                    settle[i] = True
        else:
            target = fxy[int(j[0])]
        err = float(_wrap(np.arctan2(target[1] - pose[i, 1], target[0] - pose[i, 0]) - pose[i, 2]))
        if at_goal[i] or settle[i]:
            v[i] = 0.0
            w[i] = float(np.clip(params.face_gain * err, -w_max, w_max))
        elif v[i] == 0.0 and w[i] == 0.0 and not aside[i]:
            # stopped on its way (waiting for a teammate, or no safe move): it turns to
            # its fire in place, so that its camera keeps the fire in view (the maze,
            # seed 0: two fighters stood 200-600 s facing the walls of the passage, and
            # the fire burned on unseen behind flames the team held soaked)
            w[i] = float(np.clip(params.face_gain * err, -w_max, w_max))
        if aim is not None and abs(err) <= half and obs.tank_l[i] > 0.0:
            # only a cone that holds dry cells at the flames (the ledger's)
            rows, cols = cone_cells(state.coarse, pose[i], params.spray_range_m, half)
            if wets_flames(
                wet,
                state.coarse,
                rows,
                cols,
                spots,
                params.soak_l_m2,
                params.front_m,
            ):
                spray[i] = True
                wet = add_water(
                    wet, state.coarse, rows, cols, params.flow_l_s * params.nav_period_s
                )
    if spray.any():
        state = replace(state, knowledge=replace(k, wet_l_m2=wet))
    # a confirmer settles only where it can confirm its victim; elsewhere it is sent to a
    # new viewpoint (the next plan; ``_people.confirm_sight``)
    lost = np.flatnonzero(settle & (mode == CONFIRM))
    if len(lost):
        sees = confirm_sight(
            state.coarse,
            pose[lost, :2],
            k.victim_xy_m[state.task_victim[lost]],
            params,
        )
        lost = lost[~sees]
        settle[lost] = False
        goals = goals.copy()
        goals[lost] = np.nan
        pending = pending or len(lost) > 0
    if settle.any():
        nav = navigation_retarget(nav, pose[:, :2], settle)
        at_goal = at_goal | settle
    # a fighter that has stood without a shot for reslot_s gets a new slot (next plan)
    reslot = (mode == FIGHT) & at_goal & ~aside & (obs.t_s - shot_s >= params.reslot_s)
    if reslot.any():
        goals = goals.copy()
        goals[reslot] = np.nan
        shot_s[reslot] = obs.t_s
        pending = True
    watching = np.flatnonzero((mode == CONFIRM) & at_goal & ~aside)
    for i in map(int, watching):
        vic = k.victim_xy_m[state.task_victim[i]]
        err = float(_wrap(np.arctan2(vic[1] - pose[i, 1], vic[0] - pose[i, 0]) - pose[i, 2]))
        v[i] = 0.0
        w[i] = float(np.clip(params.face_gain * err, -w_max, w_max))
    if len(watching):  # a victim watched too long without confirmation is given up
        know, gave_up = watch_victims(
            state.knowledge,
            state.coarse,
            pose,
            watching,
            state.task_victim[watching],
            params.nav_period_s,
            params,
        )
        state = replace(state, knowledge=know)
        pending = pending or gave_up
    scan = (mode == EXPLORE) & arrived
    v[scan] = 0.0
    w[scan] = scan_turn(state.coarse, state.covered_coarse, pose, state.explore_cell, scan, params)[
        scan
    ]
    # refilling only by the refill point (not where a blocked path left it): within
    # refill_radius_m of it, through the robot's spot and the spot nearest the point
    spots_r = state.refill_spots_m
    spot_i = np.clip(state.refill_spot, 0, len(spots_r) - 1)
    group = state.refill_group
    head = np.searchsorted(group, group[spot_i]) if len(group) else np.zeros_like(spot_i)
    off = np.hypot(*(spots_r[spot_i] - spots_r[head]).T)  # from its point's first spot
    d_spot = np.hypot(*(pose[:, :2] - spots_r[spot_i]).T)  # not where it waits (_refill)
    refilling = (mode == REFILL) & at_goal & (d_spot + off <= params.refill_radius_m)
    stop = (mode == DAMAGED) | refilling | ((mode == IDLE) & ~aside)
    v[stop] = 0.0
    w[stop] = 0.0
    flames = dry_flames(state, params)  # soaked: the way in once the door's flames are out
    if params.flame_guard_m > 0.0 and len(flames):
        # every robot stops short of flames, a refiller too (one exempt, its tank at
        # 2.6 L, drove from its slot onto a burning cell between a classroom's desks and
        # was damaged: a school wing, seed 1)
        before = v.copy()
        v, w = flame_guard(
            v, w, pose, flames, params.flame_guard_m, math.radians(60.0), w_max, state.coarse
        )
        # one held with water sprays its way on (``fight_through``), a refiller too
        # (exempt before: on mission-office seed 1 two were held in the fire's room by
        # the flames at its door)
        held = (mode == FIGHT) | (mode == REFILL)
        held &= (before > 0.0) & (v == 0.0) & (obs.tank_l > 0.0) & ~spray
        wet = state.knowledge.wet_l_m2
        for i in map(int, np.flatnonzero(held)):
            w[i], spray[i], wet = fight_through(pose[i], flames, wet, state.coarse, params)
        if (held & spray).any():
            state = replace(state, knowledge=replace(state.knowledge, wet_l_m2=wet))
    nav = replace(nav, command=np.stack([v, w], axis=1))
    orders = Orders(
        v_m_s=v,
        omega_rad_s=w,
        spray=spray,
        mode=mode.astype(np.int8),
        goal_xy_m=state.goal_xy_m.copy(),
    )
    return replace(
        state,
        nav=nav,
        orders=orders,
        refilling=refilling,
        shot_s=shot_s,
        goal_xy_m=goals,
        pending=pending,
    )


def tactics_step(
    state: TacticsState, obs: TacticsObservation, params: TacticsParams, dt_s: float
) -> tuple[TacticsState, Orders]:
    """The team's orders for one tick.

    Every tick: the detections join the team's knowledge (a change marks the plan
    stale), damaged robots are dropped, empty tanks are sent to refill and full ones
    brought back. At ``coverage_period_s``: the cameras' cones join the coverage. When
    the plan is stale and ``replan_s`` has passed since the last one, or
    ``explore_replan_s`` has passed: the allocation and the frontiers (``_plan``). At
    ``nav_period_s``: the navigation controller and the orders (arrived fighters turn to
    their fire and spray while it is in reach and in sight; arrived explorers look
    around; confirmers face their victim); in between, the last orders hold.

    Parameters
    ----------
    state : TacticsState
        From :func:`tactics_init` or the previous step.
    obs : TacticsObservation
        What the team knows this tick.
    params : TacticsParams
    dt_s : float
        The tick [s] (only checked: the periods are the parameters').

    Returns
    -------
    state : TacticsState
    orders : Orders

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import load_map
    >>> from firefleet.control.mission import (
    ...     MODES, TacticsObservation, TacticsParams, tactics_init, tactics_step)
    >>> params = TacticsParams()
    >>> pose = np.array([[1.0, 5.0, 0.0], [1.5, 4.6, 0.0]])
    >>> state = tactics_init(load_map("office"), pose, params)
    >>> obs = TacticsObservation(
    ...     t_s=0.0, pose_m=pose, fire_xy_m=np.zeros((0, 2)), fire_robot=np.zeros(0, int),
    ...     person_xy_m=np.zeros((0, 2)), person_robot=np.zeros(0, int), ranges={},
    ...     tank_l=np.full(2, 20.0), damaged=np.zeros(2, bool), alive=np.ones(2, bool))
    >>> state, orders = tactics_step(state, obs, params, 0.01)
    >>> [MODES[m] for m in orders.mode], bool(np.all(orders.v_m_s >= 0.0))
    (['explore', 'explore'], True)
    >>> bool(state.covered.any()), orders.goal_xy_m.shape
    (True, (2, 2))
    """
    if not (math.isfinite(dt_s) and dt_s > 0.0):
        raise InputError(f"dt_s must be > 0, got {dt_s!r}")
    if is_quiet(state, obs, params):  # nothing due, nothing new: the held orders
        return state, state.orders
    start = state
    n = len(state.mode)
    t = float(obs.t_s)
    pose = as_float_array(obs.pose_m, "obs.pose_m", (n, 3))
    tank = np.asarray(obs.tank_l, dtype=float)
    working = np.asarray(obs.alive, dtype=bool) & ~np.asarray(obs.damaged, dtype=bool)
    if tank.shape != (n,) or working.shape != (n,):
        raise InputError(f"obs.tank_l, damaged and alive must hold one value per robot ({n})")
    lost = ~working & ~state.known_damaged
    if lost.any():
        state = dropped(state, pose, lost)
    looked = working if obs.looked is None else working & np.asarray(obs.looked, dtype=bool)
    fire_xy = np.asarray(obs.fire_xy_m, dtype=float).reshape(-1, 2)
    person_xy = np.asarray(obs.person_xy_m, dtype=float).reshape(-1, 2)
    if len(fire_xy) or len(person_xy) or (looked.any() and len(state.knowledge.spot_xy_m)):
        know, changed = update_knowledge(
            state.knowledge,
            state.coarse,
            pose,
            fire_xy,
            np.asarray(obs.fire_robot, dtype=np.int64),
            person_xy,
            np.asarray(obs.person_robot, dtype=np.int64),
            looked,
            t,
            params,
            None if obs.fire_peak_c is None else np.asarray(obs.fire_peak_c, dtype=float),
        )
        state = replace(
            state,
            knowledge=know,
            pending=state.pending or changed,
            messages_sent=state.messages_sent + len(fire_xy) + len(person_xy),
        )
    state = tank_changes(state, pose, tank, working, params)
    near = np.zeros(n, dtype=bool)
    if len(fire_xy) and params.flame_guard_m > 0.0:
        fr = np.asarray(obs.fire_robot, dtype=np.int64)
        flame = (
            np.ones(len(fire_xy), dtype=bool)
            if obs.fire_peak_c is None
            else np.asarray(obs.fire_peak_c, dtype=float) >= params.flame_c
        )
        close = flame & (np.hypot(*(fire_xy - pose[fr, :2]).T) < params.flame_guard_m)
        near[fr[close]] = True
    if obs.air_c is not None or near.any():
        air = None if obs.air_c is None else np.asarray(obs.air_c, dtype=float)
        if air is not None and t >= state.next_nav_s - _EPS_S:
            # the probe lags the air: its reading and its rise (at the navigation's
            # period: never a quiet tick, ``_quiet``)
            air, prev_c, prev_s = probe_estimate(
                air, state.air_prev_c, state.air_prev_s, t, params.probe_lag_s
            )
            if prev_s != state.air_prev_s:
                state = replace(state, air_prev_c=prev_c, air_prev_s=prev_s)
        state = too_hot(state, pose, air, working, params, near, t)
    if t >= state.next_coverage_s - _EPS_S:
        rows, cols = cone_coverage(
            state.coarse,
            pose[working],
            params.sensing_range_m,
            params.hfov_rad,
            params.sensing_near_m,
            params.person_half_width_m,
        )
        covered = state.covered_coarse.copy()
        covered[rows, cols] = True
        seen = seen_update(
            state.fire_seen_s, state.coarse, pose[working], t, params.scout_view_m, params.hfov_rad
        )
        state = replace(
            state,
            covered_coarse=covered,
            fire_seen_s=seen,
            next_coverage_s=_next(state.next_coverage_s, params.coverage_period_s, t),
        )
    if t >= state.next_nav_s - _EPS_S:
        status = state.nav.status
        explorers = np.flatnonzero(state.mode == EXPLORE)
        stuck = [i for i in explorers if status[i] in ("unreachable", "goal_blocked")]
        if stuck:
            excluded = state.excluded.copy()
            for i in stuck:
                r, c = state.explore_cell[i]
                if r >= 0:
                    excluded[r, c] = True
            state = replace(state, excluded=excluded, pending=True)
        if any(status[i] == "arrived" for i in explorers):
            state = replace(state, pending=True)
        state = watchdog(state, pose, t, params)
        state = refill_wait(state, pose, working, params, t)
    since = t - state.last_plan_s
    if (state.pending and since >= params.replan_s) or since >= params.explore_replan_s:
        state = _plan(state, pose, tank, working, params)
        state = replace(state, last_plan_s=t)
    if t >= state.next_nav_s - _EPS_S:
        state = _orders(state, obs, pose, params)
        state = replace(state, next_nav_s=_next(state.next_nav_s, params.nav_period_s, t))
    if state is start:  # a quiet tick: the held orders, nothing to copy
        return state, state.orders
    return replace(state, t_s=t), state.orders
