"""One tick of team navigation (the stages are described in ``_team``)."""

from __future__ import annotations

import math

import numba
import numpy as np

from firefleet._frozen import replace
from firefleet._typing import FloatArray
from firefleet.control.navigation._astar import adopt_plans
from firefleet.control.navigation._dwa import dwa_command
from firefleet.control.navigation._makeway import (
    clear_of,
    cuts_path,
    make_way_spot,
    open_cells_near,
    passed,
)
from firefleet.control.navigation._team import (
    _SAMPLE_M,
    NavigationInputs,
    NavigationParams,
    NavigationState,
    _plan,
    _samples,
    _with_teammates,
)
from firefleet.control.path_following import controller_inputs
from firefleet.errors import InputError, as_float_array
from firefleet.planning.planar import PlanarPath

__all__ = ["navigation_step"]

_FAR = 1e9


def _range_points(inputs: NavigationInputs, pose: FloatArray, reach_m: float) -> FloatArray:
    """Every sensor's returns as world points (N, M, 2); no return or beyond reach: far."""
    n = pose.shape[0]
    blocks = []
    for name, (ranges, bearings) in inputs.ranges.items():
        r = np.asarray(ranges, dtype=float)
        b = np.asarray(bearings, dtype=float)
        if r.ndim != 2 or r.shape[0] != n:
            raise InputError(f"ranges[{name!r}] must be (N, B) with N = {n}, got {r.shape}")
        if b.shape not in ((r.shape[1],), r.shape):
            raise InputError(
                f"bearings of {name!r} must be (B,) or (N, B) with B = {r.shape[1]}, got {b.shape}"
            )
        ang = pose[:, 2:3] + np.broadcast_to(b, r.shape)
        ok = np.isfinite(r) & (r <= reach_m)
        rr = np.where(ok, r, 0.0)
        pts = np.stack([pose[:, 0:1] + rr * np.cos(ang), pose[:, 1:2] + rr * np.sin(ang)], axis=-1)
        blocks.append(np.where(ok[..., None], pts, _FAR))
    if not blocks:
        return np.full((n, 1, 2), _FAR)
    return np.concatenate(blocks, axis=1)


_MAX_WALL_POINTS = 400
"""Most known wall cells given to DWA per robot (the nearest)."""


def _near_walls(
    state: NavigationState, pose: FloatArray, reach_m: float
) -> tuple[FloatArray, float]:
    """The known wall cells within reach of each robot (N, M, 2), padded far, and the
    radius of the disc covering a cell [m]."""
    n = pose.shape[0]
    pts = state.wall_points_m
    radius = state.costmap.grid.resolution_m * math.sqrt(0.5)
    if len(pts) == 0:
        return np.full((n, 1, 2), _FAR), radius
    out = np.full((n, _MAX_WALL_POINTS, 2), _FAR)
    used = 1
    tree = state.wall_tree
    found = None if tree is None else tree.query_ball_point(pose[:, :2], reach_m)
    for i in range(n):
        if found is None:
            d = np.hypot(pts[:, 0] - pose[i, 0], pts[:, 1] - pose[i, 1])
            near = np.nonzero(d <= reach_m)[0]
            dn = d[near]
        else:  # the same points (in the same order), from the k-d tree
            near = np.sort(np.asarray(found[i], dtype=np.int64))
            dn = np.hypot(pts[near, 0] - pose[i, 0], pts[near, 1] - pose[i, 1])
        if len(near) > _MAX_WALL_POINTS:
            near = near[np.argpartition(dn, _MAX_WALL_POINTS - 1)[:_MAX_WALL_POINTS]]
        out[i, : len(near)] = pts[near]
        used = max(used, len(near))
    return out[:, :used], radius


