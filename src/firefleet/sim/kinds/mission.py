"""The firefighting mission (issue 15): a team that explores a burning building, finds
the fires and the people in it with its thermal cameras, and puts the fires out.

On the world loop (:mod:`firefleet.sim.loop`) with the kind's own stages::

    world        fire, heat, smoke, victims and water on the field grid (every
                 ``world_step_s``), damage, tanks; the run's log   (_mission_world)
    sensors      range sensors on the map, the air at each robot, thermal frames at
                 ``sensors.thermal.rate_hz`` read by perception.thermal.detect
    link         ideal: every robot's detections and assignment reach the team at the
                 next tick (the tactics' shared knowledge counts the messages)
    estimation   odometry (dead reckoning of the encoders)
    decide       detections placed on the map by each robot's pose estimate ->
                 control.mission.tactics_step (exploration, allocation, the ring
                 around a fire, spray, refill) -> (v, omega) -> wheel references;
                 spray and refill go to the world as actions
    drive        the wheel stack

``command.robots: false`` runs the same world (the same seed: the fire draws from its
own generator) without the team: the baseline of ``baseline_burned_area_m2``, which
every run computes alongside.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.models.kinematics import body_to_wheels
from firefleet.scenarios._mission import Mission
from firefleet.scenarios.schema import Scenario
from firefleet.sim.kinds._mission_smoke import STEREO_METRIC_NAMES, stereo_team_metrics
from firefleet.sim.kinds._mission_world import (
    FIRE,
    PERSON,
    MissionSensors,
    MissionWorld,
    nearest_open,
)
from firefleet.sim.loop import (
    DecideInputs,
    Decider,
    Odometry,
    Stages,
    WheelCommand,
    default_stages,
)
from firefleet.sim.registry import Metrics, TaskKind
from firefleet.sim.result import SimResult
from firefleet.world import BURNING, UNBURNT, OccupancyGrid, coarsen

__all__ = ["KINDS", "METRIC_NAMES", "mission_decide", "mission_metrics", "mission_world"]

METRIC_NAMES = (
    "fires_detected",
    "first_detection_s",
    "fires_extinguished",
    "all_out_s",
    "burned_area_m2",
    "baseline_burned_area_m2",
    "burned_vs_baseline",
    "victims_found",
    "victims_found_s",
    "victims_alive",
    "explored_pct",
    "collisions",
    "robots_damaged",
    "water_used_l",
    *STEREO_METRIC_NAMES,
)

REFILL_L_S = 2.0
"""Refill rate at the refill point [L/s] (a hose at the entrance)."""


def _command(scenario: Scenario) -> Mission:
    cmd = scenario.command
    if not isinstance(cmd, Mission):
        raise InputError(f"command.kind: expected mission, got {cmd.kind!r}")
    return cmd


def _grid(scenario: Scenario) -> OccupancyGrid:
    if scenario.world is None:
        raise InputError("world.map: a mission needs a map")
    return scenario.world.grid()


def mission_world(scenario: Scenario) -> MissionWorld:
    """The scenario's world stage: the field grid, fuel, fires and victims.

    Examples
    --------
    >>> from firefleet import load_scenario
    >>> from firefleet.sim.kinds.mission import mission_world
    >>> world = mission_world(load_scenario("examples/missions/mission-office.yaml"))
    >>> world.field.shape, world.field.resolution_m
    ((40, 80), 0.25)
    """
    cmd = _command(scenario)
    spec = scenario.world
    assert spec is not None  # _grid
    grid = _grid(scenario)
    field = coarsen(grid, spec.field_factor(grid))
    fuel = np.full(field.shape, spec.fuel.default)
    if spec.fuel.regions:
        h, w = field.shape
        centres = field.center_of(np.moveaxis(np.indices((h, w)), 0, -1))
        for region in spec.fuel.regions:
            inside = (
                (centres[..., 0] >= region.x_m[0])
                & (centres[..., 0] <= region.x_m[1])
                & (centres[..., 1] >= region.y_m[0])
                & (centres[..., 1] <= region.y_m[1])
            )
            fuel[inside] = region.load
    fuel[field.occupied] = 0.0
    fires = np.array([[f.x_m, f.y_m] for f in spec.fires], dtype=float).reshape(-1, 2)
    victims = np.array([[v.x_m, v.y_m] for v in spec.victims], dtype=float).reshape(-1, 2)
    from firefleet.models.pt100 import Pt100Params
    from firefleet.world import SMOKE, FireParams, SprayParams

    pt100 = scenario.sensors.pt100 if scenario.sensors is not None else None

    return MissionWorld(
        field=field,
        fuel=fuel,
        fire_cells=np.array([nearest_open(field, xy) for xy in fires], dtype=int).reshape(-1, 2),
        fire_start_s=np.array([f.start_s for f in spec.fires], dtype=float),
        victim_xy_m=victims,
        victim_cells=np.array([nearest_open(field, xy) for xy in victims], dtype=int).reshape(
            -1, 2
        ),
        tank_l=cmd.tank_l,
        refill_l_s=REFILL_L_S,
        rating_c=cmd.rating_c,
        world_step_s=cmd.world_step_s,
        record_s=cmd.record_s,
        seed=scenario.seed,
        spray_params=SprayParams(flow_l_s=cmd.flow_l_s, range_m=cmd.spray_range_m),
        fire_params=FireParams(spread_m_s=spec.spread_m_s),
        pt100=pt100.params() if pt100 is not None else Pt100Params(),
        smoke_params=dataclasses.replace(SMOKE, source=SMOKE.source * spec.fuel.smoke_yield),
    )


def _range_sensors(
    scenario: Scenario, grid: OccupancyGrid, rng: np.random.Generator, smoke: Any = None
) -> Any:
    from firefleet.sim.kinds._mission_smoke import stereo_scan_params
    from firefleet.sim.kinds.navigate import _sensor_params  # the same sensors, one reading
    from firefleet.sim.ranging import RangeSensors

    params = _sensor_params(scenario)
    stereo = stereo_scan_params(_command(scenario).perception)  # a stereo-only team's scan
    if not params and stereo is None:
        return None
    return RangeSensors(
        grid,
        _command(scenario).robot_radius_m,
        ultrasonic=params.get("ultrasonic_range_m"),
        lidar=params.get("lidar_range_m"),
        stereo=stereo,
        dt_s=scenario.dt_s,
        rng=rng,
        smoke=smoke,  # smoke dims the lidar and the stereo scan (_mission_smoke)
    )


def mission_stages(scenario: Scenario, decider: Decider, rng: np.random.Generator) -> Stages:
    """The mission's stages (module notes)."""
    from firefleet.sim.kinds._mission_smoke import SmokeAt, VisibleDetector
    from firefleet.sim.kinds._mission_world import LOWER_LAYER
    from firefleet.sim.sensors import ThermalCameraParams
    from firefleet.sim.visible import VisibleCameraParams

    world = mission_world(scenario)
    spec = scenario.sensors
    thermal = spec.thermal if spec is not None else None
    rate = thermal.rate_hz if thermal is not None else 9.0
    camera = ThermalCameraParams(
        supersample=thermal.supersample if thermal is not None else 2,
        netd_k=thermal.netd_k if thermal is not None else 0.05,
    )
    smoke = SmokeAt(world.field, LOWER_LAYER)
    visible = None
    if _command(scenario).perception == "stereo":  # no thermal camera: Jin's law in smoke
        visible = VisibleDetector(
            _grid(scenario), smoke, world.victim_xy_m, VisibleCameraParams(), rng=rng
        )
    sensors = MissionSensors(
        world=world,
        ranging=_range_sensors(scenario, _grid(scenario), rng, smoke),
        camera=camera,
        every=max(1, round(1.0 / (rate * scenario.dt_s))),
        dt_s=scenario.dt_s,
        rng=rng,
        visible=visible,
    )
    stages: Any = dataclasses.replace  # the Stages fields are typed for the default stages
    out: Stages = stages(
        default_stages(scenario, decider), world=world, sensors=sensors, estimation=Odometry()
    )
    return out


