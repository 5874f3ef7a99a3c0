"""The team's hot places (``control.mission._hot``) against independent references:
hand-computed merges and forgetting times, the analytic step response of a first-order
probe, and a brute-force retreat (a plain Dijkstra over a small plan, every cell tried)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.control.mission._coverage import CoarseMap, coarse_map
from firefleet.control.mission._hot import live_hot, mark_hot, probe_estimate, retreat_point
from firefleet.control.navigation import build_costmap
from firefleet.world import OccupancyGrid
from tests._dijkstra import grid_dijkstra

CELL_M = 0.25

# ---------------------------------------------------------------- mark_hot / live_hot


def test_mark_hot_merges_within_merge_m_inclusive_and_adds_beyond() -> None:
    """A point exactly ``merge_m`` from a place refreshes it; one a hair farther is a new
    place (hand-placed on the x axis, distances exact in binary)."""
    known, ts = np.array([[0.0, 0.0]]), np.array([5.0])
    xy, t, added = mark_hot(known, ts, np.array([[0.5, 0.0]]), 9.0, merge_m=0.5)
    assert xy.tolist() == [[0.0, 0.0]]
    assert t.tolist() == [9.0]
    assert not added
    xy, t, added = mark_hot(known, ts, np.array([[0.0, 0.5 + 1e-9]]), 9.0, merge_m=0.5)
    assert xy.tolist() == [[0.0, 0.0], [0.0, 0.5 + 1e-9]]
    assert t.tolist() == [5.0, 9.0]
    assert added
    # the inputs are not changed
    assert known.tolist() == [[0.0, 0.0]]
    assert ts.tolist() == [5.0]


def test_mark_hot_refreshes_every_place_in_reach_and_only_those() -> None:
    """Places at x = 0, 0.8, 3 m (marked at 1, 2, 3 s); a point at x = 0.4 is 0.4 m from
    the first two, 2.6 m from the third: the first two take the new time, the third keeps
    its own."""
    known = np.array([[0.0, 0.0], [0.8, 0.0], [3.0, 0.0]])
    xy, t, added = mark_hot(known, np.array([1.0, 2.0, 3.0]), np.array([[0.4, 0.0]]), 10.0)
    assert xy.tolist() == known.tolist()
    assert t.tolist() == [10.0, 10.0, 3.0]
    assert not added


def test_mark_hot_points_of_one_call_merge_with_each_other() -> None:
    """From no place: (0, 0) is new; (0.3, 0.4), 0.5 m from it, refreshes it; (0, 1), 1 m
    from it, is new; (0, 1.4), 0.4 m from the place the same call added, refreshes it;
    (3, 4) is new. By hand: places (0, 0), (0, 1), (3, 4)."""
    pts = np.array([[0.0, 0.0], [0.3, 0.4], [0.0, 1.0], [0.0, 1.4], [3.0, 4.0]])
    xy, t, added = mark_hot(np.zeros((0, 2)), np.zeros(0), pts, 2.0, merge_m=0.5)
    assert xy.tolist() == [[0.0, 0.0], [0.0, 1.0], [3.0, 4.0]]
    assert t.tolist() == [2.0, 2.0, 2.0]
    assert added


def test_mark_hot_without_times_takes_the_call_time_for_the_known_places() -> None:
    """``hot_s`` of another length than the places (no times kept): every known place
    takes ``t_s``."""
    known = np.array([[0.0, 0.0], [5.0, 0.0]])
    xy, t, added = mark_hot(known, np.zeros(0), np.zeros((0, 2)), 7.5)
    assert xy.tolist() == known.tolist()
    assert t.tolist() == [7.5, 7.5]
    assert not added


def test_live_hot_forgets_exactly_forget_s_after_the_last_mark() -> None:
    """Marked at 0 s and 20 s with forget_s = 30 s: at 29.999 s both live; at 30 s the
    first is forgotten (30 - 0 is not < 30), at 50 s the second."""
    xy, ts = np.array([[0.0, 0.0], [4.0, 0.0]]), np.array([0.0, 20.0])
    assert live_hot(xy, ts, 29.999, 30.0).tolist() == [[0.0, 0.0], [4.0, 0.0]]
    assert live_hot(xy, ts, 30.0, 30.0).tolist() == [[4.0, 0.0]]
    assert live_hot(xy, ts, 49.999, 30.0).tolist() == [[4.0, 0.0]]
    assert live_hot(xy, ts, 50.0, 30.0).shape == (0, 2)
    # no times recorded: every place is live
    assert live_hot(xy, np.zeros(0), 1e6, 30.0).tolist() == xy.tolist()


def test_a_forgotten_place_marked_again_lives_again() -> None:
    """The cycle the module notes describe: a door marked hot at 10 s, forgotten at 40 s;
    a robot finds its air hot again at 45 s, 0.2 m off: the old place takes the new time
    (no new one), live until 75 s."""
    xy, ts, _ = mark_hot(np.zeros((0, 2)), np.zeros(0), np.array([[2.0, 3.0]]), 10.0)
    assert live_hot(xy, ts, 39.9, 30.0).shape == (1, 2)
    assert live_hot(xy, ts, 40.0, 30.0).shape == (0, 2)
    xy, ts, added = mark_hot(xy, ts, np.array([[2.2, 3.0]]), 45.0)
    assert not added
    assert xy.tolist() == [[2.0, 3.0]]
    assert live_hot(xy, ts, 74.9, 30.0).tolist() == [[2.0, 3.0]]
    assert live_hot(xy, ts, 75.0, 30.0).shape == (0, 2)


# ---------------------------------------------------------------------- probe_estimate


def _first_order(t_s: np.ndarray, t0_c: float, t1_c: float, tau_s: float) -> np.ndarray:
    """A first-order probe's reading after a step of its air from t0 to t1 at 0 s."""
    r: np.ndarray = t1_c + (t0_c - t1_c) * np.exp(-np.maximum(t_s, 0.0) / tau_s)
    return r


