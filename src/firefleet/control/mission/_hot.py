"""The team's hot places: where a robot's air reached the retreat temperature, or its
camera saw flames within the guard distance, and for how long the fighters' slots keep
away from them.

A place is hot while the fire next to it burns; once the flames there are soaked the gas
cools within tens of seconds (the field's heat halves in about that time by a door:
mission-office seed 2, the air at a fighter 1 m from the fire room's door fell from 190
C to 40 C in 30 s once the door's flames were out). A hot place kept for good barred
the fighters from the door, and from the flames behind it, for the rest of a run
(mission-office seed 2: nine places marked by 250 s, every slot with a shot at the last
flames within 1.5 m of one, the fighters standing 350 s without a shot). So a place is
avoided for ``forget_s`` after it was last marked; a robot that finds it hot again
marks it again.
"""

from __future__ import annotations

import numpy as np

from firefleet._typing import BoolArray, FloatArray
from firefleet.control.mission._coverage import CoarseMap
from firefleet.control.mission._near import any_within

__all__ = ["live_hot", "mark_hot", "probe_estimate", "retreat_point"]


def mark_hot(
    hot_xy_m: FloatArray,
    hot_s: FloatArray,
    xy_m: FloatArray,
    t_s: float,
    merge_m: float = 0.5,
) -> tuple[FloatArray, FloatArray, bool]:
    """The hot places after robots at ``xy_m`` (K, 2) [m] found their air hot at ``t_s``.

    A point within ``merge_m`` of a known place refreshes that place's time; one farther
    from all (and from the points before it) is a new place.

    Parameters
    ----------
    hot_xy_m : ndarray, shape (P, 2)
        Known hot places [m].
    hot_s : ndarray, shape (P,) or (0,)
        When each was last marked [s] (empty with P > 0: all at ``t_s``).
    xy_m : ndarray, shape (K, 2)
    t_s : float
    merge_m : float

    Returns
    -------
    hot_xy_m : ndarray, shape (P', 2)
    hot_s : ndarray, shape (P',)
    added : bool
        Whether a new place was added.

    Examples
    --------
    >>> import numpy as np
    >>> xy, ts, added = mark_hot(np.array([[0.0, 0.0]]), np.array([5.0]),
    ...                          np.array([[0.3, 0.0], [2.0, 0.0], [2.2, 0.0]]), 9.0)
    >>> xy.tolist(), ts.tolist(), added
    ([[0.0, 0.0], [2.0, 0.0]], [9.0, 9.0], True)
    """
    pts = np.asarray(hot_xy_m, dtype=float).reshape(-1, 2).copy()
    ts = np.asarray(hot_s, dtype=float).reshape(-1)
    ts = np.full(len(pts), float(t_s)) if len(ts) != len(pts) else ts.copy()
    added = False
    for p in np.asarray(xy_m, dtype=float).reshape(-1, 2):
        d = np.hypot(pts[:, 0] - p[0], pts[:, 1] - p[1]) if len(pts) else np.zeros(0)
        near = d <= merge_m
        if near.any():
            ts[near] = float(t_s)
        else:
            pts = np.vstack([pts, p[None]])
            ts = np.append(ts, float(t_s))
            added = True
    return pts, ts, added


def live_hot(hot_xy_m: FloatArray, hot_s: FloatArray, t_s: float, forget_s: float) -> FloatArray:
    """The hot places marked within ``forget_s`` before ``t_s`` (M, 2) [m] (places with
    no time recorded count as live).

    Examples
    --------
    >>> import numpy as np
    >>> live_hot(np.array([[0.0, 0.0], [1.0, 0.0]]), np.array([0.0, 50.0]), 60.0, 30.0).tolist()
    [[1.0, 0.0]]
    """
    pts = np.asarray(hot_xy_m, dtype=float).reshape(-1, 2)
    ts = np.asarray(hot_s, dtype=float).reshape(-1)
    if len(ts) != len(pts):
        return pts
    keep: BoolArray = t_s - ts < forget_s
    out: FloatArray = pts[keep]
    return out


def probe_estimate(
    air_c: FloatArray,
    prev_c: FloatArray,
    prev_s: float,
    t_s: float,
    lag_s: float,
    window_s: float = 1.0,
) -> tuple[FloatArray, FloatArray, float]:
    """The air at each robot, from its probe's reading and the probe's lag.

    A sheathed probe reads the air through a first-order lag, ``dT_read/dt = (T_air -
    T_read) / lag_s``, so ``T_air = T_read + lag_s dT_read/dt``: a robot driving into hot
    gas reads it ``lag_s`` late (mission-office seed 4: a fighter in a burning room's
    door read 91 C while its air was past 250 C; it stood there, its reading climbing
    to 215 C before it left, and was damaged). The slope is taken over at least
    ``window_s`` (the readings held in ``prev_c`` from ``prev_s``); a falling reading
    counts as steady (the estimate is never below the reading).

    Parameters
    ----------
    air_c : ndarray, shape (N,)
        This tick's readings [C].
    prev_c : ndarray, shape (N,) or (0,)
        The readings the slope starts from [C] (another shape: none yet).
    prev_s : float
        Their time [s].
    t_s, lag_s, window_s : float
        Now [s]; the probe's time constant [s]; the slope's least span [s].

    Returns
    -------
    air_c : ndarray, shape (N,)
        The estimated air [C].
    prev_c : ndarray, shape (N,)
    prev_s : float
        The readings to take the next slope from (renewed every ``window_s``).

    Examples
    --------
    >>> import numpy as np
    >>> est, prev, ts = probe_estimate(np.array([91.0, 40.0]), np.array([50.0, 45.0]),
    ...                                169.0, 171.0, 10.0)
    >>> est.tolist(), prev.tolist(), ts  # 20.5 C/s for 10 s; a falling one as read
    ([296.0, 40.0], [91.0, 40.0], 171.0)
    """
    air = np.asarray(air_c, dtype=float)
    prev = np.asarray(prev_c, dtype=float)
    if prev.shape != air.shape or not np.isfinite(prev_s):
        return air.copy(), air.copy(), float(t_s)
    dt = t_s - prev_s
    if dt <= 0.0:
        return air.copy(), prev, prev_s
    slope = np.maximum(air - prev, 0.0) / dt
    est: FloatArray = air + lag_s * slope
    if dt >= window_s:
        return est, air.copy(), float(t_s)
    return est, prev, prev_s