# --- the decision --------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class MissionParams:
    """The decision's constants: the tactics', the robot geometry, the range sensors'
    bearings, and whether the team takes part at all."""

    tactics: Any
    geometry: Any
    bearings_rad: dict[str, FloatArray]
    robots: bool
    arrive_s: float = 0.0


def _init(scenario: Scenario) -> tuple[Any, MissionParams]:
    from firefleet.control.mission import TacticsParams, tactics_init
    from firefleet.control.navigation import DwaParams, NavigationParams
    from firefleet.sim.kinds._mission_smoke import stereo_scan_params
    from firefleet.sim.kinds.navigate import reading_bearings

    cmd = _command(scenario)
    tactics = TacticsParams(
        standoff_m=cmd.standoff_m,
        spray_range_m=cmd.spray_range_m,
        tank_l=cmd.tank_l,
        flow_l_s=cmd.flow_l_s,
        refill_l_s=REFILL_L_S,
        refill_xy_m=cmd.refill_m,
        # a person is confirmed by a robot that sees them again from within 3 m (the
        # detector cannot call a standing person a person from much closer: the frame
        # cuts them); found when that position lies within 2 m of them (the world's test)
        confirm_radius_m=3.0,
        # a fighter leaves air at half its rating (the hot layer can rise by tens of
        # degrees in the seconds it takes to drive off, and the PT100 lags it by ~10 s:
        # mission-office seed 0, a fighter in a door at 190 C stayed till flames came)
        retreat_c=0.5 * cmd.rating_c,
        # a fire never takes the whole team: one robot at least keeps searching for people
        fire_robots_max=max(1, min(6, scenario.n_robots - 1)),
        fire_robots_min=min(2, max(1, scenario.n_robots - 1)),
        # the lighter dynamic window (5 x 9 candidates over 8 steps, control.mission's
        # notes): four times cheaper than navigate's 9 x 21 x 15, and on mission-office
        # seed 0 the finer one left a victim unfound and two robots touching
        # DWA's disc is the robot's plus the planner's margin (0.05 m): it avoids the
        # teammates where their dead-reckoned estimates put them, a few cm off (mission-office
        # seed 0: two robots touched at 0.293 m between centres with the bare radius)
        nav=NavigationParams(
            robot_radius_m=cmd.robot_radius_m,
            dwa=DwaParams(n_v=5, n_omega=9, n_steps=8, robot_radius_m=cmd.robot_radius_m + 0.05),
        ),
    )
    bearings = reading_bearings(scenario)
    stereo = stereo_scan_params(cmd.perception)
    if stereo is not None:  # a stereo-only team navigates with its scan too
        bearings["stereo_scan_m"] = np.asarray(stereo.bearings_rad)
    params = MissionParams(tactics, scenario.robot, bearings, cmd.robots, cmd.arrive_s)
    if not cmd.robots:
        return None, params
    return tactics_init(_grid(scenario), scenario.initial_poses, tactics), params