def test_probe_estimate_undoes_the_lag_of_a_first_order_probe() -> None:
    """The air steps 20 -> 300 C at 0 s; a probe of 10 s lag reads it every 0.125 s. The
    estimate over a backward difference of span h is, analytically,
    ``T1 + (T1 - T0) exp(-t / tau) (tau (exp(h / tau) - 1) / h - 1)``, the slope taken
    from the last renewal (every whole second, window 1 s: h = t - (ceil(t) - 1)). So
    the estimate is within 5.2 % of the step from the first second on (tau (e^0.1 - 1)
    - 1 = 0.0517 at h = 1 s), while the reading lags by up to the whole step."""
    t0, t1, tau = 20.0, 300.0, 10.0
    times = np.arange(0, 161) * 0.125  # 0 .. 20 s, exact in binary
    reads = _first_order(times, t0, t1, tau)
    est, prev, prev_s = probe_estimate(np.array([reads[0]]), np.zeros(0), math.nan, 0.0, tau)
    assert est.tolist() == [t0]
    assert prev.tolist() == [t0]
    assert prev_s == 0.0
    worst_read, worst_est = 0.0, 0.0
    for t, r in zip(times[1:], reads[1:], strict=True):
        est, prev, prev_s = probe_estimate(np.array([r]), prev, prev_s, float(t), tau)
        h = t - (math.ceil(t) - 1.0)
        expected = t1 + (t1 - t0) * math.exp(-t / tau) * (tau * math.expm1(h / tau) / h - 1.0)
        assert est[0] == pytest.approx(expected, rel=1e-12, abs=1e-9), t
        assert prev_s == (t if t == math.floor(t) else math.floor(t))
        worst_read = max(worst_read, (t1 - r) / (t1 - t0))
        worst_est = max(worst_est, abs(est[0] - t1) / (t1 - t0))
    assert worst_est <= 0.052
    assert worst_read >= 0.86  # the reading alone is 86 % short 0.125 s after the step
    # at 1 s, by hand: the reading 20 + 280 (1 - e^-0.1) = 46.65 C, the air estimated at
    # 300 + 280 e^-0.1 (10 (e^0.1 - 1) - 1) = 313.10 C
    r1 = _first_order(np.array([0.0, 1.0]), t0, t1, tau)
    assert r1[1] == pytest.approx(46.65, abs=0.01)
    e1, _, _ = probe_estimate(r1[1:], r1[:1], 0.0, 1.0, tau)
    assert e1[0] == pytest.approx(313.10, abs=0.01)


def test_probe_estimate_falling_and_steady_readings_are_taken_as_read() -> None:
    """Two robots at once: one probe cooling 300 -> 20 C (slope < 0), one steady; both
    estimates are the readings, never below them."""
    tau = 10.0
    est, prev, ps = probe_estimate(np.array([300.0, 55.0]), np.zeros(0), math.nan, 0.0, tau)
    for t in np.arange(1, 41) * 0.25:
        r = np.array([_first_order(np.array([t]), 300.0, 20.0, tau)[0], 55.0])
        est, prev, ps = probe_estimate(r, prev, ps, float(t), tau)
        assert est.tolist() == r.tolist()


