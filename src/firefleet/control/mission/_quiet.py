"""The quiet tick: whether :func:`~firefleet.control.mission.tactics_step` would leave its
state as it is (nothing due, nothing new), answered without the full step (nine ticks in
ten at the default periods), and the tank tests the full step shares with it."""

from __future__ import annotations

import dataclasses

import numba
import numpy as np

from firefleet._typing import BoolArray, FloatArray
from firefleet.control.mission._params import (
    EXPLORE,
    IDLE,
    REFILL,
    TacticsObservation,
    TacticsParams,
)
from firefleet.control.mission._plan import _empty_l
from firefleet.control.mission._team import TacticsState

__all__ = ["EPS_S", "is_quiet", "nothing_due", "quiet_ticks", "robots_quiet", "tank_flags"]

EPS_S = 1e-9
"""Times this close count as equal (ticks summed in floating point) [s]."""


def tank_flags(
    state: TacticsState, tank: FloatArray, working: BoolArray, params: TacticsParams
) -> tuple[BoolArray, BoolArray]:
    """Robots to send to refill (their tank empty, or low while a fire is known) and
    robots back from it with a full tank."""
    mode = state.mode
    empty = working & (tank <= _empty_l(params)) & (mode != REFILL)
    if len(state.knowledge.spot_xy_m):
        # while a fire burns, a robot off the fires with a low tank tops it up
        idle = (mode == EXPLORE) | (mode == IDLE)
        empty |= working & idle & (tank < params.low_tank_frac * params.tank_l)
    full = (mode == REFILL) & (tank >= 0.98 * params.tank_l)
    return empty, full


def is_quiet(state: TacticsState, obs: TacticsObservation, params: TacticsParams) -> bool:
    """Whether the tick at ``obs`` leaves ``state`` as it is (:func:`tactics_step` would
    return it unchanged, with its held orders): nothing is due (coverage, navigation,
    a plan), no detection, no robot lost, no tank to send or bring back, no robot in
    hot air. Nine ticks in ten at the default periods; an input of another shape is
    not quiet (the full step checks it)."""
    if not nothing_due(state, float(obs.t_s), params):
        return False
    if np.size(obs.fire_xy_m) or np.size(obs.person_xy_m):
        return False
    n = len(state.mode)
    if np.shape(obs.pose_m) != (n, 3):
        return False
    tank = np.asarray(obs.tank_l, dtype=np.float64)
    alive = np.asarray(obs.alive, dtype=np.bool_)
    damaged = np.asarray(obs.damaged, dtype=np.bool_)
    if tank.shape != (n,) or alive.shape != (n,) or damaged.shape != (n,):
        return False
    looked = np.ones(n, dtype=np.bool_) if obs.looked is None else np.asarray(obs.looked)
    air = None if obs.air_c is None else np.asarray(obs.air_c, dtype=np.float64)
    if looked.shape != (n,) or looked.dtype != np.bool_ or (air is not None and air.shape != (n,)):
        return False
    return robots_quiet(
        state.mode,
        tank,
        alive,
        damaged,
        state.known_damaged,
        looked,
        np.zeros(n) if air is None else air,
        air is not None,
        len(state.knowledge.spot_xy_m) > 0,
        _empty_l(params),
        params.low_tank_frac * params.tank_l,
        0.98 * params.tank_l,
        params.retreat_c,
    )


def nothing_due(state: TacticsState, t_s: float, params: TacticsParams) -> bool:
    """The time tests of :func:`is_quiet`: at ``t_s`` no coverage, navigation or plan is
    due (the rest of the tests read the observation)."""
    t = t_s
    if t >= state.next_coverage_s - EPS_S or t >= state.next_nav_s - EPS_S:
        return False
    since = t - state.last_plan_s
    return not ((state.pending and since >= params.replan_s) or since >= params.explore_replan_s)


def quiet_ticks(
    state: TacticsState, obs: TacticsObservation, params: TacticsParams, times_s: list[float]
) -> int:
    """How many of the leading ``times_s`` are quiet ticks (:func:`is_quiet`) for the
    observation ``obs`` with only its time changed: the whole test at the first, the time
    tests (:func:`nothing_due`) at the others (the rest reads the same observation).

    Examples
    --------
    >>> import dataclasses, itertools
    >>> import numpy as np
    >>> from firefleet.world import load_map
    >>> from firefleet.control.mission import (
    ...     TacticsObservation, TacticsParams, tactics_init, tactics_step)
    >>> params = TacticsParams()
    >>> pose = np.array([[1.0, 5.0, 0.0], [1.5, 4.6, 0.0]])
    >>> state = tactics_init(load_map("office"), pose, params)
    >>> obs = TacticsObservation(
    ...     t_s=0.0, pose_m=pose, fire_xy_m=np.zeros((0, 2)), fire_robot=np.zeros(0, int),
    ...     person_xy_m=np.zeros((0, 2)), person_robot=np.zeros(0, int), ranges={},
    ...     tank_l=np.full(2, 20.0), damaged=np.zeros(2, bool), alive=np.ones(2, bool))
    >>> state, _ = tactics_step(state, obs, params, 0.01)
    >>> times = [0.01 * k for k in range(1, 30)]
    >>> m = quiet_ticks(state, obs, params, times)
    >>> m == sum(1 for _ in itertools.takewhile(
    ...     lambda t: is_quiet(state, dataclasses.replace(obs, t_s=t), params),
    ...     times))
    True
    >>> 1 <= m < len(times)  # quiet until the next navigation tick
    True
    """
    if not times_s:
        return 0
    first = dataclasses.replace(obs, t_s=times_s[0])
    if not is_quiet(state, first, params):
        return 0
    m = 1
    while m < len(times_s) and nothing_due(state, times_s[m], params):
        m += 1
    return m


@numba.njit(cache=True)
def robots_quiet(
    mode: np.ndarray,
    tank: FloatArray,
    alive: BoolArray,
    damaged: BoolArray,
    known_damaged: BoolArray,
    looked: BoolArray,
    air: FloatArray,
    has_air: bool,
    has_spots: bool,
    empty_l: float,
    low_l: float,
    full_l: float,
    retreat_c: float,
) -> bool:  # pragma: no cover - compiled
    """The per-robot tests of :func:`is_quiet` in one compiled pass, the comparisons of the
    full step's (``tactics_step``'s prologue, ``tank_flags``, ``_too_hot``): no robot
    newly lost, no look at a known fire, no tank to send to refill or bring back, no
    robot in air of ``retreat_c``."""
    for i in range(mode.shape[0]):
        working = alive[i] and not damaged[i]
        if not working:
            if not known_damaged[i]:
                return False  # newly lost
            if mode[i] == REFILL and tank[i] >= full_l:
                return False  # back from refill (whatever its state)
            continue
        if has_spots and looked[i]:
            return False  # a look that may update the knowledge
        if mode[i] != REFILL and tank[i] <= empty_l:
            return False
        if has_spots and (mode[i] == EXPLORE or mode[i] == IDLE) and tank[i] < low_l:
            return False
        if mode[i] == REFILL and tank[i] >= full_l:
            return False
        if has_air and air[i] >= retreat_c:
            return False
    return True
