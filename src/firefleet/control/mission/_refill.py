"""Refilling clear of the fire: a refiller waits away from a refill spot the fire reaches.

The refill point is fixed (a standpipe, a hose cabinet, or by default the centroid of
the start poses), and the fire may spread to it. Traced on
``examples/missions/small-house`` seed 2: the default point lay in the fire's path, its
air past a robot's 300 C rating from ~290 s, and all three robots were damaged while
refilling or waiting there (405-492 s, air 720-800 C). A tank is filled only at the
point (the kind fills it while ``TacticsState.refilling``), so a robot whose spot is
hot does not refill elsewhere: it waits at the nearest place clear of the hot places and
the flames the team knows (:func:`._hot.retreat_point`), and goes back when its spot is
clear again (a hot place is forgotten ``hot_forget_s`` after it was last marked).
"""

from __future__ import annotations

import numpy as np

from firefleet._typing import BoolArray, FloatArray
from firefleet.control.mission._coverage import CoarseMap
from firefleet.control.mission._hot import retreat_point

__all__ = ["hot_spots", "refill_goals"]


def hot_spots(spots_m: FloatArray, away_xy_m: FloatArray, clear_m: float) -> BoolArray:
    """Whether each refill spot (R, 2) lies nearer than ``clear_m`` to a point of
    ``away_xy_m`` (K, 2) [m] (the fire reaches it); none is hot without such points.

    Examples
    --------
    >>> import numpy as np
    >>> hot_spots(np.array([[0.0, 0.0], [3.0, 0.0]]), np.array([[1.0, 0.0]]), 1.5).tolist()
    [True, False]
    """
    spots = np.asarray(spots_m, dtype=float).reshape(-1, 2)
    away = np.asarray(away_xy_m, dtype=float).reshape(-1, 2)
    if len(away) == 0 or len(spots) == 0:
        return np.zeros(len(spots), dtype=bool)
    d = np.hypot(spots[:, None, 0] - away[None, :, 0], spots[:, None, 1] - away[None, :, 1])
    out: BoolArray = d.min(axis=1) < clear_m
    return out


def refill_goals(
    cm: CoarseMap,
    spots_m: FloatArray,
    away_xy_m: FloatArray,
    clear_m: float,
    stay_xy_m: FloatArray,
) -> FloatArray:
    """Where each refiller goes: its spot, or the nearest place clear of the fire.

    Parameters
    ----------
    cm : CoarseMap
        The team's coarse plan.
    spots_m : ndarray, shape (R, 2)
        Each refiller's refill spot [m].
    away_xy_m : ndarray, shape (K, 2)
        What the team keeps out of [m]: its live hot places and the flames not soaked.
    clear_m : float
        A spot within this distance of a point of ``away_xy_m`` is hot [m]; a waiting
        place is at least this far from every one.
    stay_xy_m : ndarray, shape (R, 2)
        Where each refiller is [m]: it stays there when no clear place lies within
        reach of its spot (8 m of travel).

    Returns
    -------
    ndarray, shape (R, 2)
        The goal of each refiller [m]: its spot when clear, else the place nearest the
        spot by travel that is clear (:func:`._hot.retreat_point`).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.world import OccupancyGrid
    >>> walls = np.zeros((20, 40), dtype=bool)
    >>> cm = coarse_map(build_costmap(OccupancyGrid(walls, ~walls, resolution_m=0.25), 0.1), 0.25)
    >>> spots = np.array([[2.0, 2.5], [8.0, 2.5]])
    >>> goals = refill_goals(cm, spots, np.array([[2.5, 2.5]]), 1.5, spots)
    >>> bool(np.allclose(goals[1], spots[1])), bool(np.hypot(*(goals[0] - [2.5, 2.5])) >= 1.5)
    (True, True)
    """
    spots = np.asarray(spots_m, dtype=float).reshape(-1, 2)
    away = np.asarray(away_xy_m, dtype=float).reshape(-1, 2)
    goals = spots.copy()
    if len(away) == 0 or len(spots) == 0:
        return goals
    hot = hot_spots(spots, away, clear_m)
    stay = np.asarray(stay_xy_m, dtype=float).reshape(-1, 2)
    for i in map(int, np.flatnonzero(hot)):
        p = retreat_point(cm, spots[i], away, clear_m)
        goals[i] = p if np.isfinite(p[0]) else stay[i]
    return goals
