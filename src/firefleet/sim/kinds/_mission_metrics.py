"""The mission's metrics (:func:`mission_metrics`, issue 15, item 6) and the collision
tests on recorded poses they fall back on."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from firefleet._typing import FloatArray
from firefleet.scenarios.schema import Scenario
from firefleet.sim.kinds._mission_contacts import touched_walls
from firefleet.sim.kinds._mission_smoke import stereo_team_metrics
from firefleet.sim.registry import Metrics
from firefleet.sim.result import SimResult
from firefleet.world import BURNING, UNBURNT, OccupancyGrid

__all__ = ["baseline_burned_area_m2", "mission_metrics"]


def baseline_burned_area_m2(scenario: Scenario) -> float:
    """Burned area [m^2] of the same world without the team at ``duration_s`` (the same
    seed: the fire draws from its own generator, so the two runs burn alike until the
    team's water changes them)."""
    return _baseline(scenario)[0]


def _baseline(scenario: Scenario) -> tuple[float, float]:
    """The world without the team to ``duration_s``: its burned area [m^2] and when
    every fire in it was out [s] (NaN: some still burned at the end)."""
    from firefleet.sim.kinds.mission import mission_world

    world = mission_world(scenario)
    state = world.init(scenario.n_robots)
    t = 0.0
    while t <= scenario.duration_s + 1e-9:
        state = world.step(state, t)
        t = state.next_s
    area = world.field.resolution_m**2
    burned = float(np.count_nonzero(state.fire.state != UNBURNT) * area)
    return burned, float(state.log["all_out_s"])


def _component_burning(fire_state: np.ndarray, cell: tuple[int, int]) -> bool:
    """Whether the burned region (burning or burnt cells, 8-connected) holding ``cell``
    still burns."""
    import scipy.ndimage as ndi

    labels, _ = ndi.label(fire_state != UNBURNT, structure=np.ones((3, 3)))
    lab = labels[cell]
    return bool(lab and np.any((labels == lab) & (fire_state == BURNING)))


def _touches_wall(grid: OccupancyGrid, xy_m: FloatArray, radius_m: float) -> np.ndarray:
    """Whether each robot's disc ever overlapped an occupied cell (or the map's edge),
    shape (N,) from positions (T, N, 2) [m].

    The exact clearance (``clearance_m``, a Python loop over points) is computed only
    where a lower bound allows a touch: a point in a cell whose centre lies ``e`` cells
    from the nearest occupied centre is at least ``(e - sqrt 2) * resolution`` from any
    occupied square. A 50-robot run of 20 minutes at 100 Hz has 6 million points; the
    bound leaves those near walls.
    """
    import scipy.ndimage as ndi

    from firefleet.sim.kinds._navigate_metrics import clearance_m

    h, w = grid.shape
    edt = ndi.distance_transform_edt(~np.pad(grid.occupied, 1, constant_values=True))[1:-1, 1:-1]
    rc = grid.cell_of(xy_m)
    inside = grid.contains(xy_m)
    bound = np.where(
        inside,
        (edt[np.clip(rc[..., 0], 0, h - 1), np.clip(rc[..., 1], 0, w - 1)] - math.sqrt(2.0))
        * grid.resolution_m,
        -1.0,
    )
    near = bound < radius_m + 1e-9
    touch = np.zeros(xy_m.shape[1], dtype=bool)
    if near.any():
        t_idx, robot = np.nonzero(near)
        clear = clearance_m(grid, xy_m[t_idx, robot])
        np.logical_or.at(touch, robot, clear < radius_m)
    return touch


def _touching(grid: OccupancyGrid, xy_m: FloatArray, radius_m: float) -> np.ndarray:
    """Whether each robot (discs of ``radius_m``, positions (T, N, 2) [m]) ever touched a
    wall or another robot, shape (N,); robot pairs one robot at a time, (T, N) arrays and
    not (T, N, N) (50 robots over 120,000 ticks: 2.4 GB)."""
    touch = _touches_wall(grid, xy_m, radius_m)
    for i in range(xy_m.shape[1]):
        d = np.hypot(xy_m[:, :, 0] - xy_m[:, i : i + 1, 0], xy_m[:, :, 1] - xy_m[:, i : i + 1, 1])
        d[:, i] = np.inf
        touch[i] |= bool((d < 2 * radius_m).any())
    return touch


def mission_metrics(result: SimResult) -> Metrics:
    """Metrics of a mission run (issue 15, item 6; module notes).

    ``fires_detected``: fires (of ``world.fires``) with a thermal fire detection within
    2 m of their burned region; ``first_detection_s``: the first fire detection;
    ``fires_extinguished``: started fires whose burned region burns no more at the end;
    ``all_out_s``: when every fire had started and none burned (None if never);
    ``burned_area_m2`` (cells that burned) and ``baseline_burned_area_m2`` (the same
    world without the team) and their ratio ``burned_vs_baseline`` (NaN when the
    baseline burns nothing); ``baseline_all_out_s``: when every fire of the baseline
    was out (None if it burned on to the end: the fire the team put out, or held to a
    room until its fuel was spent, would not have gone out without it);
    ``victims_found`` and ``victims_found_s`` (a victim is found when the team confirms
    a person detection within 2 m of it); ``victims_alive`` (fractional effective dose
    below 1); ``explored_pct`` (free map cells a thermal camera covered);
    ``collisions`` (robots that touched a wall or another robot); ``robots_damaged``;
    ``water_used_l`` per robot.
    """
    from firefleet.sim.kinds.mission import _command, _grid, mission_world

    scenario = result.scenario
    cmd = _command(scenario)
    world = mission_world(scenario)
    x = result.extra
    fire_state = np.asarray(x["fire_state"])
    final = fire_state[-1]
    area = world.field.resolution_m**2
    det: Any = x["detections"]  # structured (DETECTION_DTYPE)
    fire_det = det[det["kind"] == "fire"]
    burned_xy = [
        world.field.center_of(np.argwhere(final != UNBURNT)),
    ][0]
    detected = 0
    started = np.asarray(x["fire_started"]) > 0.5
    extinguished = 0
    import scipy.ndimage as ndi
    from scipy.spatial import cKDTree

    labels, _ = ndi.label(final != UNBURNT, structure=np.ones((3, 3)))
    for i, cell in enumerate(world.fire_cells):
        lab = labels[tuple(cell)]
        region = world.field.center_of(np.argwhere(labels == lab)) if lab else burned_xy[:0]
        if len(fire_det) and len(region):
            # nearest region cell per detection by a k-d tree: (K, R) distances would be
            # gigabytes at 50 robots (1e5 fire detections x 1e3 burned cells)
            near, _ = cKDTree(region).query(np.c_[fire_det["x_m"], fire_det["y_m"]])
            if np.min(near) <= 2.0:
                detected += 1
        if started[i] and not _component_burning(final, (int(cell[0]), int(cell[1]))):
            extinguished += 1
    found_s = np.asarray(x["victims_found_s"])
    all_out = float(np.asarray(x["all_out_s"])[0])
    collided = 0
    if cmd.robots and "touched_robot" in x:  # noted at every tick (_mission_contacts)
        n = result.pose.shape[1]
        wall = touched_walls(_grid(scenario), x["near_wall_xy_m"], n, cmd.robot_radius_m)
        collided = int((wall | (np.asarray(x["touched_robot"]) > 0.5)).sum())
    elif cmd.robots:  # a result without them: the recorded poses
        collided = int(_touching(_grid(scenario), result.pose[:, :, :2], cmd.robot_radius_m).sum())
    burned = float(np.count_nonzero(final != UNBURNT) * area)
    baseline, baseline_out = _baseline(scenario)
    return {
        "fires_detected": float(detected),
        "first_detection_s": float(fire_det["t_s"].min()) if len(fire_det) else math.nan,
        "fires_extinguished": float(extinguished),
        "all_out_s": all_out,  # NaN (null in metrics.json): not all out
        "burned_area_m2": burned,
        "baseline_burned_area_m2": baseline,
        "burned_vs_baseline": burned / baseline if baseline > 0.0 else math.nan,
        "baseline_all_out_s": baseline_out,  # NaN (null): the fire without the team burns on
        "victims_found": float(np.count_nonzero(np.isfinite(found_s))),
        "victims_found_s": [float(v) for v in found_s],  # NaN: not found
        "victims_alive": float(np.count_nonzero(np.asarray(x["victim_dose"]) < 1.0)),
        "explored_pct": float(np.asarray(x["explored_pct"])[0]),
        "collisions": float(collided),
        "robots_damaged": float(np.count_nonzero(np.asarray(x["damaged"]) > 0.5)),
        "water_used_l": [float(v) for v in np.asarray(x["water_used_l"])],
        **stereo_team_metrics(scenario, mission_metrics),  # NaN unless command.stereo_team
    }
