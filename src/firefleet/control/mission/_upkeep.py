"""The robots' upkeep between plans: tanks, heat, damage, stalls.

:func:`tank_changes` (empty tanks go to refill, full ones come back), :func:`too_hot` (a
robot in hot air or by flames marks its place and backs out), :func:`dropped` (damaged
robots leave their tasks), :func:`watchdog` (explorers that stall give their viewpoint
up), :func:`refill_wait` (refillers wait clear of a refill spot the fire reaches), and
:func:`retarget`, which hands new goals to the navigation; called by
:func:`._step.tactics_step`.
"""

from __future__ import annotations

import math

import numpy as np

from firefleet._frozen import replace
from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.mission._fight import dry_flames
from firefleet.control.mission._hot import live_hot, mark_hot, retreat_point
from firefleet.control.mission._params import DAMAGED, EXPLORE, FIGHT, IDLE, REFILL, TacticsParams
from firefleet.control.mission._quiet import tank_flags
from firefleet.control.mission._refill import hot_spots, refill_goals
from firefleet.control.mission._team import TacticsState
from firefleet.control.navigation import navigation_retarget

__all__ = ["dropped", "refill_wait", "retarget", "tank_changes", "too_hot", "watchdog"]

_MOVE_M = 0.25
"""A new goal this close to the old one does not re-plan the robot's path [m]."""


def retarget(state: TacticsState, goals: FloatArray, pose: FloatArray) -> TacticsState:
    """New goals into the navigation (NaN: stay where it is) for robots whose goal moved."""
    old = state.goal_xy_m
    fin = np.isfinite(goals[:, 0])
    moved = np.where(
        fin & np.isfinite(old[:, 0]),
        np.hypot(goals[:, 0] - old[:, 0], goals[:, 1] - old[:, 1]) > _MOVE_M,
        fin != np.isfinite(old[:, 0]),
    )
    if not moved.any():
        return replace(state, goal_xy_m=goals)
    nav_goal = np.where(fin[:, None], goals, pose[:, :2])
    nav = navigation_retarget(state.nav, nav_goal, moved)
    closest = state.closest_m.copy()
    closest[moved] = np.inf
    since = state.closest_s.copy()
    since[moved] = max(state.t_s, 0.0)
    return replace(state, nav=nav, goal_xy_m=goals, closest_m=closest, closest_s=since)


def tank_changes(
    state: TacticsState,
    pose: FloatArray,
    tank: FloatArray,
    working: BoolArray,
    params: TacticsParams,
) -> TacticsState:
    """Empty tanks go to refill at once; full ones come back (an allocation follows)."""
    empty, full = tank_flags(state, tank, working, params)
    if not (empty.any() or full.any()):
        return state
    mode = state.mode.copy()
    spot = state.refill_spot.copy()
    goals = state.goal_xy_m.copy()
    task_fire = state.task_fire.copy()
    task_victim = state.task_victim.copy()
    spots = state.refill_spots_m
    for i in map(int, np.flatnonzero(empty)):
        used = np.bincount(spot[spot >= 0], minlength=len(spots))
        # the free spot nearest the point (spots come nearest first): one farther out,
        # nearer the robot, leaves it refilling up to 2 refill_radius_m from the point;
        # of several points, the one nearest the robot by travel
        used = used + _farther_points(state, pose[i, :2], params) * (len(spot) + 1)
        spot[i] = int(np.lexsort((np.arange(len(spots)), used))[0])
        goals[i] = spots[spot[i]]
        mode[i] = REFILL
        task_fire[i] = -1
        task_victim[i] = -1
    spot[full] = -1
    goals[full] = np.nan
    mode[full] = IDLE
    new = replace(
        state,
        mode=mode,
        refill_spot=spot,
        task_fire=task_fire,
        task_victim=task_victim,
        pending=True,
    )
    return retarget(new, goals, pose)