def test_probe_estimate_with_no_history_or_no_time_passed() -> None:
    """No slope without a history: a ``prev_c`` of another shape, or a NaN ``prev_s``,
    returns the readings and starts the history; a tick at the same time as the history
    (dt = 0) or before it returns the readings and keeps the history."""
    air = np.array([80.0, 30.0])
    for prev_c, prev_s in ((np.zeros(0), 0.0), (np.zeros(3), 0.0), (np.zeros(2), math.nan)):
        est, prev, ps = probe_estimate(air, prev_c, prev_s, 4.0, 10.0)
        assert est.tolist() == air.tolist()
        assert prev.tolist() == air.tolist()
        assert ps == 4.0
    hist = np.array([20.0, 20.0])
    for t in (4.0, 3.0):
        est, prev, ps = probe_estimate(air, hist, 4.0, t, 10.0)
        assert est.tolist() == air.tolist()
        assert prev.tolist() == hist.tolist()
        assert ps == 4.0


def test_probe_estimate_window_keeps_the_slope_base_until_it_is_spanned() -> None:
    """window_s = 2 s: readings 20, 30, 40 C at 0, 1, 2 s: at 1 s the slope is
    (30 - 20) / 1 with the base kept at 0 s; at 2 s (40 - 20) / 2 and the base renewed
    to 2 s. lag 10 s: estimates 130 C and 140 C."""
    est, prev, ps = probe_estimate(np.array([20.0]), np.zeros(0), math.nan, 0.0, 10.0, 2.0)
    est, prev, ps = probe_estimate(np.array([30.0]), prev, ps, 1.0, 10.0, 2.0)
    assert est.tolist() == [130.0]
    assert prev.tolist() == [20.0]
    assert ps == 0.0
    est, prev, ps = probe_estimate(np.array([40.0]), prev, ps, 2.0, 10.0, 2.0)
    assert est.tolist() == [140.0]
    assert prev.tolist() == [40.0]
    assert ps == 2.0


# ----------------------------------------------------------------------- retreat_point


def _plan() -> np.ndarray:
    """A 6 m x 3 m plan at 0.25 m (12 x 24 cells, row 0 at the top): outer walls, a wall
    at x = 3.0-3.25 m with a 0.5 m door at y = 1.0-1.5 m, and a pillar."""
    occ = np.zeros((12, 24), dtype=bool)
    occ[0] = occ[-1] = True
    occ[:, 0] = occ[:, -1] = True
    occ[:, 12] = True
    occ[6:8, 12] = False  # rows 6-7: y 1.0-1.5 m
    occ[3:5, 17:19] = True  # a pillar in the east room
    return occ


def _cm(occ: np.ndarray) -> CoarseMap:
    cm = coarse_map(build_costmap(OccupancyGrid(occ, ~occ, resolution_m=CELL_M), 0.1), CELL_M)
    assert cm.factor == 1
    assert (cm.standable == ~occ).all()
    return cm


def _dijkstra(free: np.ndarray, start: tuple[int, int]) -> np.ndarray:
    """Travel [m] on the free cells' 8-neighbour graph (no corner cutting), by heapq."""
    return grid_dijkstra(free, start, CELL_M)


def _centre(r: int, c: int, h: int) -> tuple[float, float]:
    return (c + 0.5) * CELL_M, (h - r - 0.5) * CELL_M


def _brute_retreat(
    occ: np.ndarray, start_rc: tuple[int, int], away: np.ndarray, clear_m: float, limit_m: float
) -> tuple[float, np.ndarray]:
    """Least travel to a free cell whose centre is at least ``clear_m`` from every point
    of ``away`` (inf: none within ``limit_m``), and the travel of every cell."""
    free = ~occ
    dist = _dijkstra(free, start_rc)
    best = math.inf
    h = occ.shape[0]
    for r, c in np.argwhere(free & (dist <= limit_m)):
        x, y = _centre(int(r), int(c), h)
        if len(away) == 0 or np.hypot(away[:, 0] - x, away[:, 1] - y).min() >= clear_m:
            best = min(best, float(dist[r, c]))
    return best, dist


