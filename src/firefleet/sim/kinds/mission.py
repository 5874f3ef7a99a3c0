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
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from firefleet._typing import BoolArray, FloatArray
from firefleet.errors import InputError
from firefleet.models.kinematics import body_to_wheels
from firefleet.scenarios._mission import Mission
from firefleet.scenarios.schema import Scenario
from firefleet.sim.kinds._mission_contacts import ContactCheck
from firefleet.sim.kinds._mission_metrics import _touching as _touching  # re-exported
from firefleet.sim.kinds._mission_metrics import (
    baseline_burned_area_m2,
    mission_metrics,
)
from firefleet.sim.kinds._mission_odometry import MissionOdometry
from firefleet.sim.kinds._mission_smoke import STEREO_METRIC_NAMES
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
    ProgressCallback,
    Stages,
    WheelCommand,
    default_stages,
)
from firefleet.sim.registry import TaskKind
from firefleet.sim.result import SimResult
from firefleet.world import OccupancyGrid, coarsen

__all__ = [
    "KINDS",
    "METRIC_NAMES",
    "baseline_burned_area_m2",
    "mission_decide",
    "mission_held",
    "mission_metrics",
    "mission_world",
]

METRIC_NAMES = (
    "fires_detected",
    "first_detection_s",
    "fires_extinguished",
    "all_out_s",
    "burned_area_m2",
    "baseline_burned_area_m2",
    "burned_vs_baseline",
    "baseline_all_out_s",
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

ROBOT_RECORD_S = 0.1
"""The robots' series (poses, the wheel stack's quantities, the decision's ``mode``,
``spray``, ``tank_l``) are recorded at most this often [s], the tactics' rate: every
tick of 50 robots over 20 minutes was 516 MB of result.npz. What a sample between
would change, the ``collisions`` metric, is noted at every tick
(:mod:`~firefleet.sim.kinds._mission_contacts`); the rest of the metrics read the
world's log."""


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
    >>> world = mission_world(load_scenario("mission-office"))
    >>> world.field.shape, world.field.resolution_m
    ((40, 80), 0.25)
    """
    cmd = _command(scenario)
    spec = scenario.world
    assert spec is not None  # _grid
    grid = _grid(scenario)
    # blocks counted from the map's first row, as the team's plan grid counts them
    # (control.mission's coarse map): the world's cells and the team's ledger of its
    # water are the same cells. Kept from the bottom, on the maze (168 rows of 5) they
    # lay 0.15 m apart, and the ledger held cells soaked that no water reached.
    field = coarsen(grid, spec.field_factor(grid), keep="top")
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
        contacts=ContactCheck.of(_grid(scenario), cmd.robot_radius_m) if cmd.robots else None,
        # where tanks fill: the team's refill points (default: the start poses' centroid,
        # as the team takes it), checked against the robots' true positions
        refill_xy_m=_refill_points(scenario),
    )


def _refill_points(scenario: Scenario) -> FloatArray | None:
    """The refill points (P, 2) [m] the world fills tanks at: the team's
    (``team_refill_points``: ``command.refill_m``, else the start poses' centroid); None
    without robots."""
    from firefleet.control.mission._params import team_refill_points

    poses = np.asarray(scenario.poses, dtype=float).reshape(-1, 3)
    if len(poses) == 0:
        return None
    return team_refill_points(_command(scenario).refill_points_m or None, poses)


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
        # the tactics read the ranges at their navigation ticks, which are never quiet
        # (control.mission._quiet): a scan between is no news for the decision
        scans_in_stretch=True,
    )
    stages: Any = dataclasses.replace  # the Stages fields are typed for the default stages
    out: Stages = stages(
        default_stages(scenario, decider),
        world=world,
        sensors=sensors,
        estimation=MissionOdometry(),  # Odometry, on the loop's arrays
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


@dataclass(frozen=True, eq=False)
class MissionMemory:
    """The decision's memory: the team's (``tactics``, a TacticsState) and the command
    it last gave, with the damaged robots it was made for: a tick that changes neither
    (the tactics' quiet tick, no frame, no detection) gives the same wheel references,
    spray and refill."""

    tactics: Any
    held: WheelCommand | None = None
    damaged: BoolArray | None = None


_NO_XY = np.zeros((0, 2))
_NO_ROBOT = np.zeros(0, dtype=np.int64)
_NO_PEAK = np.zeros(0)


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
        refill_xy_m=cmd.refill_points_m or None,
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
    return MissionMemory(tactics_init(_grid(scenario), scenario.initial_poses, tactics)), params


def _on_map(
    rows: FloatArray, pose: FloatArray, kind: int
) -> tuple[FloatArray, np.ndarray, FloatArray]:
    """Detections of one kind placed on the map by the robots' pose estimates: (K, 2)
    positions, robots, peak readings [C]."""
    if not rows.shape[0]:  # most ticks: no frame, nothing to place (empty: read-only)
        return _NO_XY, _NO_ROBOT, _NO_PEAK
    pick = rows[rows[:, 1] == kind]
    robot = pick[:, 0].astype(np.int64)
    heading = pose[robot, 2] + pick[:, 2]
    xy = pose[robot, :2] + pick[:, 3:4] * np.stack([np.cos(heading), np.sin(heading)], axis=-1)
    ok = np.isfinite(xy).all(axis=1)
    return xy[ok], robot[ok], pick[ok, 4]


def _observation(
    inputs: DecideInputs, pose: FloatArray, params: MissionParams
) -> tuple[Any, FloatArray]:
    """The tactics' observation at a tick, and the thermal detections' rows (K, 5)."""
    from firefleet.control.mission import TacticsObservation

    tank = np.asarray(inputs.readings["tank_l"])
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
    return obs, rows


def mission_quiet_ticks(
    state: Any, inputs: DecideInputs, params: MissionParams, k: int, dt_s: float, limit: int
) -> int:
    """The decision's quiet ticks (:data:`firefleet.sim.loop.QuietTicks`): after a tick it
    held its command (:class:`MissionMemory`), the ticks ``k, k + 1, ...`` at which the
    tactics' step is quiet (:func:`firefleet.control.mission._quiet.quiet_ticks`) with
    the same readings: the same state and the held command again (no frame, no
    detection, no robot newly damaged: the stages hold those)."""
    from firefleet.control.mission._quiet import quiet_ticks

    pose = inputs.pose_estimate
    if not params.robots or state is None or state.held is None or pose is None:
        return 0
    if k * dt_s < params.arrive_s:
        return 0
    obs, rows = _observation(inputs, pose, params)
    if rows.shape[0] or obs.looked.any() or not np.array_equal(obs.damaged, state.damaged):
        return 0
    times = [(k + j) * dt_s for j in range(limit)]
    return quiet_ticks(state.tactics, obs, params.tactics, times)


def mission_held(state: Any, inputs: DecideInputs) -> WheelCommand | None:
    """The command of the quiet ticks after a tick that made ``state``
    (:data:`firefleet.sim.loop.HeldCommand`): the held one with the tanks of ``inputs``
    (:func:`mission_decide`'s answer when nothing is new); None without a held one."""
    if not isinstance(state, MissionMemory) or state.held is None:
        return None
    held = state.held
    return WheelCommand(
        reference_rad_s=held.reference_rad_s,
        series={**held.series, "tank_l": np.asarray(inputs.readings["tank_l"])},
        actions=held.actions,
    )


def mission_decide(
    state: Any, inputs: DecideInputs, params: MissionParams, dt_s: float
) -> tuple[Any, WheelCommand]:
    """The team's decision at a tick (module notes).

    Parameters
    ----------
    state : MissionMemory or None
        The team's brain and the last command (None for a run without the team).
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
    from firefleet.control.mission import tactics_step

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
    obs, rows = _observation(inputs, pose, params)
    fire_xy, fire_robot, person_xy, person_robot = (
        obs.fire_xy_m,
        obs.fire_robot,
        obs.person_xy_m,
        obs.person_robot,
    )
    damaged, looked, tank = obs.damaged, obs.looked, obs.tank_l
    memory = state
    held = memory.held
    state, orders = tactics_step(memory.tactics, obs, params.tactics, dt_s)
    if (
        held is not None
        and state is memory.tactics
        and not rows.shape[0]
        and not looked.any()
        and np.array_equal(damaged, memory.damaged)
    ):  # nothing new (MissionMemory): the held command, with this tick's tanks
        return memory, WheelCommand(
            reference_rad_s=held.reference_rad_s,
            series={**held.series, "tank_l": tank},
            actions=held.actions,
        )
    v = np.where(damaged, 0.0, orders.v_m_s)
    omega = np.where(damaged, 0.0, orders.omega_rad_s)
    actions: dict[str, Any] = {
        "spray": np.asarray(orders.spray, dtype=bool),
        "refill": np.asarray(state.refilling, dtype=bool),
    }
    reference = body_to_wheels(v, omega, params.geometry)
    series = {
        "mode": np.asarray(orders.mode, dtype=float),
        "spray": np.asarray(orders.spray, dtype=float),
        "tank_l": tank,
    }
    held = WheelCommand(reference_rad_s=reference, series=series, actions=dict(actions))
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
    return MissionMemory(state, held, damaged), WheelCommand(
        reference_rad_s=reference, series=series, actions=actions
    )


def _figures(result: SimResult, metrics: dict[str, Any]) -> dict[str, bytes]:
    from firefleet.report.mission import figures

    return figures(result, metrics)


class _MissionKind(TaskKind):
    """The mission's kind: its robots' series at most every ``ROBOT_RECORD_S``."""

    def run(
        self,
        scenario: Scenario,
        rec_steps: NDArray[np.int64],
        progress: ProgressCallback | None = None,
        *,
        staged: bool = False,
    ) -> SimResult:
        """Run ``scenario``, recording the ticks of ``rec_steps`` on the
        ``ROBOT_RECORD_S`` grid (and the last)."""
        every = max(1, round(ROBOT_RECORD_S / scenario.dt_s))
        steps = np.asarray(rec_steps, dtype=np.int64)
        keep = steps[(steps % every == 0) | (steps == steps[-1])] if steps.size else steps
        return super().run(scenario, keep, progress, staged=staged)


KINDS = (
    _MissionKind(
        name="mission",
        metric_names=METRIC_NAMES,
        metrics=mission_metrics,
        figures=_figures,
        decider=Decider(
            init=_init,
            decide=mission_decide,
            series=("mode", "spray", "tank_l"),
            uses_estimate=True,
            quiet_ticks=mission_quiet_ticks,
            held=mission_held,
        ),
        stages=mission_stages,
        list_items=(("victims_found_s", "victim"), ("stereo_victims_found_s", "victim")),
    ),
)
"""The mission kind."""