def _farther_points(state: TacticsState, xy_m: FloatArray, params: TacticsParams) -> IntArray:
    """0 for the spots of the refill point nearest ``xy_m`` (2,) by travel, 1 for the
    others (K,); all 0 with one point. A point no travel reaches counts as farthest, and
    so does a hot one (a spot of it within ``standoff_m`` of a live hot place or a dry
    flame, :func:`refill_wait`'s test) while it reaches one that is not: an empty tank
    sent to a hot cabinet waits there for the fire to pass (mission-large's hose
    cabinets)."""
    group = state.refill_group
    if len(group) == 0 or group.max() == 0:
        return np.zeros(len(state.refill_spots_m), dtype=np.int64)
    cm = state.coarse
    travel = cm.distances(cm.node_of(np.asarray(xy_m, dtype=float)[None]))[0]
    to_spot = travel[cm.node_of(state.refill_spots_m)]
    to_point = np.full(int(group.max()) + 1, np.inf)
    np.minimum.at(to_point, group, to_spot)
    spot_hot = hot_spots(
        state.refill_spots_m, _refill_away(state, params, state.t_s), params.standoff_m
    )
    if spot_hot.any():
        hot = np.zeros(len(to_point), dtype=bool)
        hot[group[spot_hot]] = True
        # after every clear point it reaches, before any it does not reach
        to_point = np.where(hot, to_point + 1e9, to_point)
    best = int(np.argmin(to_point))
    out: IntArray = (group != best).astype(np.int64)
    return out


def _refill_away(state: TacticsState, params: TacticsParams, t_s: float) -> FloatArray:
    """What a refill spot keeps ``standoff_m`` from (K, 2) [m]: the live hot places and
    the dry flames (:func:`refill_wait` and :func:`_farther_points` alike)."""
    out: FloatArray = np.vstack(
        [live_hot(state.hot_xy_m, state.hot_s, t_s, params.hot_forget_s), dry_flames(state, params)]
    )
    return out


def refill_wait(
    state: TacticsState, pose: FloatArray, working: BoolArray, params: TacticsParams, t_s: float
) -> TacticsState:
    """Refillers whose spot lies within ``standoff_m`` of a live hot place or a dry flame
    wait at the nearest place clear of them; they go back once it is clear
    (:func:`._refill.refill_goals`); at the navigation's period (never a quiet tick)."""
    who = working & (state.mode == REFILL) & (state.refill_spot >= 0)
    if not who.any():
        return state
    goals = state.goal_xy_m.copy()
    goals[who] = refill_goals(
        state.coarse,
        state.refill_spots_m[state.refill_spot[who]],
        _refill_away(state, params, t_s),
        params.standoff_m,
        pose[who, :2],
    )
    return retarget(state, goals, pose)


