"""The ring of robots around a fire: the regular formation law with the fire as leader.

The slots are where the deliverable's formation puts robots about a virtual leader:
``control.formation``'s regular law (the eq. 6 attraction to the circle of radius
``alpha`` and the angular-neighbour spacing of Wang, Xie and Cao 2013) is relaxed on
points started at the robots' bearings about the fire, with ``alpha`` the ring's radius;
its equilibrium is the regular polygon in the order the robots already have. The
polygon may then turn as a whole (the law is blind to a rotation) to put the most slots
on open floor with a line of sight to the fire; a slot still in a wall moves along its
ray to the nearest open radius within the nozzle's reach (the spacing is then regular
only where the walls allow). Robots take the slots by an optimal assignment (Kuhn 1955)
of their straight-line distances.

References
----------
C. Wang, G. Xie and M. Cao, "Forming circle formations of anonymous mobile agents with
order preservation", IEEE Trans. Automatic Control 58(12), 2013.
H. W. Kuhn, "The Hungarian method for the assignment problem", Naval Research Logistics
Quarterly 2, 1955.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.formation import circle_attraction, ring_spacing
from firefleet.control.mission._coverage import CoarseMap, line_of_sight, lines_of_sight
from firefleet.control.navigation import Costmap
from firefleet.planning.allocation import allocate_tasks

__all__ = ["regular_ring", "ring_slots"]

_STEP = 1.0
"""Relaxation step (a unit damping and mass: the displacement per unit force)."""
_SPACING_N_M = 0.5
"""K_s of the relaxation: its fastest angular mode moves by 2 K_s _STEP < 2 (stable)."""


def regular_ring(
    center_xy_m: FloatArray, radius_m: float, start_xy_m: FloatArray, *, tol_rad: float = 1e-6
) -> FloatArray:
    """The formation law's equilibrium on the circle about a leader.

    Parameters
    ----------
    center_xy_m : ndarray, shape (2,)
        The leader (the fire) [m].
    radius_m : float
        The circle's radius alpha [m].
    start_xy_m : ndarray, shape (M, 2)
        Where the robots are [m] (their bearings start the relaxation).
    tol_rad : float, keyword-only
        Stop once every ``|g+ - g-|`` is below this [rad].

    Returns
    -------
    ndarray, shape (M, 2)
        Points on the circle at angles ``2 pi / M`` apart, in the robots' angular order.

    Examples
    --------
    >>> import numpy as np
    >>> p = regular_ring(np.zeros(2), 2.0, np.array([[1.0, 0.0], [1.0, 0.2], [0.0, 1.0]]))
    >>> a = np.sort(np.degrees(np.arctan2(p[:, 1], p[:, 0])) % 360)
    >>> np.round(np.diff(a), 3).tolist(), np.round(np.hypot(*p.T), 6).tolist()
    ([120.0, 120.0], [2.0, 2.0, 2.0])
    """
    c = np.asarray(center_xy_m, dtype=float)
    d = np.asarray(start_xy_m, dtype=float).reshape(-1, 2) - c
    m = len(d)
    theta = np.arctan2(d[:, 1], d[:, 0])
    theta[np.hypot(d[:, 0], d[:, 1]) < 1e-9] = 0.0
    # robots at one bearing: fan them out a little, in index order
    theta = theta + 1e-3 * np.arange(m)
    p = c + radius_m * np.stack([np.cos(theta), np.sin(theta)], axis=1)
    if m < 2:
        return p
    gain = 0.25 / radius_m**2  # radial stiffness 2 a alpha^2 = 0.5
    for _ in range(5000):
        force = circle_attraction(p, c, alpha_m=radius_m, gain=gain)
        force += ring_spacing(p, c, stiffness_n_m=_SPACING_N_M)
        p = p + _STEP * force
        th = np.sort(np.arctan2(p[:, 1] - c[1], p[:, 0] - c[0]))
        gaps = np.diff(np.append(th, th[0] + 2 * math.pi))
        if np.abs(gaps - 2 * math.pi / m).max() < tol_rad:
            break
    d = p - c
    out: FloatArray = c + radius_m * d / np.hypot(d[:, 0], d[:, 1])[:, None]
    return out


def has_shot(
    cm: CoarseMap,
    pts: FloatArray,
    spots: FloatArray,
    near_m: float,
    reach_m: float,
    blocks: tuple[IntArray, int] | None = None,
) -> BoolArray:
    """Whether a nozzle at each point (P, 2) has a burning spot (S, 2) at a distance in
    ``[near_m, reach_m]`` in line of sight [m]: a shot at the fire, from no closer than
    is safe.

    ``blocks`` ``(block, n_blocks)``: the points are blocks of separate calls (point
    ``p`` of block ``block[p]``), each answered as a call with only its points
    (:func:`~firefleet.control.mission._coverage.lines_of_sight`).
    """
    p = np.asarray(pts, dtype=float).reshape(-1, 2)
    s = np.asarray(spots, dtype=float).reshape(-1, 2)
    out = np.zeros(len(p), dtype=bool)
    if len(p) == 0 or len(s) == 0:
        return out
    d = np.hypot(p[:, None, 0] - s[None, :, 0], p[:, None, 1] - s[None, :, 1])
    pi, si = np.nonzero((d >= near_m) & (d <= reach_m))
    if len(pi):
        if blocks is None:
            ok = line_of_sight(cm, p[pi], s[si])
        else:
            ok = lines_of_sight(cm, p[pi], s[si], blocks[0][pi], blocks[1])
        out[pi[ok]] = True
    return out


def _clear(pts: FloatArray, others: FloatArray, dist_m: float) -> BoolArray:
    """Points (P, 2) at least ``dist_m`` from every one of ``others`` (K, 2)."""
    if len(others) == 0 or len(pts) == 0:
        return np.ones(len(pts), dtype=bool)
    d = np.hypot(pts[:, None, 0] - others[None, :, 0], pts[:, None, 1] - others[None, :, 1])
    out: BoolArray = d.min(axis=1) >= dist_m
    return out


def _valid(
    cm: CoarseMap,
    costmap: Costmap,
    reachable: BoolArray,
    spots: FloatArray,
    near_m: float,
    shot_m: float,
    pts: FloatArray,
    avoid: FloatArray,
    avoid_m: float,
    clear: FloatArray,
    blocks: tuple[IntArray, int] | None = None,
) -> BoolArray:
    """Slots a robot may stand on (open, ``near_m`` from every spot and every point of
    ``clear``, ``avoid_m`` from every hot place), can get to (``reachable``, on the map
    grid) and spray the fire from (:func:`has_shot`; ``blocks`` as there: every test
    but the shot's is the point's own)."""
    grid = costmap.grid
    inside = grid.contains(pts)
    rc = grid.cell_of(pts)
    h, w = grid.shape
    r, c = np.clip(rc[:, 0], 0, h - 1), np.clip(rc[:, 1], 0, w - 1)
    open_ = inside & ~costmap.blocked[r, c] & reachable[r, c]
    open_ &= _clear(pts, spots, near_m) & _clear(pts, clear, near_m)
    open_ &= _clear(pts, avoid, avoid_m)
    out: BoolArray = open_ & has_shot(cm, pts, spots, near_m, shot_m, blocks)
    return out


def _fix(
    slots: FloatArray,
    bad: BoolArray,
    c: FloatArray,
    radius_m: float,
    lo_m: float,
    valid: Callable[[FloatArray], BoolArray],
    cm: CoarseMap,
    spots: FloatArray,
    near_m: float,
    shot_m: float,
    gap_m: float,
) -> None:
    """Move the invalid slots (``bad``, in place) along their rays to the nearest valid
    radius, else to the nearest valid coarse cell ``gap_m`` from the other slots."""
    lo = lo_m
    radii = np.concatenate(
        [np.arange(radius_m - 0.1, lo, -0.1), np.arange(radius_m + 0.1, radius_m + 1.5, 0.1)]
    )
    radii = radii[np.argsort(np.abs(radii - radius_m), kind="stable")]
    for i in map(int, np.flatnonzero(bad)):
        u = (slots[i] - c) / radius_m
        cand = c + radii[:, None] * u
        ok = valid(cand)
        if ok.any():
            slots[i] = cand[int(np.argmax(ok))]
            bad[i] = False
    if bad.any():
        # off the ring: the nearest cell with a shot, clear of the other slots
        cells = np.argwhere(cm.standable)
        xy = cm.goal_xy(cells)
        # only cells within shot_m of a spot's box can have a shot (the same cells, fewer
        # distances: on floor100 the whole map is ~100,000 cells)
        if len(spots):
            lo_xy, hi_xy = spots.min(axis=0) - shot_m, spots.max(axis=0) + shot_m
            xy = xy[np.all((xy >= lo_xy) & (xy <= hi_xy), axis=1)]
        ds = np.hypot(xy[:, None, 0] - spots[None, :, 0], xy[:, None, 1] - spots[None, :, 1])
        xy = xy[np.any((ds >= near_m) & (ds <= shot_m), axis=1)]
        xy = xy[valid(xy)]
        for i in map(int, np.flatnonzero(bad)):
            others = slots[~bad]
            if len(others):
                gap = np.hypot(
                    xy[:, None, 0] - others[None, :, 0], xy[:, None, 1] - others[None, :, 1]
                )
                cand = xy[gap.min(axis=1) >= gap_m]
            else:
                cand = xy
            if len(cand):
                slots[i] = cand[int(np.argmin(np.hypot(*(cand - slots[i]).T)))]
                bad[i] = False


def ring_slots(
    cm: CoarseMap,
    costmap: Costmap,
    center_xy_m: FloatArray,
    radius_m: float,
    robots_xy_m: FloatArray,
    *,
    spots_xy_m: FloatArray | None = None,
    reachable: BoolArray | None = None,
    near_m: float = 0.0,
    shot_m: float = math.inf,
    gap_m: float = 0.0,
    avoid_xy_m: FloatArray | None = None,
    avoid_m: float = 0.0,
    clear_xy_m: FloatArray | None = None,
) -> FloatArray:
    """Each robot's slot on the ring about a fire (module notes).

    A slot is valid when it is open, reachable and has a shot: a burning spot at a
    distance in ``[near_m, shot_m]`` in line of sight. The regular polygon turns to put
    the most slots on valid spots; a slot still invalid moves along its ray to the
    nearest valid radius, else to the nearest valid coarse cell at least ``gap_m`` from
    every other slot (the spacing is then regular only where the walls allow).

    Parameters
    ----------
    cm : CoarseMap
        For the lines of sight and the candidate cells.
    costmap : Costmap
        Where a robot may stand.
    center_xy_m : ndarray, shape (2,)
        The fire [m].
    radius_m : float
        The ring's radius [m].
    robots_xy_m : ndarray, shape (M, 2)
        The robots assigned to the fire [m].
    spots_xy_m : ndarray, shape (S, 2), optional
        The fire's burning spots [m] (default: its centre).
    reachable : ndarray of bool, shape (H, W), optional
        Map cells the robots can get to (default: every open cell).
    near_m, shot_m : float
        Nearest and farthest a slot's shot may be [m].
    gap_m : float
        Least distance between two slots moved off the ring [m].
    avoid_xy_m : ndarray, shape (K, 2), optional
        Places too hot to stand (where a robot's air reached its retreat temperature).
    avoid_m : float
        Least distance of a slot from them [m].
    clear_xy_m : ndarray, shape (C, 2), optional
        More places a slot keeps ``near_m`` from without aiming at them (flames the
        team believes it has soaked: the fire may still burn next to them).

    Returns
    -------
    ndarray, shape (M, 2)
        Robot k's slot [m].
    """
    c = np.asarray(center_xy_m, dtype=float)
    robots = np.asarray(robots_xy_m, dtype=float).reshape(-1, 2)
    spots = c[None] if spots_xy_m is None else np.asarray(spots_xy_m, dtype=float).reshape(-1, 2)
    reach = np.ones(costmap.grid.shape, dtype=bool) if reachable is None else reachable

    avoid = np.zeros((0, 2)) if avoid_xy_m is None else np.asarray(avoid_xy_m).reshape(-1, 2)
    clear = np.zeros((0, 2)) if clear_xy_m is None else np.asarray(clear_xy_m).reshape(-1, 2)

    def valid(pts: FloatArray) -> BoolArray:
        return _valid(cm, costmap, reach, spots, near_m, shot_m, pts, avoid, avoid_m, clear)

    m = len(robots)
    ring = regular_ring(c, radius_m, robots)
    d = ring - c
    base = np.arctan2(d[:, 1], d[:, 0])
    best, best_score = ring, -1.0
    step = math.radians(5.0)
    period = 2 * math.pi / m
    turns = []
    for k in range(max(1, round(period / step))):
        delta = k * step
        delta = delta if delta <= period / 2 else delta - period
        ang = base + delta
        turns.append((delta, c + radius_m * np.stack([np.cos(ang), np.sin(ang)], axis=1)))
    # every turn's slots tested in one pass, each turn as a call of its own (_valid)
    ok = _valid(
        cm, costmap, reach, spots, near_m, shot_m, np.concatenate([p for _, p in turns]),
        avoid, avoid_m, clear, (np.repeat(np.arange(len(turns)), m), len(turns)),
    ).reshape(len(turns), m)  # fmt: skip
    for (delta, pts), ok_k in zip(turns, ok, strict=True):
        score = ok_k.sum() - abs(delta) * 1e-3
        if score > best_score:
            best, best_score = pts, score
    slots = best.copy()
    bad = ~valid(slots)
    _fix(
        slots, bad, c, radius_m, costmap.inflation_m + 0.2, valid, cm, spots, near_m, shot_m, gap_m
    )
    if bad.any() and len(avoid):
        # no slot with a shot clear of the hot places: one nearer them (a hot place is
        # where the air was hot once; the fire's cells burn on behind it)
        def valid_near_hot(pts: FloatArray) -> BoolArray:
            return _valid(cm, costmap, reach, spots, near_m, shot_m, pts, avoid[:0], 0.0, clear)

        _fix(
            slots,
            bad,
            c,
            radius_m,
            costmap.inflation_m + 0.2,
            valid_near_hot,
            cm,
            spots,
            near_m,
            shot_m,
            gap_m,
        )
    cost = np.hypot(robots[:, None, 0] - slots[None, :, 0], robots[:, None, 1] - slots[None, :, 1])
    pick = allocate_tasks(cost)
    out: FloatArray = slots[pick]
    return out