def _on_map(
    rows: FloatArray, pose: FloatArray, kind: int
) -> tuple[FloatArray, np.ndarray, FloatArray]:
    """Detections of one kind placed on the map by the robots' pose estimates: (K, 2)
    positions, robots, peak readings [C]."""
    if not rows.shape[0]:  # most ticks: no frame, nothing to place
        return np.zeros((0, 2)), np.zeros(0, dtype=np.int64), np.zeros(0)
    pick = rows[rows[:, 1] == kind]
    robot = pick[:, 0].astype(np.int64)
    heading = pose[robot, 2] + pick[:, 2]
    xy = pose[robot, :2] + pick[:, 3:4] * np.stack([np.cos(heading), np.sin(heading)], axis=-1)
    ok = np.isfinite(xy).all(axis=1)
    return xy[ok], robot[ok], pick[ok, 4]


def mission_decide(
    state: Any, inputs: DecideInputs, params: MissionParams, dt_s: float
) -> tuple[Any, WheelCommand]:
    """The team's decision at a tick (module notes).

    Parameters
    ----------
    state : TacticsState or None
        The team's brain (None for a run without the team).
    inputs : DecideInputs
        The pose estimate (N, 3) and the readings: ranges, ``thermal_detections``
        (K, 5: robot, kind, bearing [rad], range [m], peak [C]), ``tank_l``,
        ``damaged``, ``looked``.
    params : MissionParams
    dt_s : float

    Returns
    -------
    state, WheelCommand
        Wheel references, the series (``mode``, ``spray``, ``tank_l``) and the actions
        (``spray``, ``refill``, the detections on the map, the confirmed victims, the
        coverage) for the world.
    """
    from firefleet.control.mission import TacticsObservation, tactics_step

    pose = inputs.pose_estimate
    if pose is None:
        raise InputError("mission needs a pose estimate")
    n = pose.shape[0]
    tank = np.asarray(inputs.readings["tank_l"])
    if not params.robots:
        zero = np.zeros((n, 2))
        return state, WheelCommand(reference_rad_s=zero, series={"tank_l": tank})
    if inputs.t_s < params.arrive_s:  # the team has not entered yet: it waits, idle
        idle = {"mode": np.full(n, 4.0), "spray": np.zeros(n), "tank_l": tank}  # MODES[4]
        return state, WheelCommand(reference_rad_s=np.zeros((n, 2)), series=idle)
    rows = np.asarray(inputs.readings["thermal_detections"]).reshape(-1, 5)
    fire_xy, fire_robot, fire_peak = _on_map(rows, pose, FIRE)
    person_xy, person_robot, _ = _on_map(rows, pose, PERSON)
    damaged = np.asarray(inputs.readings["damaged"]) > 0.5
    ranges = {
        name: (inputs.readings[name], bearings)
        for name, bearings in params.bearings_rad.items()
        if name in inputs.readings
    }
    looked = np.asarray(inputs.readings["looked"]) > 0.5
    obs = TacticsObservation(
        t_s=inputs.t_s,
        pose_m=pose,
        fire_xy_m=fire_xy,
        fire_robot=fire_robot,
        person_xy_m=person_xy,
        person_robot=person_robot,
        ranges=ranges,
        tank_l=tank,
        damaged=damaged,
        alive=~damaged,
        looked=looked,
        fire_peak_c=fire_peak,
        air_c=np.asarray(inputs.readings["air_c"], dtype=float)
        if "air_c" in inputs.readings
        else None,
    )
    state, orders = tactics_step(state, obs, params.tactics, dt_s)
    v = np.where(damaged, 0.0, orders.v_m_s)
    omega = np.where(damaged, 0.0, orders.omega_rad_s)
    actions: dict[str, Any] = {
        "spray": np.asarray(orders.spray, dtype=bool),
        "refill": np.asarray(state.refilling, dtype=bool),
    }
    if rows.shape[0]:
        both = np.concatenate(
            [
                np.c_[
                    np.full(len(fire_xy), inputs.t_s), fire_robot, np.zeros(len(fire_xy)), fire_xy
                ],
                np.c_[
                    np.full(len(person_xy), inputs.t_s),
                    person_robot,
                    np.ones(len(person_xy)),
                    person_xy,
                ],
            ]
        )
        picked = np.concatenate([rows[rows[:, 1] == FIRE], rows[rows[:, 1] == PERSON]])
        if len(both) == len(picked):
            actions["detections"] = np.c_[both, picked[:, 3], picked[:, 4]]
        confirmed = np.asarray(state.victims_confirmed, dtype=bool)
        actions["victims_confirmed_xy_m"] = np.asarray(state.victims_xy_m)[confirmed]
    if looked.any():
        actions["explored_pct"] = np.array(100.0 * state.explored_frac)
    return state, WheelCommand(
        reference_rad_s=body_to_wheels(v, omega, params.geometry),
        series={
            "mode": np.asarray(orders.mode, dtype=float),
            "spray": np.asarray(orders.spray, dtype=float),
            "tank_l": tank,
        },
        actions=actions,
    )


