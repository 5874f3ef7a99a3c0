"""The team's knowledge of fires and victims, merged from every robot's detections.

With the ideal link every robot receives what all the others sent at the last tick, so
the team holds one knowledge, the union of all detections (each detection a message):

- a *fire* is a cluster of burning *spots* (points a robot detected fire at, kept at
  least half ``fire_merge_m`` apart, so the cluster keeps the fire's extent); a
  detection within ``fire_merge_m`` of a spot joins that spot's fire (and joins two
  fires it touches into one), farther it starts a new fire. A spot is believed out
  after ``fire_out_looks`` thermal frames in a row that looked at it (in a camera's
  cone, within ``sensing_range_m``, in line of sight; a spot without flames inside a
  wall or a rack looked at on its face: :func:`seen_point`) and saw no fire within
  ``fire_merge_m``; a fire without spots is out. A fire's position is the mean of its
  spots, its extent the largest distance of a spot from it;
- a *victim* is a person detection that can be a person (not on a wall of the plan,
  not behind one: :mod:`._people`); later ones within ``victim_merge_m`` refine its
  position (running mean). It is *confirmed* once ``confirm_repeats`` detections of it
  came from robots within ``confirm_radius_m`` (2 m, the issue's rule) of it. An
  unconfirmed victim is *dismissed* after ``victim_out_looks`` looks at it that saw no
  person there (until detected again), or *given up* once a confirmer has stood
  ``confirm_watch_s`` where it could confirm it (:func:`watch_victims`; only a
  confirmation brings it back).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.ndimage as ndi

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.mission._coverage import CoarseMap, in_view, line_of_sight
from firefleet.control.mission._params import TacticsParams
from firefleet.control.mission._people import confirm_sight, person_plausible
from firefleet.control.mission._water import soaked_at

__all__ = [
    "Knowledge",
    "empty_knowledge",
    "fires_of",
    "seen_point",
    "update_knowledge",
    "watch_victims",
]


@dataclass(frozen=True, eq=False)
class Knowledge:
    """Fires (as spots) and victims the team believes in (module notes).

    Attributes
    ----------
    spot_xy_m : ndarray, shape (S, 2)
        Burning spots [m].
    spot_fire : ndarray of int, shape (S,)
        The fire (a stable id) of each spot.
    spot_flame : ndarray of bool, shape (S,)
        Whether a detection reading ``flame_c`` or more put or kept each spot (flames,
        not the hot gas a fire pushes ahead of it).
    spot_misses : ndarray of int, shape (S,)
        Looks in a row that saw no fire at each spot.
    next_fire : int
        The next fire id.
    victim_xy_m : ndarray, shape (V, 2)
        Victims [m].
    victim_hits : ndarray of int, shape (V,)
        Detections merged into each.
    victim_close : ndarray of int, shape (V,)
        Detections of each from within ``confirm_radius_m``.
    victim_confirmed_s : ndarray, shape (V,)
        When each was confirmed [s] (NaN: not yet).
    victim_misses : ndarray of int, shape (V,)
        Looks in a row at each (where the camera would name a person: in its cone
        narrowed by the person's width, from ``sensing_near_m`` to ``sensing_range_m``,
        in sight) that saw no person there; an unconfirmed victim with
        ``victim_out_looks`` of them is dismissed (a false detection: hot gas at a
        door) until detected again.
    wet_l_m2 : ndarray, shape (Hc, Wc) or (0, 0)
        The team's ledger of the water it sprayed on the coarse cells [L/m^2]
        (:mod:`._water`; (0, 0) before the first spray).
    victim_watch_s : ndarray, shape (V,)
        Time a confirmer has stood where it can confirm each (:func:`watch_victims`) [s].
    victim_given_up : ndarray of bool, shape (V,)
        Unconfirmed victims a confirmer watched for ``confirm_watch_s`` without
        confirming: no robot is sent to them again (a detection from within the
        confirmation radius still confirms them).
    fire_last_s : ndarray, shape (next_fire,) or (0,)
        When a detection last joined each fire id [s] (``fire_forget_s``).
    """

    spot_xy_m: FloatArray
    spot_fire: IntArray
    spot_flame: BoolArray
    spot_misses: IntArray
    next_fire: int
    victim_xy_m: FloatArray
    victim_hits: IntArray
    victim_close: IntArray
    victim_confirmed_s: FloatArray
    victim_misses: IntArray
    wet_l_m2: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))
    victim_watch_s: FloatArray = field(default_factory=lambda: np.zeros(0))
    victim_given_up: BoolArray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    fire_last_s: FloatArray = field(default_factory=lambda: np.zeros(0))

    @property
    def victim_confirmed(self) -> BoolArray:
        """Whether each victim is confirmed, shape (V,)."""
        out: BoolArray = np.isfinite(self.victim_confirmed_s)
        return out

    def dismissed(self, params: TacticsParams) -> BoolArray:
        """Unconfirmed victims dismissed as false detections (looked at without a
        person there, or given up by a confirmer), shape (V,)."""
        out: BoolArray = ~self.victim_confirmed & (
            (self.victim_misses >= params.victim_out_looks) | self.victim_given_up
        )
        return out


def empty_knowledge() -> Knowledge:
    """Nothing known yet."""
    return Knowledge(
        spot_xy_m=np.zeros((0, 2)),
        spot_fire=np.zeros(0, dtype=np.int64),
        spot_flame=np.zeros(0, dtype=bool),
        spot_misses=np.zeros(0, dtype=np.int64),
        next_fire=0,
        victim_xy_m=np.zeros((0, 2)),
        victim_hits=np.zeros(0, dtype=np.int64),
        victim_close=np.zeros(0, dtype=np.int64),
        victim_confirmed_s=np.zeros(0),
        victim_misses=np.zeros(0, dtype=np.int64),
    )


def fires_of(k: Knowledge) -> tuple[IntArray, FloatArray, FloatArray]:
    """The believed fires: ids (F,) ascending, positions (F, 2) [m], extents (F,) [m]."""
    ids, inv = np.unique(k.spot_fire, return_inverse=True)
    f = len(ids)
    if f == 0:
        return ids.astype(np.int64), np.zeros((0, 2)), np.zeros(0)
    counts = np.bincount(inv, minlength=f).astype(float)
    xy = (
        np.stack(
            [np.bincount(inv, k.spot_xy_m[:, 0], f), np.bincount(inv, k.spot_xy_m[:, 1], f)], axis=1
        )
        / counts[:, None]
    )
    d = np.hypot(*(k.spot_xy_m - xy[inv]).T)
    extent = np.zeros(f)
    np.maximum.at(extent, inv, d)
    return ids.astype(np.int64), xy, extent


def _add_fire(
    k: Knowledge, p: FloatArray, merge_m: float, flame: bool = False
) -> tuple[Knowledge, bool]:
    """One fire detection into the spots; True when the set of fires changed."""
    if len(k.spot_xy_m):
        d = np.hypot(k.spot_xy_m[:, 0] - p[0], k.spot_xy_m[:, 1] - p[1])
        near = d <= merge_m
    else:
        d = np.zeros(0)
        near = np.zeros(0, dtype=bool)
    if near.any():
        touched = np.unique(k.spot_fire[near])
        fire = int(touched.min())
        spot_fire = k.spot_fire
        if len(touched) > 1:  # the detection joins fires that grew together
            spot_fire = np.where(np.isin(spot_fire, touched), fire, spot_fire)
        misses = k.spot_misses.copy()
        misses[d <= 0.5 * merge_m] = 0
        flames = k.spot_flame | (flame & (d <= 0.5 * merge_m))
        if d.min() > 0.5 * merge_m:  # a new spot of that fire
            return replace(
                k,
                spot_xy_m=np.vstack([k.spot_xy_m, p[None]]),
                spot_fire=np.append(spot_fire, fire),
                spot_flame=np.append(flames, flame),
                spot_misses=np.append(misses, 0),
            ), len(touched) > 1 or (flame and not k.spot_flame.any())
        return replace(k, spot_fire=spot_fire, spot_flame=flames, spot_misses=misses), len(
            touched
        ) > 1 or bool(flames.sum() > k.spot_flame.sum() and not k.spot_flame.any())
    return replace(
        k,
        spot_xy_m=np.vstack([k.spot_xy_m, p[None]]),
        spot_fire=np.append(k.spot_fire, k.next_fire),
        spot_flame=np.append(k.spot_flame, flame),
        spot_misses=np.append(k.spot_misses, 0),
        next_fire=k.next_fire + 1,
    ), True


def _add_person(
    k: Knowledge, p: FloatArray, robot_xy: FloatArray, t_s: float, params: TacticsParams
) -> tuple[Knowledge, bool]:
    """One person detection into the victims; True when a victim appeared or was confirmed."""
    close = math.hypot(*(robot_xy - p)) <= params.confirm_radius_m
    if len(k.victim_xy_m):
        d = np.hypot(k.victim_xy_m[:, 0] - p[0], k.victim_xy_m[:, 1] - p[1])
        j = int(np.argmin(d))
        if d[j] <= params.victim_merge_m:
            hits = k.victim_hits.copy()
            hits[j] += 1
            xy = k.victim_xy_m.copy()
            xy[j] += (p - xy[j]) / hits[j]
            near = k.victim_close.copy()
            near[j] += int(math.hypot(*(robot_xy - xy[j])) <= params.confirm_radius_m)
            conf = k.victim_confirmed_s.copy()
            new = bool(~np.isfinite(conf[j]) and near[j] >= params.confirm_repeats)
            if new:
                conf[j] = t_s
            misses = k.victim_misses.copy()
            back = bool(misses[j] >= params.victim_out_looks) and not k.victim_given_up[j]
            misses[j] = 0
            return replace(
                k,
                victim_xy_m=xy,
                victim_hits=hits,
                victim_close=near,
                victim_confirmed_s=conf,
                victim_misses=misses,
            ), new or back
    conf_s = t_s if close and params.confirm_repeats <= 1 else math.nan
    return replace(
        k,
        victim_xy_m=np.vstack([k.victim_xy_m, p[None]]),
        victim_hits=np.append(k.victim_hits, 1),
        victim_close=np.append(k.victim_close, int(close)),
        victim_confirmed_s=np.append(k.victim_confirmed_s, conf_s),
        victim_misses=np.append(k.victim_misses, 0),
        victim_watch_s=np.append(k.victim_watch_s, 0.0),
        victim_given_up=np.append(k.victim_given_up, False),
    ), True


def behind_water(
    wet_l_m2: FloatArray,
    cm: CoarseMap,
    pose: FloatArray,
    fire_xy: FloatArray,
    fire_robot: IntArray,
    flames: BoolArray,
    soak_l_m2: float,
    *,
    step_m: float = 0.125,
    max_m: float = 1.5,
    front_m: float = 0.5,
) -> FloatArray:
    """Flame detections that fell on soaked cells, moved along their camera's ray to the
    first open cell not soaked (within ``max_m``), or, with none behind it before a wall,
    to the nearest such cell in front of it (within ``front_m``); none: unchanged.

    A soaked cell no longer burns (:mod:`._water`): flames seen there are behind it, as
    the detector's range reads short over a fire's near edge (mission-office, seed 1:
    a median 0.44 m short of the first burning cell on the ray, a quarter more than
    2 m short), or, with only soaked cells and a wall behind, in front of it: the range
    read long (small-house, seed 4: three cells along a cabinet burned from 500 s to
    the end, 0-0.1 L/m^2 on them, their flames seen 0.2 m beyond them on cells the team
    had soaked, so no fighter aimed at them).

    Parameters
    ----------
    wet_l_m2 : ndarray, shape (Hc, Wc)
    cm : CoarseMap
    pose : ndarray, shape (N, 3)
    fire_xy : ndarray, shape (K, 2)
    fire_robot : ndarray of int, shape (K,)
    flames : ndarray of bool, shape (K,)
    soak_l_m2 : float
        Water per area that soaks a cell [L/m^2].
    step_m, max_m : float
        The walk's step and length [m].

    Returns
    -------
    ndarray, shape (K, 2)
        A new array.
    """
    out = np.array(fire_xy, dtype=float, copy=True)
    todo = np.flatnonzero(flames & soaked_at(wet_l_m2, cm, out, soak_l_m2))

    def first_dry(walk: FloatArray) -> int:
        """Index of the first point of ``walk`` on a dry cell before a wall (-1: none)."""
        rc = cm.cell_of(walk)
        wall = cm.opaque[rc[:, 0], rc[:, 1]]
        stop = int(np.argmax(wall)) if wall.any() else len(walk)
        dry = np.flatnonzero(~soaked_at(wet_l_m2, cm, walk[:stop], soak_l_m2))
        return int(dry[0]) if len(dry) else -1

    for j in map(int, todo):
        u = out[j] - pose[int(fire_robot[j]), :2]
        norm = math.hypot(float(u[0]), float(u[1]))
        if norm < 1e-9:
            continue
        # behind it, then in front of it short of the camera (never within a step of it)
        for steps in (
            np.arange(step_m, max_m + 1e-9, step_m),
            -np.arange(step_m, min(front_m, norm - step_m) + 1e-9, step_m),
        ):
            walk = out[j] + steps[:, None] * (u / norm)
            k = first_dry(walk) if len(walk) else -1
            if k >= 0:
                out[j] = walk[k]
                break
    return out


def seen_burning(
    k: Knowledge, cm: CoarseMap, flames_xy_m: FloatArray, soak_l_m2: float
) -> Knowledge:
    """The ledger told by the cameras: a flame seen on a cell the ledger holds soaked,
    with no dry cell near it on its ray (:func:`behind_water`), burns: the water the
    ledger put there did not reach it (a wall the coarse line of sight missed, a pose
    off by a cell), so the cell is dry again (its water 0) and the fighters aim at it.

    The maze, seed 0: at 200 s the team held all eight of its fire's flames soaked and
    no fighter aimed, while the fire burned on cells the ledger held at 2.5 L/m^2 and
    the world's water there was 0 (the coarse cone had passed a wall's corner); the fire
    then burned along the only passage to both people.

    Parameters
    ----------
    k : Knowledge
    cm : CoarseMap
    flames_xy_m : ndarray, shape (K, 2)
        Where this tick's flame detections lie [m] (after :func:`behind_water`).
    soak_l_m2 : float
        Water per area that soaks a cell [L/m^2].

    Returns
    -------
    Knowledge
        ``k`` itself when no flame lies on a soaked cell; else with a new ledger.

    Examples
    --------
    >>> import numpy as np
    >>> from dataclasses import replace
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.world import OccupancyGrid
    >>> walls = np.zeros((8, 8), dtype=bool)
    >>> cm = coarse_map(build_costmap(OccupancyGrid(walls, ~walls, resolution_m=0.25), 0.2), 0.25)
    >>> k = replace(empty_knowledge(), wet_l_m2=np.full(cm.shape, 2.0))
    >>> k2 = seen_burning(k, cm, np.array([[0.6, 0.6]]), 1.3)
    >>> float(k2.wet_l_m2.sum()), float(k.wet_l_m2.sum())  # one cell dry again
    (126.0, 128.0)
    >>> seen_burning(k2, cm, np.zeros((0, 2)), 1.3) is k2
    True
    """
    pts = np.asarray(flames_xy_m, dtype=float).reshape(-1, 2)
    if len(pts) == 0 or k.wet_l_m2.shape != cm.shape:
        return k
    wet = soaked_at(k.wet_l_m2, cm, pts, soak_l_m2)
    if not wet.any():
        return k
    rc = cm.cell_of(pts[wet])
    ledger = k.wet_l_m2.copy()
    ledger[rc[:, 0], rc[:, 1]] = 0.0
    return replace(k, wet_l_m2=ledger)


def seen_point(cm: CoarseMap, xy_m: FloatArray) -> FloatArray:
    """Where a camera looks to see each spot (M, 2) [m]: the spot itself, or, for one in
    an opaque coarse cell, the centre of the nearest cell that is not (the face of the
    shelf or wall a stereo depth put it behind).

    Nothing burns inside a wall or a rack (their cells hold no fuel), so a fire spot
    there is the detector's depth error; looks at the spot itself never had a line of
    sight, and it was never believed out (mission-warehouse seed 3: spots 0.2 m inside
    the racks beside a burnt-out aisle held a flameless fire, and a fighter with it,
    from 150 s to the end, while the fires that burned ran their fighters dry).
    :func:`update_knowledge` looks at the spots without flames so (the hot floor and
    gas a fire leaves behind); flames stay where they were placed (with flame spots
    too, mission-office seed 1 left a cell behind a door's jamb burning to the end).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.mission._coverage import coarse_map
    >>> from firefleet.control.navigation import build_costmap
    >>> from firefleet.world import OccupancyGrid
    >>> occ = np.zeros((8, 8), dtype=bool)
    >>> occ[:, 4:] = True  # a wall from x = 2 m
    >>> cm = coarse_map(build_costmap(OccupancyGrid(occ, ~occ, 0.5), 0.1), 0.5)
    >>> seen_point(cm, np.array([[2.2, 1.1], [1.2, 1.1]])).tolist()  # in the wall; not
    [[1.75, 1.25], [1.2, 1.1]]
    """
    pts = np.array(xy_m, dtype=float, copy=True).reshape(-1, 2)
    if len(pts) == 0:
        return pts
    rc = cm.cell_of(pts)
    inside = cm.opaque[rc[:, 0], rc[:, 1]]
    if not inside.any() or cm.opaque.all():
        return pts
    key = ("nearest_clear",)
    near = cm.cache.get(key)
    if not isinstance(near, np.ndarray):
        _, idx = ndi.distance_transform_edt(cm.opaque, return_indices=True)
        near = np.stack(idx, axis=-1)
        cm.cache[key] = near
    pts[inside] = cm.centre_xy(near[rc[inside, 0], rc[inside, 1]])
    return pts


def update_knowledge(
    k: Knowledge,
    cm: CoarseMap,
    pose: FloatArray,
    fire_xy: FloatArray,
    fire_robot: IntArray,
    person_xy: FloatArray,
    person_robot: IntArray,
    looked: BoolArray,
    t_s: float,
    params: TacticsParams,
    fire_peak_c: FloatArray | None = None,
) -> tuple[Knowledge, bool]:
    """This tick's detections and looks into the knowledge (module notes).

    Parameters
    ----------
    k : Knowledge
    cm : CoarseMap
        For the lines of sight of the looks.
    pose : ndarray, shape (N, 3)
        Estimated poses.
    fire_xy, person_xy : ndarray, shape (K, 2), (P, 2)
        Detections [m].
    fire_robot, person_robot : ndarray of int, shape (K,), (P,)
        Who made them.
    looked : ndarray of bool, shape (N,)
        Robots (working) whose thermal frame was read this tick.
    t_s : float
    params : TacticsParams
    fire_peak_c : ndarray, shape (K,), optional
        Each fire detection's peak reading [C] (``flame_c`` or more: flames; not given:
        every detection is flames).

    Returns
    -------
    Knowledge
    changed : bool
        A fire or a victim appeared, merged, went out or was confirmed.
    """
    changed = False
    if len(person_xy):
        # person detections that cannot be a person (on a wall of the plan, behind
        # one: :mod:`._people`) go before anything else
        keep = person_plausible(cm, pose[person_robot, :2], person_xy, params.person_wall_m)
        if not keep.all():
            person_xy, person_robot = person_xy[keep], person_robot[keep]
    flames = (
        np.ones(len(fire_xy), dtype=bool) if fire_peak_c is None else fire_peak_c >= params.flame_c
    )
    if flames.any() and k.wet_l_m2.shape == cm.shape:
        fire_xy = behind_water(k.wet_l_m2, cm, pose, fire_xy, fire_robot, flames, params.soak_l_m2)
        k = seen_burning(k, cm, fire_xy[flames], params.soak_l_m2)
    for p, f in zip(fire_xy, flames, strict=True):
        k, c = _add_fire(k, p, params.fire_merge_m, bool(f))
        changed |= c
    for p, r in zip(person_xy, person_robot, strict=True):
        k, c = _add_person(k, p, pose[int(r), :2], t_s, params)
        changed |= c
    if len(k.spot_xy_m) and looked.any():
        lookers = np.flatnonzero(looked)
        # a spot with flames is looked at where the detection put it; one without (the
        # hot floor and gas a fire leaves) on the face of the wall or rack it lies in
        spots = k.spot_xy_m.copy()
        gas = ~k.spot_flame
        spots[gas] = seen_point(cm, spots[gas])
        dx = spots[None, :, 0] - pose[lookers, None, 0]
        dy = spots[None, :, 1] - pose[lookers, None, 1]
        bearing = np.arctan2(dy, dx) - pose[lookers, None, 2]
        off = np.abs((bearing + np.pi) % (2 * np.pi) - np.pi)
        in_cone = (np.hypot(dx, dy) <= params.sensing_range_m) & (off <= 0.5 * params.hfov_rad)
        if in_cone.any():
            li, si = np.nonzero(in_cone)
            ok = line_of_sight(cm, pose[lookers[li], :2], spots[si])
            seen = np.zeros(len(spots), dtype=bool)
            seen[si[ok]] = True
            if len(fire_xy):
                at = k.spot_xy_m
                d = np.hypot(
                    at[:, None, 0] - fire_xy[None, :, 0], at[:, None, 1] - fire_xy[None, :, 1]
                )
                seen &= d.min(axis=1) > params.fire_merge_m
            if seen.any():
                misses = k.spot_misses + seen
                keep = misses < params.fire_out_looks
                before = len(np.unique(k.spot_fire))
                k = replace(
                    k,
                    spot_xy_m=k.spot_xy_m[keep],
                    spot_fire=k.spot_fire[keep],
                    spot_flame=k.spot_flame[keep],
                    spot_misses=misses[keep],
                )
                changed |= len(np.unique(k.spot_fire)) != before
    if len(k.victim_xy_m) and looked.any():
        k, c = _victim_looks(k, cm, pose, person_xy, looked, params)
        changed |= c
    if math.isfinite(params.fire_forget_s):
        k, c = _forget_fires(k, fire_xy, t_s, params.fire_forget_s)
        changed |= c
    return k, changed


def _forget_fires(
    k: Knowledge, fire_xy: FloatArray, t_s: float, forget_s: float
) -> tuple[Knowledge, bool]:
    """Each fire's last detection time updated by this tick's detections (each joins
    the fire of its nearest spot; a new fire counts from now), and the fires no
    detection joined for more than ``forget_s`` dropped with all their spots; True when
    a fire was dropped."""
    ids = max(k.next_fire, int(k.spot_fire.max()) + 1 if len(k.spot_fire) else 0)
    last = np.full(ids, t_s)
    n = min(len(k.fire_last_s), ids)
    last[:n] = k.fire_last_s[:n]
    if len(fire_xy) and len(k.spot_xy_m):
        d = np.hypot(
            k.spot_xy_m[:, None, 0] - fire_xy[None, :, 0],
            k.spot_xy_m[:, None, 1] - fire_xy[None, :, 1],
        )
        last[np.unique(k.spot_fire[np.argmin(d, axis=0)])] = t_s
    changed = False
    if len(k.spot_xy_m):
        keep = t_s - last[k.spot_fire] <= forget_s
        if not keep.all():
            changed = True
            k = replace(
                k,
                spot_xy_m=k.spot_xy_m[keep],
                spot_fire=k.spot_fire[keep],
                spot_flame=k.spot_flame[keep],
                spot_misses=k.spot_misses[keep],
            )
    return replace(k, fire_last_s=last), changed


def _victim_looks(
    k: Knowledge,
    cm: CoarseMap,
    pose: FloatArray,
    person_xy: FloatArray,
    looked: BoolArray,
    params: TacticsParams,
) -> tuple[Knowledge, bool]:
    """Unconfirmed victims looked at without a person detection near them: one miss
    each; True when one was dismissed."""
    open_ = ~k.victim_confirmed
    if not open_.any():
        return k, False
    lookers = np.flatnonzero(looked)
    vic = k.victim_xy_m
    dx = vic[None, :, 0] - pose[lookers, None, 0]
    dy = vic[None, :, 1] - pose[lookers, None, 1]
    off = np.abs((np.arctan2(dy, dx) - pose[lookers, None, 2] + np.pi) % (2 * np.pi) - np.pi)
    # a look counts only where the detector would name the person (:func:`in_view`)
    in_cone = in_view(
        np.hypot(dx, dy),
        off,
        params.sensing_range_m,
        params.hfov_rad,
        params.sensing_near_m,
        params.person_half_width_m,
    )
    in_cone &= open_[None, :]
    if not in_cone.any():
        return k, False
    li, vi = np.nonzero(in_cone)
    ok = line_of_sight(cm, pose[lookers[li], :2], vic[vi])
    seen = np.zeros(len(vic), dtype=bool)
    seen[vi[ok]] = True
    if len(person_xy):
        d = np.hypot(
            vic[:, None, 0] - person_xy[None, :, 0], vic[:, None, 1] - person_xy[None, :, 1]
        )
        seen &= d.min(axis=1) > params.victim_merge_m
    if not seen.any():
        return k, False
    misses = k.victim_misses + seen
    dismissed = (misses == params.victim_out_looks) & seen
    return replace(k, victim_misses=misses), bool(dismissed.any())


def watch_victims(
    k: Knowledge,
    cm: CoarseMap,
    pose: FloatArray,
    confirmers: IntArray,
    victims: IntArray,
    dt_s: float,
    params: TacticsParams,
) -> tuple[Knowledge, bool]:
    """Confirmers standing at their victims: each one's watch clock runs while it stands
    where it can confirm them (:func:`._people.confirm_sight`); an unconfirmed victim
    watched for ``confirm_watch_s`` is given up (``Knowledge.victim_given_up``).

    A person in sight of a confirmer is named within a frame or two (9 Hz), so a watch of
    seconds without confirmation is a false detection that keeps coming back (the
    misses a look counts are reset by each new detection near it): on mission-office
    seed 1 a robot stood 360 s on one.

    Parameters
    ----------
    k : Knowledge
    cm : CoarseMap
    pose : ndarray, shape (N, 3)
    confirmers : ndarray of int, shape (M,)
        Robots standing at their victims (arrived or settled), facing them.
    victims : ndarray of int, shape (M,)
        Their victims.
    dt_s : float
        Time since the last call [s].
    params : TacticsParams

    Returns
    -------
    Knowledge
    given_up : bool
        A victim was given up.
    """
    if len(confirmers) == 0:
        return k, False
    sees = confirm_sight(
        cm,
        pose[confirmers, :2],
        k.victim_xy_m[victims],
        params,
    )
    if not sees.any():
        return k, False
    watch = k.victim_watch_s.copy()
    np.add.at(watch, victims[sees], dt_s)
    late = (watch >= params.confirm_watch_s - 1e-9) & ~k.victim_confirmed & ~k.victim_given_up
    if late.any():
        return replace(k, victim_watch_s=watch, victim_given_up=k.victim_given_up | late), True
    return replace(k, victim_watch_s=watch), False