def retreat_point(
    cm: CoarseMap, xy_m: FloatArray, away_xy_m: FloatArray, clear_m: float, limit_m: float = 8.0
) -> FloatArray:
    """The nearest place by travel from ``xy_m`` (2,) [m] at least ``clear_m`` from
    every point of ``away_xy_m`` (K, 2) [m] (hot places, flames): where a robot in hot
    air backs out to (a fighter told only to leave its slot stood 8 s in a door held by
    the flame guard, its reading rising 55 -> 177 C: mission-office seed 0). NaN when
    none lies within ``limit_m``.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.world import OccupancyGrid
    >>> walls = np.zeros((20, 40), dtype=bool)
    >>> cm = coarse_map(build_costmap(OccupancyGrid(walls, ~walls, resolution_m=0.25), 0.1), 0.25)
    >>> hot = np.array([[5.0, 2.5], [6.0, 2.5]])
    >>> p = retreat_point(cm, np.array([5.0, 2.5]), hot, 1.5)
    >>> bool(np.hypot(*(p - [5.0, 2.5])) < 1.8), bool(np.hypot(*(hot - p).T).min() >= 1.5)
    (True, True)
    """
    node = int(cm.node_of(np.asarray(xy_m, dtype=float).reshape(1, 2))[0])
    away = np.asarray(away_xy_m, dtype=float).reshape(-1, 2)
    # the answer is a function of the node, the points and the two distances: a robot
    # in hot air asks it at every tick it stays hot (mission-office, 300 s: 4,135
    # calls, 4 distinct), so the last answers are kept in the map's cache
    kept = cm.cache.setdefault(("retreat",), {})
    assert isinstance(kept, dict)
    key = (node, float(clear_m), float(limit_m), away.tobytes())
    if key in kept:
        got: FloatArray = kept[key]
        return got.copy()
    out = _retreat(cm, node, away, clear_m, limit_m)
    if len(kept) >= _RETREAT_KEPT:
        kept.pop(next(iter(kept)))
    kept[key] = out.copy()
    return out


_RETREAT_KEPT = 16
"""Most answers :func:`retreat_point` keeps in a map's cache (the oldest dropped)."""


def _retreat(
    cm: CoarseMap, node: int, away: FloatArray, clear_m: float, limit_m: float
) -> FloatArray:
    """:func:`retreat_point` from ``node``, ``away`` (K, 2) as floats, not kept."""
    xy, travel = _reach(cm, node, limit_m)
    if len(xy) == 0:
        return np.full(2, np.nan)
    # a point farther than clear_m from the reach's box is clear of every cell in it
    lo_xy, hi_xy = xy.min(axis=0) - clear_m, xy.max(axis=0) + clear_m
    away = away[np.all((away >= lo_xy) & (away <= hi_xy), axis=1)]
    if len(away):
        ok = ~any_within(xy, away, clear_m, inclusive=False)
        xy, travel = xy[ok], travel[ok]
    if len(xy) == 0:
        return np.full(2, np.nan)
    out: FloatArray = xy[int(np.argmin(travel))]
    return out


_REACH_KEPT = 256
"""Most nodes whose reach :func:`_reach` keeps in a map's cache."""


def _reach(cm: CoarseMap, node: int, limit_m: float) -> tuple[FloatArray, FloatArray]:
    """The goal points [m] (M, 2) of the standable cells within ``limit_m`` of travel
    from ``node``, in row-major order, and their travel [m] (M,).

    Kept in ``cm.cache`` (the oldest node dropped past ``_REACH_KEPT``): a robot in hot
    air asks for a retreat from the same cell at every tick it stays hot (on
    mission-large a quarter of the run went to these searches)."""
    kept = cm.cache.setdefault(("reach", float(limit_m)), {})
    assert isinstance(kept, dict)
    if node in kept:
        got: tuple[FloatArray, FloatArray] = kept[node]
        return got
    travel = cm.distances(np.array([node]), limit_m)[0].reshape(cm.shape)
    cells = np.argwhere(np.isfinite(travel) & cm.standable)
    out = (cm.goal_xy(cells), travel[cells[:, 0], cells[:, 1]])
    if len(kept) >= _REACH_KEPT:
        kept.pop(next(iter(kept)))
    kept[node] = out
    return out