# --- metrics -------------------------------------------------------------------------------


def baseline_burned_area_m2(scenario: Scenario) -> float:
    """Burned area [m^2] of the same world without the team at ``duration_s`` (the same
    seed: the fire draws from its own generator, so the two runs burn alike until the
    team's water changes them)."""
    world = mission_world(scenario)
    state = world.init(scenario.n_robots)
    t = 0.0
    while t <= scenario.duration_s + 1e-9:
        state = world.step(state, t)
        t = state.next_s
    area = world.field.resolution_m**2
    return float(np.count_nonzero(state.fire.state != UNBURNT) * area)


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
    baseline burns nothing); ``victims_found`` and ``victims_found_s`` (a victim is
    found when the team confirms a person detection within 2 m of it); ``victims_alive``
    (fractional effective dose below 1); ``explored_pct`` (free map cells a thermal
    camera covered); ``collisions`` (robots that touched a wall or another robot);
    ``robots_damaged``; ``water_used_l`` per robot.
    """
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
    if cmd.robots:
        collided = int(_touching(_grid(scenario), result.pose[:, :, :2], cmd.robot_radius_m).sum())
    burned = float(np.count_nonzero(final != UNBURNT) * area)
    baseline = baseline_burned_area_m2(scenario)
    return {
        "fires_detected": float(detected),
        "first_detection_s": float(fire_det["t_s"].min()) if len(fire_det) else math.nan,
        "fires_extinguished": float(extinguished),
        "all_out_s": all_out,  # NaN (null in metrics.json): not all out
        "burned_area_m2": burned,
        "baseline_burned_area_m2": baseline,
        "burned_vs_baseline": burned / baseline if baseline > 0.0 else math.nan,
        "victims_found": float(np.count_nonzero(np.isfinite(found_s))),
        "victims_found_s": [float(v) for v in found_s],  # NaN: not found
        "victims_alive": float(np.count_nonzero(np.asarray(x["victim_dose"]) < 1.0)),
        "explored_pct": float(np.asarray(x["explored_pct"])[0]),
        "collisions": float(collided),
        "robots_damaged": float(np.count_nonzero(np.asarray(x["damaged"]) > 0.5)),
        "water_used_l": [float(v) for v in np.asarray(x["water_used_l"])],
        **stereo_team_metrics(scenario, mission_metrics),  # NaN unless command.stereo_team
    }


def _figures(result: SimResult, metrics: dict[str, Any]) -> dict[str, bytes]:
    from firefleet.report.mission import figures

    return figures(result, metrics)


KINDS = (
    TaskKind(
        name="mission",
        metric_names=METRIC_NAMES,
        metrics=mission_metrics,
        figures=_figures,
        decider=Decider(
            init=_init,
            decide=mission_decide,
            series=("mode", "spray", "tank_l"),
            uses_estimate=True,
        ),
        stages=mission_stages,
    ),
)
"""The mission kind."""
