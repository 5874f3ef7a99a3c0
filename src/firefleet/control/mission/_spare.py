"""Spare robots to the fires: once the search has run dry, the fires' cap lifts.

The fires' demand is capped at ``fire_robots_max`` (the mission sets it to one robot
fewer than the team, so that one keeps searching for people). Once a robot has nothing
left to explore (it stands ``IDLE``) while a fire burns, that reason is gone: measured on
``examples/missions/small-house`` seed 0, all three robots stood idle from 360 s to the
end of the run. :func:`spare_demand` then raises each fire's demand up to the robots its
extent asks for without the cap (``fire_robots_min + floor(extent / robot_per_fire_m)``),
one spare robot at a time, to the fire short of the most; and it keeps a fire's demand
at the robots it holds already (so that the next plan, with no robot idle any more, does
not send them back to stand idle: no flip-flop between plans).

Called by :func:`._step._plan` before the allocation.
"""

from __future__ import annotations

import numpy as np

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.mission._params import TacticsParams
from firefleet.control.mission._plan import fire_demand

__all__ = ["spare_demand"]


def spare_demand(
    need: IntArray,
    extent_m: FloatArray,
    fire_ids: IntArray,
    task_fire: IntArray,
    spare: BoolArray,
    params: TacticsParams,
) -> IntArray:
    """The fires' demands (F,) raised by the spare robots (module notes).

    Parameters
    ----------
    need : ndarray of int, shape (F,)
        Each fire's demand as capped (``_plan.fire_demand``, ``cut_demand``).
    extent_m : ndarray, shape (F,)
        Each fire's extent [m].
    fire_ids : ndarray of int, shape (F,)
        Each fire's id.
    task_fire : ndarray of int, shape (N,)
        The fire id each robot fights now (-1: none).
    spare : ndarray of bool, shape (N,)
        Robots with nothing to do (idle, working, water in the tank).

    Returns
    -------
    ndarray of int, shape (F,)
        ``need`` unchanged when no robot is spare and no fire holds more robots
        than its capped demand (``fire_demand``: the explorers ``cut_demand`` frees
        stay free); else each fire's demand at least the robots it holds, plus the
        spare robots one at a time to the fire whose uncapped demand it falls short of
        the most (ties: the lower index), while any falls short.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.mission import TacticsParams
    >>> p = TacticsParams(fire_robots_min=2, fire_robots_max=2, robot_per_fire_m=1.0)
    >>> ids = np.array([7])
    >>> # one idle robot, a 1.5 m fire held by two: uncapped demand 3
    >>> spare_demand(np.array([2]), np.array([1.5]), ids, np.array([7, 7, -1]),
    ...              np.array([False, False, True]), p).tolist()
    [3]
    >>> # the next plan: nobody idle, the fire holds three: it keeps them
    >>> spare_demand(np.array([2]), np.array([1.5]), ids, np.array([7, 7, 7]),
    ...              np.zeros(3, bool), p).tolist()
    [3]
    """
    out = np.array(need, dtype=np.int64)
    ids = np.asarray(fire_ids, dtype=np.int64)
    tf = np.asarray(task_fire, dtype=np.int64)
    held = np.array([int(np.sum(tf == f)) for f in ids], dtype=np.int64)
    n_spare = int(np.sum(np.asarray(spare, dtype=bool)))
    ext = np.asarray(extent_m, dtype=float)
    if len(out) == 0 or (n_spare == 0 and not np.any(held > fire_demand(ext, params))):
        return out
    out = np.maximum(out, held)
    uncapped = np.maximum(
        params.fire_robots_min + np.floor(ext / params.robot_per_fire_m), params.fire_robots_min
    ).astype(np.int64)
    for _ in range(n_spare):
        short = uncapped - out
        f = int(np.argmax(short))
        if short[f] <= 0:
            break
        out[f] += 1
    return out