@numba.njit(cache=True)
def _conflict(
    mine: FloatArray, theirs: FloatArray, me: FloatArray, gap_m: float
) -> tuple[bool, bool]:  # pragma: no cover - compiled
    """(my path ahead meets theirs, I stand in their way): whether any of my points
    (K, 2) lies within ``gap_m`` of any of theirs (L, 2), and whether any of theirs lies
    within ``gap_m`` of me.

    A pair whose ``|dx|`` or ``|dy|`` is ``gap_m`` or more is not near: ``hypot``
    returns at least ``max(|dx|, |dy|)`` (its result is within an ulp of the exact
    value, which is at least that float), so the test skips its ``hypot``; the same
    answers (NaN differences still go to ``hypot``)."""
    in_way = False
    for j in range(theirs.shape[0]):
        dx = theirs[j, 0] - me[0]
        dy = theirs[j, 1] - me[1]
        if abs(dx) >= gap_m or abs(dy) >= gap_m:
            continue
        if np.hypot(dx, dy) < gap_m:
            in_way = True
            break
    for i in range(mine.shape[0]):
        for j in range(theirs.shape[0]):
            dx = mine[i, 0] - theirs[j, 0]
            dy = mine[i, 1] - theirs[j, 1]
            if abs(dx) >= gap_m or abs(dy) >= gap_m:
                continue
            if np.hypot(dx, dy) < gap_m:
                return True, in_way
    return False, in_way


def _aside_spot(
    state: NavigationState,
    params: NavigationParams,
    pose: FloatArray,
    mates: FloatArray,
    i: int,
    j: int,
    rest: FloatArray,
    gap: float,
) -> FloatArray | None:
    """The nearest open spot (within 3 m of robot ``i``) that keeps ``gap`` + the goal
    tolerance + 0.1 m (so a robot arrived near it is out of the way) from
    teammate ``j``'s remaining path ``rest`` (K, 2) and from every other robot, and
    that ``i`` can reach around ``j``; None if there is none."""
    xy = open_cells_near(state.costmap, params, pose[i, :2], 3.0)
    if len(xy) == 0:
        return None
    limit = gap + params.goal_tolerance_m + 0.1
    keep = clear_of(xy, np.ascontiguousarray(rest, dtype=float), limit) & clear_of(
        xy, np.ascontiguousarray(np.delete(mates, i, axis=0), dtype=float), limit
    )
    xy = xy[keep]
    if len(xy) == 0:
        return None
    order = np.argsort(np.hypot(xy[:, 0] - pose[i, 0], xy[:, 1] - pose[i, 1]))
    costmap = _with_teammates(state, params, mates[j : j + 1])
    # the nearest first, then farther ones (the nearest may lie behind a wall)
    tries = dict.fromkeys([0, 1, *(int(f * (len(order) - 1)) for f in (0.05, 0.15, 0.3, 0.6))])
    for k in tries:
        spot = xy[order[k]]
        status, _ = _plan(costmap, pose[i, :2], spot, params)
        if status == "moving":
            return np.asarray(spot)
    return None