def test_retreat_point_is_the_nearest_clear_place_by_travel_brute_force() -> None:
    """Random robots and hot places on the two-room plan: the point returned is a cell
    centre clear of every hot place by ``clear_m``, and no clear cell is nearer by travel
    (a Dijkstra of its own, every free cell tried). The door makes travel differ from
    the straight line: a robot in the door with the west room hot goes east."""
    occ = _plan()
    cm = _cm(occ)
    h = occ.shape[0]
    free_rc = np.argwhere(~occ)
    rng = np.random.default_rng(15)
    checked_found = checked_none = 0
    for _ in range(60):
        r0, c0 = free_rc[rng.integers(len(free_rc))]
        start = np.array(_centre(int(r0), int(c0), h))
        k = int(rng.integers(0, 5))
        away = rng.uniform([0.0, 0.0], [6.0, 3.0], size=(k, 2))
        clear_m = float(rng.uniform(0.5, 2.0))
        limit_m = float(rng.choice([2.0, 8.0]))
        best, dist = _brute_retreat(occ, (int(r0), int(c0)), away, clear_m, limit_m)
        p = retreat_point(cm, start, away, clear_m, limit_m)
        if not math.isfinite(best):
            assert np.isnan(p).all()
            checked_none += 1
            continue
        rc = cm.cell_of(p[None])[0]
        assert np.allclose(p, _centre(int(rc[0]), int(rc[1]), h))
        if k:
            assert np.hypot(away[:, 0] - p[0], away[:, 1] - p[1]).min() >= clear_m
        assert dist[rc[0], rc[1]] == pytest.approx(best, abs=1e-9)
        checked_found += 1
    assert checked_found >= 30
    assert checked_none >= 1


def test_retreat_point_goes_through_the_door_not_through_the_wall() -> None:
    """The west room all hot (places at x 1.0 and 2.5 m, y 0.5, 1.5, 2.5 m; clear_m 1 m:
    every west cell is nearer than 1 m to one), a robot just west of the wall at
    (2.875, 2.375): the clear cell nearest by straight line is across the wall, 0.75 m
    away; by travel the retreat is through the door (y 1.0-1.5 m), east of the wall, at
    the travel the brute force finds, more than 1.5 m."""
    occ = _plan()
    cm = _cm(occ)
    away = np.array([[x, y] for x in (1.0, 2.5) for y in (0.5, 1.5, 2.5)])
    start = np.array([2.875, 2.375])
    p = retreat_point(cm, start, away, 1.0)
    best, dist = _brute_retreat(occ, (2, 11), away, 1.0, 8.0)
    rc = cm.cell_of(p[None])[0]
    assert dist[rc[0], rc[1]] == pytest.approx(best)
    assert p[0] > 3.25
    assert best > 1.5
    assert np.hypot(away[:, 0] - p[0], away[:, 1] - p[1]).min() >= 1.0


def test_retreat_point_with_nothing_to_avoid_stays_put() -> None:
    """No hot place: the robot's own cell (travel 0)."""
    cm = _cm(_plan())
    p = retreat_point(cm, np.array([1.125, 1.125]), np.zeros((0, 2)), 1.0)
    assert p.tolist() == [1.125, 1.125]


def test_retreat_point_is_nan_when_no_clear_cell_is_in_reach() -> None:
    """Every cell within the limit is hot: NaN, not a point inside the heat. A hot place
    at the robot with clear_m 3 m and a limit of 1 m; and a plan with no standable cell."""
    cm = _cm(_plan())
    start = np.array([1.125, 1.125])
    assert np.isnan(retreat_point(cm, start, start[None], 3.0, limit_m=1.0)).all()
    walls = np.ones((6, 6), dtype=bool)
    cm0 = coarse_map(build_costmap(OccupancyGrid(walls, ~walls, resolution_m=CELL_M), 0.1), CELL_M)
    assert np.isnan(retreat_point(cm0, np.array([0.5, 0.5]), np.zeros((0, 2)), 1.0)).all()


def test_retreat_point_with_a_small_reach_cache_agrees_with_brute_force(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The reach of each start cell is kept in the map's cache (at most ``_REACH_KEPT``
    cells); with room for three, 40 random starts (most evicted, some asked again) still
    give the brute force's travel, and the cache never holds more than three."""
    import firefleet.control.mission._hot as hot

    monkeypatch.setattr(hot, "_REACH_KEPT", 3)
    occ = _plan()
    cm = _cm(occ)
    h = occ.shape[0]
    free_rc = np.argwhere(~occ)
    rng = np.random.default_rng(7)
    away = np.array([[1.0, 1.5], [4.5, 2.0]])
    picks = free_rc[rng.integers(len(free_rc), size=20)]
    for r0, c0 in np.concatenate([picks, picks[::-1]]):
        start = np.array(_centre(int(r0), int(c0), h))
        best, dist = _brute_retreat(occ, (int(r0), int(c0)), away, 1.0, 8.0)
        p = retreat_point(cm, start, away, 1.0)
        rc = cm.cell_of(p[None])[0]
        assert dist[rc[0], rc[1]] == pytest.approx(best, abs=1e-9)
        kept = cm.cache[("reach", 8.0)]
        assert isinstance(kept, dict)
        assert len(kept) <= 3
