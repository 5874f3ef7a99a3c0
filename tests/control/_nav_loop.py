"""A small self-contained closed loop for the navigation tests.

Unicycle kinematics (exact arcs, :func:`firefleet.models.unicycle_step`) driven by the
team controller's commands, a 360-degree lidar ray-marched on the grid (other robots
are obstacles to it) and the exact disc-overlap check the metrics need.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from firefleet.control.navigation import (
    NavigationInputs,
    NavigationParams,
    NavigationState,
    navigation_init,
    navigation_step,
)
from firefleet.models import unicycle_step
from firefleet.world import OccupancyGrid


def lidar(
    grid: OccupancyGrid,
    pose: np.ndarray,
    radius_m: float,
    beams: int = 72,
    max_range_m: float = 4.0,
    step_m: float = 0.02,
) -> tuple[np.ndarray, np.ndarray]:
    """Ranges (N, B) with inf for no return, bearings (B,): first sample in a wall or
    in another robot's disc along each beam."""
    n = pose.shape[0]
    bearings = np.linspace(-np.pi, np.pi, beams, endpoint=False)
    dist = np.arange(1, int(max_range_m / step_m) + 1) * step_m  # (S,)
    ang = pose[:, 2:3] + bearings[None]  # (N, B)
    x = pose[:, 0, None, None] + dist[None, None] * np.cos(ang)[..., None]  # (N, B, S)
    y = pose[:, 1, None, None] + dist[None, None] * np.sin(ang)[..., None]
    hit = grid.occupied_at(np.stack([x, y], axis=-1))
    for j in range(n):
        inside = np.hypot(x - pose[j, 0], y - pose[j, 1]) <= radius_m
        inside[j] = False
        hit |= inside
    first = np.where(hit.any(axis=-1), hit.argmax(axis=-1), -1)
    ranges = np.where(first >= 0, dist[np.maximum(first, 0)], np.inf)
    return ranges, bearings


def wall_distance(grid: OccupancyGrid, xy: np.ndarray) -> np.ndarray:
    """Exact distance (N,) from each point to the nearest occupied cell's square [m]."""
    cells = np.argwhere(grid.occupied)
    centres = grid.center_of(cells)
    half = grid.resolution_m / 2.0
    dx = np.maximum(np.abs(xy[:, None, 0] - centres[None, :, 0]) - half, 0.0)
    dy = np.maximum(np.abs(xy[:, None, 1] - centres[None, :, 1]) - half, 0.0)
    return np.asarray(np.hypot(dx, dy).min(axis=1))


@dataclass
class Run:
    """What a closed-loop run did."""

    poses: np.ndarray  # (T + 1, N, 3)
    commands: np.ndarray  # (T, N, 2)
    state: NavigationState
    min_wall_clearance_m: np.ndarray  # (N,): distance to walls minus the radius
    min_robot_clearance_m: float  # least gap between two discs
    arrival_s: np.ndarray  # (N,), nan if never


def run(
    grid: OccupancyGrid,
    poses: np.ndarray,
    goals: np.ndarray,
    params: NavigationParams,
    duration_s: float,
    dt_s: float = 0.1,
) -> Run:
    pose = np.array(poses, dtype=float)
    n = pose.shape[0]
    state = navigation_init(grid, pose, goals, params)
    r = params.robot_radius_m
    history = [pose.copy()]
    commands = []
    wall = np.full(n, np.inf)
    robot = np.inf
    arrival = np.full(n, np.nan)
    steps = round(duration_s / dt_s)
    for k in range(steps):
        t = k * dt_s
        ranges, bearings = lidar(grid, pose, r)
        inputs = NavigationInputs(pose.copy(), {"lidar": (ranges, bearings)}, pose[:, :2].copy(), t)
        state, v, w = navigation_step(state, inputs, params, dt_s)
        commands.append(np.stack([v, w], axis=1))
        pose = unicycle_step(pose, v, w, dt_s)
        history.append(pose.copy())
        wall = np.minimum(wall, wall_distance(grid, pose[:, :2]) - r)
        if n > 1:
            d = np.hypot(*(pose[:, None, :2] - pose[None, :, :2]).transpose(2, 0, 1))
            d[np.arange(n), np.arange(n)] = np.inf
            robot = min(robot, float(d.min()) - 2.0 * r)
        newly = state.arrived & np.isnan(arrival)
        arrival[newly] = t + dt_s
        if state.arrived.all():
            break
    return Run(np.array(history), np.array(commands), state, wall, robot, arrival)


def doorway_map(resolution_m: float = 0.05, door_m: float = 0.9) -> OccupancyGrid:
    """8 m x 4 m, walled, a wall across x = 4 m with one door centred on y = 2 m."""
    h, w = round(4.0 / resolution_m), round(8.0 / resolution_m)
    occ = np.zeros((h, w), dtype=bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    wall = round(4.0 / resolution_m)
    occ[:, wall - 1 : wall + 1] = True
    half = round(door_m / 2.0 / resolution_m)
    mid = h // 2
    occ[mid - half : mid + half, wall - 1 : wall + 1] = False
    return OccupancyGrid(occ, ~occ, resolution_m, name="doorway")
