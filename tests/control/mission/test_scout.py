"""Looking for the fire the team does not see (``control.mission._scout``) against
independent references: the camera's cone by geometry (bounds a cell wide), a
breadth-first search for the fire's region, and every cell tried for the scout's goal
(a Dijkstra and a line of sight of the test's own)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.control.mission._coverage import CoarseMap, coarse_map
from firefleet.control.mission._scout import fire_region, scout_goals, seen_update
from firefleet.control.navigation import build_costmap
from firefleet.world import OccupancyGrid
from tests._dijkstra import grid_dijkstra

CELL_M = 0.25
HFOV = math.radians(51.0)


def _cm(occ: np.ndarray) -> CoarseMap:
    """The coarse map of a plan drawn at the coarse cell itself (factor 1: coarse cells
    are the plan's cells; the inflation 0.1 m is under a cell, so standable = free)."""
    cm = coarse_map(build_costmap(OccupancyGrid(occ, ~occ, resolution_m=CELL_M), 0.1), CELL_M)
    assert cm.factor == 1
    assert (cm.standable == ~occ).all()
    return cm


def _centres(shape: tuple[int, int]) -> np.ndarray:
    """Cell centres [m] (H, W, 2), row 0 at the top."""
    h, w = shape
    r, c = np.mgrid[:h, :w]
    return np.stack([(c + 0.5) * CELL_M, (h - r - 0.5) * CELL_M], axis=-1)


def _room(h: int = 24, w: int = 40) -> np.ndarray:
    occ = np.zeros((h, w), dtype=bool)
    occ[0] = occ[-1] = True
    occ[:, 0] = occ[:, -1] = True
    return occ


# ------------------------------------------------------------------------- seen_update


def test_seen_update_marks_the_cone_to_within_a_cell_of_its_border() -> None:
    """A robot at (3, 3) facing +x in an open 10 m x 6 m room, range 3 m: every cell
    whose centre lies 0.25-2.75 m away and inside the cone by twice the angle of half a
    cell (the cone narrowed by half a cell, then a sample within the cell's half
    diagonal of its centre) is marked at the time; no cell whose centre lies beyond
    3.18 m (range + a cell's half diagonal) or off the cone by more than the angle of
    half a cell."""
    occ = _room()
    cm = _cm(occ)
    pose = np.array([[3.0, 3.0, 0.0]])
    s = seen_update(np.zeros((0, 0)), cm, pose, 7.0, 3.0, HFOV)
    assert s.shape == cm.shape
    assert set(np.unique(s).tolist()) == {7.0, -math.inf}
    xy = _centres(cm.shape)
    d = np.hypot(xy[..., 0] - 3.0, xy[..., 1] - 3.0)
    off = np.abs(np.arctan2(xy[..., 1] - 3.0, xy[..., 0] - 3.0))
    slack = np.arctan2(0.5 * CELL_M, np.maximum(d, 1e-9))
    inside = (d >= CELL_M) & (d <= 3.0 - CELL_M) & (off <= HFOV / 2 - 2 * slack)
    outside = (d > 3.0 + CELL_M * math.sqrt(0.5)) | (off > HFOV / 2 + slack)
    assert inside.sum() >= 30  # the premise: a cone of many cells (4 m^2: 64 cells in all)
    assert (s[inside] == 7.0).all()
    assert (s[outside] == -math.inf).all()


def test_seen_update_keeps_earlier_times_and_stops_at_a_wall() -> None:
    """A wall across the view at x = 4.5-4.75 m: cells beyond it (x > 5 m) are not seen,
    the wall's face is. A second look at 9 s facing -x: its cells take 9 s, the cells
    only the first look saw keep 7 s; an empty team changes nothing (a new array)."""
    occ = _room()
    occ[1:-1, 18] = True  # x 4.5-4.75 m
    cm = _cm(occ)
    s7 = seen_update(np.zeros((0, 0)), cm, np.array([[3.0, 3.0, 0.0]]), 7.0, 3.0, HFOV)
    xy = _centres(cm.shape)
    beyond = xy[..., 0] > 5.0
    assert (s7[beyond] == -math.inf).all()
    assert s7[cm.cell_of(np.array([4.6, 3.0]))[0], cm.cell_of(np.array([4.6, 3.0]))[1]] == 7.0
    s9 = seen_update(s7, cm, np.array([[3.0, 3.0, math.pi]]), 9.0, 3.0, HFOV)
    assert s7.max() == 7.0  # the input is not changed
    east = xy[..., 0] > 3.5
    west = xy[..., 0] < 2.5
    assert (s9[east] == s7[east]).all()
    assert (s9[west & (s9 > -math.inf)] == 9.0).all()
    assert (s9[west] == 9.0).sum() > 30
    same = seen_update(s9, cm, np.zeros((0, 3)), 11.0, 3.0, HFOV)
    assert same is not s9
    assert (same == s9).all()


# ------------------------------------------------------------------------- fire_region


def _bfs_band(cm: CoarseMap, spots: np.ndarray, k_max: int) -> np.ndarray:
    """8-neighbour breadth-first steps from the spots' cells through floor that is not
    opaque, up to ``k_max`` (-1 beyond): the test's own."""
    h, w = cm.shape
    band = np.full((h, w), -1)
    frontier = []
    for r, c in cm.cell_of(spots).tolist():
        if band[r, c] < 0:
            band[r, c] = 0
            frontier.append((r, c))
    for k in range(1, k_max + 1):
        nxt = []
        for r, c in frontier:
            for dr in (-1, 0, 1):
                for dc in (-1, 0, 1):
                    rr, cc = r + dr, c + dc
                    if not (0 <= rr < h and 0 <= cc < w) or band[rr, cc] >= 0:
                        continue
                    if cm.floor[rr, cc] and not cm.opaque[rr, cc]:
                        band[rr, cc] = k
                        nxt.append((rr, cc))
        frontier = nxt
    return band


def _two_rooms() -> np.ndarray:
    """10 m x 6 m, a wall at x 5.0-5.25 m with a 0.75 m door at y 2.0-2.75 m."""
    occ = _room()
    occ[1:-1, 20] = True
    occ[13:16, 20] = False  # rows 13-15: y 2.0-2.75 m
    return occ


def test_fire_region_is_the_breadth_first_band_through_the_floor() -> None:
    """Random spots and radii on the two rooms: the bands equal a breadth-first search
    of the test's own, cell for cell; the region leaks to the other room only through
    the door."""
    cm = _cm(_two_rooms())
    rng = np.random.default_rng(3)
    leaked = 0
    for _ in range(25):
        spots = rng.uniform([0.3, 0.3], [9.7, 5.7], size=(int(rng.integers(1, 4)), 2))
        scout_m = float(rng.uniform(0.5, 4.0))
        band = fire_region(cm, spots, scout_m)
        ref = _bfs_band(cm, spots, max(1, round(scout_m / CELL_M)))
        assert (band == ref).all()
        west = spots[:, 0] < 5.0
        if west.all() and (band[:, 21:] >= 0).any():
            leaked += 1
            # a west fire reaches the east room through the door's cells only
            assert (band[13:16, 21] >= 0).any()
    assert leaked >= 1
    assert (fire_region(cm, np.zeros((0, 2)), 2.0) == -1).all()


# ------------------------------------------------------------------------- scout_goals


def _dijkstra(free: np.ndarray, start: tuple[int, int]) -> np.ndarray:
    return grid_dijkstra(free, start, CELL_M)


def _sight(occ: np.ndarray, a: np.ndarray, b: np.ndarray) -> bool:
    """No occupied cell on the segment a-b (sampled every 1 cm), the ends' cells excepted."""
    h = occ.shape[0]
    n = max(2, math.ceil(math.hypot(*(b - a)) / 0.01) + 1)
    pts = a + np.linspace(0.0, 1.0, n)[:, None] * (b - a)
    rc = np.stack([h - 1 - np.floor(pts[:, 1] / CELL_M), np.floor(pts[:, 0] / CELL_M)], -1)
    rc = rc.astype(int)
    ra = (h - 1 - int(a[1] // CELL_M), int(a[0] // CELL_M))
    rb = (h - 1 - int(b[1] // CELL_M), int(b[0] // CELL_M))
    return all(not ((r, c) not in (ra, rb) and occ[r, c]) for r, c in rc.tolist())


def _brute_goal(
    occ: np.ndarray,
    robot_rc: tuple[int, int],
    look_rc: tuple[int, int],
    avoid: np.ndarray,
    near_m: float,
    far_m: float,
) -> tuple[float, np.ndarray]:
    """Least travel from the robot to a free cell not avoided, near_m to far_m from the
    looked-at cell's centre, in sight of it; and the travel of every cell."""
    dist = _dijkstra(~occ, robot_rc)
    xy = _centres(occ.shape)
    target = xy[look_rc]
    best = math.inf
    for r, c in np.argwhere(~occ & ~avoid):
        d = math.hypot(*(xy[r, c] - target))
        if near_m <= d <= far_m and dist[r, c] < best and _sight(occ, xy[r, c], target):
            best = float(dist[r, c])
    return best, dist


@pytest.mark.parametrize(
    ("look_xy", "spot_xy"), [((7.125, 4.625), (7.0, 3.5)), ((2.125, 1.125), (2.0, 2.0))]
)
def test_a_scout_goes_to_the_nearest_place_in_sight_of_the_one_stale_cell(
    look_xy: tuple[float, float], spot_xy: tuple[float, float]
) -> None:
    """The two rooms, a fire's spot, every cell seen at 100 s but one near it: at 120 s
    with ``stale_s`` 30 s the robot in the west room looks at that cell from the
    standable cell 1.25-2.5 m from it, in sight, nearest by travel (every cell tried with
    the test's own Dijkstra and line of sight). Then the 5 x 5 cells about that goal
    avoided: the goal is outside them, and again the nearest such by travel."""
    occ = _two_rooms()
    cm = _cm(occ)
    look = cm.cell_of(np.array(look_xy))
    seen = np.full(cm.shape, 100.0)
    seen[look[0], look[1]] = 0.0
    spot = np.array([spot_xy])
    robot = np.array([[1.125, 4.625]])
    robot_rc = tuple(cm.cell_of(robot[0]))
    avoid = np.zeros(cm.shape, dtype=bool)
    for _ in range(2):
        goal = scout_goals(cm, seen, 120.0, spot, robot, avoid, 4.0, 30.0, 1.25, 2.5)
        assert goal.shape == (1, 2)
        assert np.isfinite(goal).all()
        best, dist = _brute_goal(occ, robot_rc, tuple(look), avoid, 1.25, 2.5)
        rc = cm.cell_of(goal[0])
        assert not avoid[rc[0], rc[1]]
        assert dist[rc[0], rc[1]] == pytest.approx(best)
        d = math.hypot(*(goal[0] - _centres(cm.shape)[look[0], look[1]]))
        assert 1.25 <= d <= 2.5
        avoid[rc[0] - 2 : rc[0] + 3, rc[1] - 2 : rc[1] + 3] = True
    # the cell seen again within stale_s: nothing to look at
    seen[look[0], look[1]] = 91.0
    assert np.isnan(scout_goals(cm, seen, 120.0, spot, robot, avoid, 4.0, 30.0, 1.25, 2.5)).all()


def test_scouts_split_over_stale_floor_and_ignore_floor_outside_the_fires_region() -> None:
    """Two stale patches of the east room 4 m apart (farther than far_m): two robots look
    at different ones; with one small patch the second robot has nothing left (NaN).
    Stale floor in the west room, farther than scout_m from the spot through the door,
    is not the fire's: no goal."""
    occ = _two_rooms()
    cm = _cm(occ)
    spot = np.array([[7.5, 3.0]])
    robots = np.array([[1.125, 4.625], [1.125, 1.125]])
    avoid = np.zeros(cm.shape, dtype=bool)
    seen = np.full(cm.shape, 100.0)
    a, b = cm.cell_of(np.array([[5.625, 5.375], [9.375, 1.125]]))
    seen[a[0] - 1 : a[0] + 1, a[1] : a[1] + 2] = 0.0
    seen[b[0] - 1 : b[0] + 1, b[1] - 1 : b[1] + 1] = 0.0
    goal = scout_goals(cm, seen, 120.0, spot, robots, avoid, 4.0, 30.0, 1.25, 2.5)
    assert np.isfinite(goal).all()
    xy = _centres(cm.shape)
    patches = [xy[seen == 0.0][:4], xy[seen == 0.0][4:]]
    near_patch = [int(np.argmin([np.hypot(*(p - g).T).min() for p in patches])) for g in goal]
    assert sorted(near_patch) == [0, 1]
    one = np.full(cm.shape, 100.0)
    one[b[0], b[1]] = 0.0
    g1 = scout_goals(cm, one, 120.0, spot, robots, avoid, 4.0, 30.0, 1.25, 2.5)
    assert np.isfinite(g1[0]).all()
    assert np.isnan(g1[1]).all()
    west = np.full(cm.shape, 100.0)
    west[4:8, 2:6] = 0.0  # x 0.5-1.5 m: more than 4 m from the spot by any way
    assert np.isnan(scout_goals(cm, west, 120.0, spot, robots, avoid, 4.0, 30.0, 1.25, 2.5)).all()
    # never seen at all (another shape): the floor about the spot is stale
    g0 = scout_goals(cm, np.zeros((0, 0)), 5.0, spot, robots[:1], avoid, 4.0, 30.0, 1.25, 2.5)
    assert np.isfinite(g0).all()