def too_hot(
    state: TacticsState,
    pose: FloatArray,
    air_c: FloatArray | None,
    working: BoolArray,
    params: TacticsParams,
    near: BoolArray | None = None,
    t_s: float = 0.0,
) -> TacticsState:
    """A robot in air of ``retreat_c`` or more, or seeing flames nearer than
    ``flame_guard_m`` (``near``: its probe lags the air by seconds, its camera does
    not), marks its place hot at ``t_s`` (once per half metre: a place marked again
    is refreshed, :func:`._hot.mark_hot`); a fighter there gets a new slot at the next
    plan."""
    hot = working & (air_c >= params.retreat_c) if air_c is not None else np.zeros_like(working)
    if near is not None:
        hot |= working & near
    if not hot.any():
        return state
    xy, ts, added = mark_hot(state.hot_xy_m, state.hot_s, pose[hot, :2], t_s)
    # a fighter in hot air leaves a slot within standoff_m of a hot place, also one
    # known before (it came back once the place was forgotten), or the place where it
    # stopped short of its slot (mission-office seed 4: 20 s in a door's gas at 163 C; seed
    # 0: held 14 s in a door by the flame guard, its reading rising 70 -> 144 C)
    goals = state.goal_xy_m.copy()
    live = live_hot(xy, ts, t_s, params.hot_forget_s)
    gap = np.hypot(goals[:, None, 0] - live[None, :, 0], goals[:, None, 1] - live[None, :, 1])
    settled = np.array([st == "arrived" for st in state.nav.status])
    settled |= state.orders.v_m_s <= 0.0  # held up there (settled, or by the flame guard)
    leave = hot & (state.mode == FIGHT) & (np.any(gap < params.standoff_m, axis=1) | settled)
    if not (added or leave.any()):
        return replace(state, hot_xy_m=xy, hot_s=ts)
    goals[leave] = np.nan
    if leave.any():
        # it backs out now, clear of the hot places and the flames (its navigation's
        # goal; the plan gives it a new slot)
        away = np.vstack([live, dry_flames(state, params)])
        back = np.where(leave[:, None], np.nan, pose[:, :2])
        for i in map(int, np.flatnonzero(leave)):
            back[i] = retreat_point(state.coarse, pose[i, :2], away, params.standoff_m)
        go = leave & np.isfinite(back[:, 0])
        if go.any():
            nav = navigation_retarget(state.nav, np.where(go[:, None], back, pose[:, :2]), go)
            state = replace(state, nav=nav)
    return replace(state, hot_xy_m=xy, hot_s=ts, goal_xy_m=goals, pending=True)


def dropped(state: TacticsState, pose: FloatArray, lost: BoolArray) -> TacticsState:
    """Damaged or dead robots stop for good and leave their tasks (an allocation follows)."""
    mode = state.mode.copy()
    mode[lost] = DAMAGED
    tf = state.task_fire.copy()
    tv = state.task_victim.copy()
    tf[lost] = -1
    tv[lost] = -1
    goals = state.goal_xy_m.copy()
    goals[lost] = np.nan
    spot = state.refill_spot.copy()
    spot[lost] = -1
    new = replace(
        state,
        mode=mode,
        task_fire=tf,
        task_victim=tv,
        refill_spot=spot,
        known_damaged=state.known_damaged | lost,
        pending=True,
    )
    new = retarget(new, goals, pose)
    nav = navigation_retarget(new.nav, pose[:, :2], lost)  # arrived at once: no one waits for it
    return replace(new, nav=nav)


def watchdog(
    state: TacticsState, pose: FloatArray, t: float, params: TacticsParams
) -> TacticsState:
    """Explorers that neither reach their goal nor come 0.2 m closer to it in
    ``stall_s`` (one arrived there: and a whole turn more) give their viewpoint up (or
    stand within the goal tolerance of it without navigation calling it reached); the
    team re-plans."""
    goal = state.goal_xy_m
    d = np.hypot(pose[:, 0] - goal[:, 0], pose[:, 1] - goal[:, 1])
    better = np.isfinite(d) & (d < state.closest_m - 0.2)
    closest = np.where(better, d, state.closest_m)
    since = np.where(better, t, state.closest_s)
    explorers = state.mode == EXPLORE
    turn_s = 2.0 * math.pi / params.scan_omega_rad_s
    there = np.array([s == "arrived" for s in state.nav.status])
    stalled = explorers & np.isfinite(d) & (t - since >= params.stall_s + there * turn_s)
    near = explorers & (d <= params.nav.goal_tolerance_m)
    if not (stalled.any() or near.any()):
        return replace(state, closest_m=closest, closest_s=since)
    excluded = state.excluded
    if stalled.any():
        excluded = excluded.copy()
        for i in map(int, np.flatnonzero(stalled)):
            for rc in (state.explore_cell[i], state.coarse.cell_of(goal[i])):
                if rc[0] >= 0:
                    excluded[rc[0], rc[1]] = True
        since = np.where(stalled, t, since)
    return replace(state, closest_m=closest, closest_s=since, excluded=excluded, pending=True)
