"""The fighters' aim (``_water.front_aim``) against a brute-force sweep of the cone."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.control.mission._coverage import CoarseMap, coarse_map
from firefleet.control.mission._water import cone_cells, front_aim
from firefleet.control.navigation import build_costmap
from firefleet.world import OccupancyGrid

RES_M = 0.05
WALL_Y_M = (2.0, 2.25)  # a wall across the plan; the room north of it
DOOR_X_M = (2.5, 3.0)
REACH_M, HALF_RAD, FRONT_M = 3.5, math.radians(15.0), 1.0


def _door_plan() -> CoarseMap:
    """8 m x 5 m: a 0.25 m wall at y 2.0-2.25 m with a 0.5 m door at x 2.5-3.0 m."""
    h, w = 100, 160
    occ = np.zeros((h, w), dtype=bool)
    rows = slice(h - round(WALL_Y_M[1] / RES_M), h - round(WALL_Y_M[0] / RES_M))
    occ[rows, :] = True
    occ[rows, round(DOOR_X_M[0] / RES_M) : round(DOOR_X_M[1] / RES_M)] = False
    grid = OccupancyGrid(occ, ~occ, resolution_m=RES_M)
    return coarse_map(build_costmap(grid, 0.1), 0.25)


def _cone_score(
    cm: CoarseMap, pose_xy: np.ndarray, bearing: float, flames: np.ndarray
) -> tuple[int, int, int]:
    """(flames whose front the cone holds, front cells, front cells in the room) of the
    cone the world's nozzle model wets (``cone_cells``) at ``bearing``."""
    rows, cols = cone_cells(cm, np.array([*pose_xy, bearing]), REACH_M, HALF_RAD)
    xy = cm.centre_xy(np.stack([rows, cols], axis=-1))
    near = np.hypot(xy[:, None, 0] - flames[None, :, 0], xy[:, None, 1] - flames[None, :, 1])
    near = near <= FRONT_M
    front = near.any(axis=1) & (np.hypot(*(xy - pose_xy).T) >= cm.cell_m)
    room = front & (xy[:, 1] > WALL_Y_M[1])
    return int(near[front].any(axis=0).sum()), int(front.sum()), int(room.sum())


FLAMES_A = ((3.4, 2.6), (3.6, 3.4), (4.6, 1.5))
FLAMES_B = ((3.4, 2.5), (3.0, 3.2), (4.5, 1.5))


def _front_bearings(cm: CoarseMap, pose_xy: np.ndarray, flames: np.ndarray) -> np.ndarray:
    """Bearings [rad] of the front cells in reach and in sight (the cones the aim weighs
    are centred on them), from the nozzle model's cells all round (``cone_cells``)."""
    rows, cols = cone_cells(cm, np.array([*pose_xy, 0.0]), REACH_M, math.pi)
    xy = cm.centre_xy(np.stack([rows, cols], axis=-1))
    d = np.hypot(xy[:, None, 0] - flames[None, :, 0], xy[:, None, 1] - flames[None, :, 1])
    front = (d <= FRONT_M).any(axis=1) & (np.hypot(*(xy - pose_xy).T) >= cm.cell_m)
    out: np.ndarray = np.arctan2(xy[front, 1] - pose_xy[1], xy[front, 0] - pose_xy[0])
    return out


@pytest.mark.parametrize(
    ("robot", "flames"),
    [
        ((1.8, 0.9), FLAMES_A),
        ((2.2, 0.8), FLAMES_A),
        ((1.8, 0.9), FLAMES_B),
        ((2.2, 0.8), FLAMES_B),
    ],
)
def test_the_aim_is_the_best_cone_on_a_front_cells_bearing(
    robot: tuple[float, float], flames: tuple[tuple[float, float], ...]
) -> None:
    # brute force: the cone of the nozzle model on every front cell's bearing
    cm = _door_plan()
    pose = np.array([*robot, 0.0])
    f = np.array(flames)
    aim = front_aim(np.zeros((0, 0)), cm, pose, f, REACH_M, HALF_RAD, 1.3, FRONT_M)
    assert aim is not None
    got = _cone_score(cm, pose[:2], math.atan2(aim[1] - robot[1], aim[0] - robot[0]), f)
    sweep = [_cone_score(cm, pose[:2], float(b), f)[:2] for b in _front_bearings(cm, pose[:2], f)]
    assert len(sweep) > 30
    assert got[:2] == max(sweep)


@pytest.mark.parametrize(("robot", "flames"), [((1.8, 0.9), FLAMES_A), ((2.2, 0.8), FLAMES_B)])
def test_the_aim_goes_through_the_door_to_the_flames_behind_the_wall(
    robot: tuple[float, float], flames: tuple[tuple[float, float], ...]
) -> None:
    # two flames behind the wall east of the door and deeper in the room; a third placed
    # short, in the corridor (where a camera's range fell)
    cm = _door_plan()
    pose = np.array([*robot, 0.0])
    f = np.array(flames)
    aim = front_aim(np.zeros((0, 0)), cm, pose, f, REACH_M, HALF_RAD, 1.3, FRONT_M)
    assert aim is not None
    bearing = math.atan2(aim[1] - robot[1], aim[0] - robot[0])
    served, cells, room = _cone_score(cm, pose[:2], bearing, f)
    # brute force over bearings every 0.1 deg: no cone holds more flames' fronts
    sweep = [_cone_score(cm, pose[:2], math.radians(a), f) for a in np.arange(0.0, 360.0, 0.1)]
    assert served == max(s[0] for s in sweep) == 3
    # the jet goes through the door: room cells by the flames behind the wall
    assert room >= 5
    # the line to the aim meets the wall's south face within 0.6 m of the door
    x_wall = robot[0] + (WALL_Y_M[0] - robot[1]) / math.tan(bearing)
    assert DOOR_X_M[0] - 0.6 <= x_wall <= DOOR_X_M[1] + 0.6
    # the cone with the most front cells (the rule before) looked down the corridor, into
    # no room cell: the test tells the rules apart
    most = max(sweep, key=lambda s: s[1])
    assert most[2] == 0
    assert most[1] > 2 * cells


def test_no_flame_in_reach_gives_no_aim() -> None:
    cm = _door_plan()
    pose = np.array([1.0, 1.0, 0.0])
    far = np.array([[7.5, 4.5]])  # 7.3 m off, past reach + front
    assert front_aim(np.zeros((0, 0)), cm, pose, far, REACH_M, HALF_RAD, 1.3, FRONT_M) is None
    none = np.zeros((0, 2))
    assert front_aim(np.zeros((0, 0)), cm, pose, none, REACH_M, HALF_RAD, 1.3, FRONT_M) is None


def test_soaked_cells_are_no_front() -> None:
    cm = _door_plan()
    pose = np.array([1.0, 1.0, 0.0])
    flame = np.array([[2.5, 1.0]])  # in the corridor, 1.5 m east
    dry = front_aim(np.zeros((0, 0)), cm, pose, flame, REACH_M, HALF_RAD, 1.3, FRONT_M)
    assert dry is not None
    assert abs(math.atan2(dry[1] - 1.0, dry[0] - 1.0)) < HALF_RAD
    wet = np.full(cm.shape, 2.0)  # every cell soaked: nothing left to wet
    assert front_aim(wet, cm, pose, flame, REACH_M, HALF_RAD, 1.3, FRONT_M) is None