def navigation_step(
    state: NavigationState, inputs: NavigationInputs, params: NavigationParams, dt_s: float
) -> tuple[NavigationState, FloatArray, FloatArray]:
    """The team's velocity commands for one control period.

    Parameters
    ----------
    state : NavigationState
        From :func:`navigation_init` or the previous step.
    inputs : NavigationInputs
        Pose estimates, range readings with their bearings, teammates' positions, time.
    params : NavigationParams
    dt_s : float
        The control period [s] (the dynamic window is what the wheels reach in it).

    Returns
    -------
    state : NavigationState
    v_m_s, omega_rad_s : ndarray, shape (N,)
        Linear [m/s] and angular [rad/s] velocity set points (0 for robots that have
        arrived or cannot move).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> from firefleet.control.navigation import (
    ...     NavigationInputs, NavigationParams, navigation_init)
    >>> occ = np.zeros((40, 60), dtype=bool)
    >>> grid = OccupancyGrid(occ, ~occ, 0.1)
    >>> params = NavigationParams()
    >>> pose = np.array([[1.0, 2.0, 0.0]])
    >>> state = navigation_init(grid, pose, [[5.0, 2.0]], params)
    >>> inputs = NavigationInputs(pose, {}, pose[:, :2], 0.0)
    >>> state, v, w = navigation_step(state, inputs, params, 0.1)
    >>> bool(0.0 < v[0] <= 0.25), round(float(w[0]), 6), state.status  # 0.25 m/s in 0.1 s
    (True, 0.0, ('moving',))
    """
    if not (math.isfinite(dt_s) and dt_s > 0.0):
        raise InputError(f"dt_s must be > 0, got {dt_s!r}")
    n = state.goals_m.shape[0]
    pose = as_float_array(inputs.pose, "inputs.pose", (n, 3))
    mates = as_float_array(inputs.teammates_xy_m, "inputs.teammates_xy_m", (n, 2))
    if state.planned_on is not None and state.planned_on is not state.costmap:
        adopt_plans(state.costmap, state.planned_on)
    t = float(inputs.t_s)
    status = list(state.status)
    paths = list(state.paths)
    samples = list(state.samples)
    progress = state.progress_m.copy()
    best = state.best_progress_m.copy()
    since = state.since_s.copy()
    stuck = state.stuck_count.copy()
    replans = state.replans.copy()
    desired = pose.copy()
    index = np.zeros(n, dtype=np.int64)
    target = state.target_m.copy()
    aside = state.aside_of.copy()
    parked = np.zeros(n, dtype=bool) if state.parked is None else state.parked.copy()
    asked = np.full(n, -math.inf) if state.asked_s is None else state.asked_s.copy()
    movable = np.zeros(n, dtype=bool)
    if inputs.movable is not None:
        movable = np.asarray(inputs.movable, dtype=bool).reshape(-1)
        if movable.shape != (n,):
            raise InputError(f"inputs.movable must be {n} booleans, got shape {movable.shape}")
    gap = 2.0 * params.robot_radius_m + params.margin_m
    limit = gap + params.goal_tolerance_m + 0.1

    def replan(i: int, with_mates: bool) -> None:
        costmap = state.costmap
        if with_mates:
            others = np.delete(mates, i, axis=0)
            costmap = _with_teammates(state, params, others)
        st, path = _plan(costmap, pose[i, :2], target[i], params)
        if path is None and with_mates:
            st, path = _plan(state.costmap, pose[i, :2], target[i], params)
        status[i] = st if path is None else "moving"
        paths[i] = path
        samples[i] = _samples(path)
        progress[i] = 0.0
        best[i] = 0.0
        since[i] = t
        replans[i] += 1

    for i in range(n):
        if parked[i]:
            # made way for a moving teammate: back once it has passed (``_makeway``)
            j = int(aside[i])
            if status[j] not in ("moving", "waiting") or passed(
                _rest(pose, samples, paths, state.progress_m, j), state.goals_m[i], limit
            ):
                parked[i] = False
                aside[i] = -1
                target[i] = state.goals_m[i]
                status[i] = "moving"
                replan(i, with_mates=False)
            elif status[i] == "arrived":
                continue
            elif math.hypot(*(pose[i, :2] - target[i])) <= 0.5 * params.goal_tolerance_m:
                status[i] = "arrived"  # out of the way: the mover re-checks its progress
                since[j] = -math.inf
                continue
        if status[i] == "arrived":
            continue
        # half the tolerance: the estimate the decision uses may be off by a few cm
        near_goal = math.hypot(*(pose[i, :2] - state.goals_m[i]))
        if not parked[i] and near_goal <= 0.5 * params.goal_tolerance_m:
            status[i] = "arrived"
            continue
        if (
            not parked[i]
            and aside[i] >= 0
            and (
                math.hypot(*(pose[i, :2] - target[i])) <= params.goal_tolerance_m
                or status[aside[i]] not in ("moving", "waiting")
            )
        ):
            # out of the way (or the teammate is done): head for the goal again
            aside[i] = -1
            target[i] = state.goals_m[i]
            replan(i, with_mates=False)
        if paths[i] is None:
            if t - since[i] >= params.stuck_time_s:  # try again now and then
                replan(i, with_mates=False)
            if paths[i] is None:
                continue
        smp = samples[i]
        spacing = paths[i].length_m / max(len(smp) - 1, 1)  # type: ignore[union-attr]
        lo = max(int((progress[i] - 0.3) / spacing), 0)
        hi = min(int((progress[i] + 1.0) / spacing) + 2, len(smp))
        d = np.hypot(smp[lo:hi, 0] - pose[i, 0], smp[lo:hi, 1] - pose[i, 1])
        k = int(np.argmin(d))
        progress[i] = (lo + k) * spacing
        index[i] = lo + k
        if d[k] > params.replan_offset_m:
            replan(i, with_mates=False)
        elif status[i] == "moving" and t - since[i] >= params.stuck_time_s:
            if progress[i] - best[i] < params.stuck_progress_m:
                stuck[i] += 1
                if aside[i] >= 0:  # cannot get out of the way there: plan anew
                    aside[i] = -1
                    parked[i] = False
                    target[i] = state.goals_m[i]
                replan(i, with_mates=True)
            else:
                stuck[i] = 0
                best[i] = progress[i]
                since[i] = t
        path = paths[i]
        if path is None:
            continue
        if status[i] == "waiting":
            status[i] = "moving"
        if progress[i] == 0.0:
            index[i] = 0  # just re-planned
        desired[i] = path.pose_at(min(progress[i] + params.lookahead_m, path.length_m))

    active = np.array([s in ("moving", "waiting") for s in status])
    v_ref = np.zeros(n)
    w_ref = np.zeros(n)
    if active.any():
        v_f, w_f, _ = params.controller.command(controller_inputs(pose[active], desired[active]))
        v_ref[active] = np.clip(v_f, 0.0, params.dwa.v_max_m_s)
        w_ref[active] = np.clip(w_f, -params.dwa.omega_max_rad_s, params.dwa.omega_max_rad_s)

    # give way: lower index first
    ahead = round(params.yield_distance_m / _SAMPLE_M)
    # a teammate's position and path ahead, made once (robot j's own turn, which may
    # re-plan it, comes before any i > j asks)
    theirs_of: dict[int, FloatArray] = {}
    near_by = 2.0 * params.yield_distance_m + gap
    # pairs that may lie within near_by (squared distances, a hair of slack): the exact
    # test below runs on those only, in the same order (50 robots: 1,225 pairs a call)
    dx = pose[:, None, 0] - pose[None, :, 0]
    dy = pose[:, None, 1] - pose[None, :, 1]
    maybe = dx * dx + dy * dy <= (near_by * (1.0 + 1e-6)) ** 2
    px, py = pose[:, 0].tolist(), pose[:, 1].tolist()  # the pairs' distances in floats
    aside_list = aside.tolist()  # kept with ``aside`` (set below for i as its turn ends)
    is_active = active.tolist()
    for i in map(int, np.nonzero(active)[0]):
        if aside[i] >= 0:
            continue  # already on its way out of a teammate's way: it does not stop
        mine = np.ascontiguousarray(samples[i][index[i] : index[i] + ahead, :2])
        me = np.ascontiguousarray(pose[i, :2])
        for j in map(int, np.flatnonzero(maybe[i, :i])):
            if not is_active[j] or len(mine) == 0:
                continue
            if math.hypot(px[i] - px[j], py[i] - py[j]) > near_by:
                continue
            if aside_list[j] == i:
                continue  # it makes way for me
            theirs = theirs_of.get(j)
            if theirs is None:
                theirs = np.vstack(
                    [pose[j : j + 1, :2], samples[j][index[j] : index[j] + ahead, :2]]
                )
                theirs_of[j] = theirs
            meets, in_way = _conflict(mine, theirs, me, gap)
            if meets and not in_way and stuck[j] > 0:
                # it is held up (no progress in stuck_time_s) and I stand by its way: I
                # make way instead of waiting for it (the house, seed 3: a fighter in a
                # doorway waited for a teammate leaving the room past it, 0.38 m off,
                # whose window found no way by it, for 600 s)
                in_way = bool(np.hypot(theirs[:, 0] - me[0], theirs[:, 1] - me[1]).min() < limit)
            if meets and in_way and aside[i] < 0:
                rest = np.vstack([pose[j : j + 1, :2], samples[j][index[j] :: 2, :2]])
                spot = _aside_spot(state, params, pose, mates, i, j, rest, gap)
                if spot is not None:
                    aside[i] = aside_list[i] = j
                    target[i] = spot
                    replan(i, with_mates=True)
                    index[i] = 0
                    v_ref[i] = 0.0
                    break
            if meets and not in_way:
                status[i] = "waiting"
                v_ref[i] = 0.0
                best[i] = progress[i]
                since[i] = t
                break

    # standing teammates in the way make way (``_makeway``)
    standing = np.array([s == "arrived" for s in status]) & movable & ~parked & (aside < 0)
    if standing.any():
        block = params.robot_radius_m + params.inflation_m
        for i in map(int, np.flatnonzero(active & (aside < 0) & ~parked)):
            mine = samples[i][index[i] : index[i] + ahead, :2]
            if len(mine) == 0:
                continue
            for j in map(int, np.flatnonzero(maybe[i] & standing)):
                if j == i or t - asked[j] < params.stuck_time_s:
                    continue
                if math.hypot(*(target[i] - pose[j, :2])) <= limit:
                    continue  # where it goes is where the other stands
                # a mover held up (no progress in stuck_time_s) asks one standing by its
                # way too: the way past it the planner finds may be one its window
                # cannot take (a school wing, seed 1: an explorer 0.45 m behind a
                # fighter standing in a 1 m classroom door, held 240 s)
                held = stuck[i] > 0
                near = np.hypot(mine[:, 0] - pose[j, 0], mine[:, 1] - pose[j, 1]).min()
                if near >= (limit if held else gap):
                    continue
                rest = _rest(pose, samples, paths, progress, i)
                if not held and not cuts_path(state.costmap, pose[j, :2], block, rest):
                    continue  # there is a way past it: a re-plan finds it
                spot = make_way_spot(state, params, pose, mates, j, i, rest)
                if spot is None:
                    asked[j] = t
                    continue
                parked[j] = True
                aside[j] = i
                target[j] = spot
                replan(j, with_mates=True)
                standing[j] = False

    # the safety layer (for the robots under way: the others brake below)
    reach = params.dwa.v_max_m_s * params.dwa.horizon_s + params.robot_radius_m + 0.5
    points = _range_points(inputs, pose, reach)
    v = np.zeros(n)
    w = np.zeros(n)
    act = np.flatnonzero(active)
    if len(act):
        mate_pts = np.broadcast_to(mates[None], (len(act), n, 2)).copy()
        mate_pts[np.arange(len(act)), act] = _FAR
        walls, wall_radius = _near_walls(state, pose[act], reach)
        obstacles = np.concatenate([points[act], walls, mate_pts], axis=1)
        radii = np.concatenate(
            [
                np.zeros((len(act), points.shape[1])),
                np.full(walls.shape[:2], wall_radius),
                # the teammates' discs grown by the margin: their positions are
                # estimates too (mission-warehouse seed 0 at the bare radius: two robots
                # 0.2997 m apart, a touch; mission-large: 0.303 m)
                np.full((len(act), n), params.robot_radius_m + params.margin_m),
            ],
            axis=1,
        )
        ref = np.stack([v_ref, w_ref], axis=1)[act]
        # a robot the stuck detector flagged may turn in place as asked (``dwa_command``)
        v[act], w[act], _ = dwa_command(
            pose[act], state.command[act], ref, obstacles, radii, params.dwa, dt_s, stuck[act] > 0
        )
    # robots that stop: brake as hard as the window allows (the window holds 0 after
    # a tenth of a second at most)
    stop = ~active
    if stop.any():
        da = params.dwa.wheel_accel_m_s2 * dt_s
        half = params.dwa.axle_length_m / 2.0
        last = state.command
        v[stop] = np.maximum(last[stop, 0] - da, 0.0)
        budget = np.maximum(da - (last[stop, 0] - v[stop]), 0.0) / half
        w[stop] = np.sign(last[stop, 1]) * np.maximum(np.abs(last[stop, 1]) - budget, 0.0)
    new = replace(
        state,
        paths=tuple(paths),
        samples=tuple(samples),
        progress_m=progress,
        status=tuple(status),
        command=np.stack([v, w], axis=1),
        best_progress_m=best,
        since_s=since,
        stuck_count=stuck,
        replans=replans,
        t_s=t,
        target_m=target,
        aside_of=aside,
        parked=parked,
        asked_s=asked,
        planned_on=state.costmap,
    )
    return new, v, w


def _rest(
    pose: FloatArray,
    samples: list[FloatArray],
    paths: list[PlanarPath | None],
    progress: FloatArray,
    j: int,
) -> FloatArray:
    """Robot ``j``'s position and its path from its progress on, every 10 cm (K, 2)."""
    path = paths[j]
    smp = samples[j]
    if path is None or len(smp) == 0:
        return np.asarray(pose[j : j + 1, :2])
    spacing = path.length_m / max(len(smp) - 1, 1)
    k = min(max(int(progress[j] / spacing), 0), len(smp) - 1)
    return np.vstack([pose[j : j + 1, :2], smp[k::2, :2]])
