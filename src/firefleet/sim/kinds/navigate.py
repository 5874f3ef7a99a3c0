"""Navigation through a building (issue 14): each robot of the team to its own goal.

For the whole team, on the world loop (:mod:`firefleet.sim.loop`), with the kind's own
stages (:func:`navigate_stages`)::

    world            the scenario's map (static), the load step on the motors
    sensors          the range sensors of ``sensors:`` (firefleet.sim.ranging.RangeSensors;
                     other robots are obstacles), none without the key
    link             ideal: each robot hears its teammates' estimated positions
    estimation       by ``localisation``: odometry (dead reckoning), Monte Carlo
                     localisation on the known map from a uniform prior, or grid SLAM
                     (firefleet.estimation.grid); the odometry is kept alongside
    decide           the team navigation controller (firefleet.control.navigation:
                     A* on the inflated map -> smoothed path -> the deliverable's fuzzy
                     follower -> give way -> dynamic window on the sensed obstacles)
                     -> (v, omega) -> wheel references (eqs. 1-4)
    drive            the wheel stack

The run ends at ``duration_s``, or earlier once no robot is under way any more (each
has arrived, or found its goal unreachable): an unreachable goal is reported by its
metrics (``goal_reached`` 0), never waited for.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.models.kinematics import RobotGeometry, body_to_wheels
from firefleet.scenarios.schema import Navigate, Scenario
from firefleet.sim.drive import DriveStack, DriveState
from firefleet.sim.kinds._navigate_metrics import METRIC_NAMES, navigate_metrics
from firefleet.sim.loop import (
    DecideInputs,
    Decider,
    Messages,
    NoSensors,
    Odometry,
    OdometryState,
    Sensors,
    Stages,
    StaticWorld,
    WheelCommand,
)
from firefleet.sim.registry import TaskKind
from firefleet.sim.result import SimResult
from firefleet.world import OccupancyGrid

__all__ = [
    "KINDS",
    "NavigateParams",
    "NavigateState",
    "Tracked",
    "navigate_decide",
    "navigate_stages",
    "reading_bearings",
    "reading_limits",
]

RANGE_READINGS = ("ultrasonic_range_m", "lidar_range_m", "stereo_scan_m")
"""The range sensors' readings, by the names the sensors stage gives them."""


def _command(scenario: Scenario) -> Navigate:
    cmd = scenario.command
    if not isinstance(cmd, Navigate):
        raise InputError(f"command.kind: expected navigate, got {cmd.kind!r}")
    return cmd


def _grid(scenario: Scenario) -> OccupancyGrid:
    if scenario.world is None:
        raise InputError("world.map: a navigate command needs a map")
    return scenario.world.grid()


# --- stages ------------------------------------------------------------------------------


@dataclass(frozen=True)
class TrackedState:
    """The odometry and the localisation filter's state, side by side."""

    odometry: OdometryState
    inner: Any


@dataclass(frozen=True, eq=False)
class Tracked:
    """An estimation stage that keeps dead reckoning alongside a localisation filter.

    ``pose`` is the filter's estimate (the odometry's without one); ``series`` gives
    ``odometry_pose`` and ``estimated_pose`` (N, 3) each tick, and ``final`` the team's
    ``occupancy`` map (H, W) where the filter maps.

    Attributes
    ----------
    inner : Estimation or None
        The localisation filter (``firefleet.estimation.grid.MclEstimation`` or
        ``GridSlamEstimation``); None: odometry only.
    """

    inner: Any = None

    def init(self, pose: FloatArray, drive: DriveState) -> TrackedState:
        """Odometry and filter at the start."""
        inner = self.inner.init(pose, drive) if self.inner is not None else None
        return TrackedState(Odometry().init(pose, drive), inner)

    def step(
        self,
        state: TrackedState,
        drive: DriveState,
        stack: DriveStack,
        readings: Messages,
    ) -> TrackedState:
        """Both moved by the counts since the last tick (the filter also by the scans)."""
        odometry = Odometry().step(state.odometry, drive, stack, readings)
        inner = state.inner
        if self.inner is not None:
            inner = self.inner.step(inner, drive, stack, readings)
        return TrackedState(odometry, inner)

    def pose(self, state: TrackedState) -> FloatArray:
        """The filter's estimate, or the odometry (N, 3)."""
        if self.inner is None:
            return state.odometry.pose
        pose: FloatArray = self.inner.pose(state.inner)
        return pose

    def series(self, state: TrackedState) -> Messages:
        """``odometry_pose`` and ``estimated_pose``, (N, 3) each."""
        return {"odometry_pose": state.odometry.pose, "estimated_pose": self.pose(state)}

    def final(self, state: TrackedState) -> Messages:
        """The team's map (``occupancy``, probability (H, W)) where the filter maps."""
        if self.inner is None or not hasattr(self.inner, "occupancy"):
            return {}
        return {"occupancy": np.asarray(self.inner.occupancy(state.inner), dtype=np.float32)}


def _sensors(scenario: Scenario, grid: OccupancyGrid, rng: np.random.Generator) -> Sensors:
    """The range sensors of ``sensors:`` (none without the key)."""
    spec = scenario.sensors
    if spec is None or (spec.ultrasonic is None and spec.lidar is None):
        return NoSensors()
    from firefleet.sim.ranging import LidarParams, RangeSensors, UltrasonicParams

    radius = _command(scenario).robot_radius_m
    ultra = spec.ultrasonic
    lidar = spec.lidar
    return RangeSensors(  # type: ignore[no-any-return]
        grid,
        radius,
        ultrasonic=None
        if ultra is None
        else UltrasonicParams(
            count=ultra.count,
            fov_deg=ultra.fov_deg,
            max_range_m=ultra.max_range_m,
            noise_m=ultra.noise_m,
        ),
        lidar=None
        if lidar is None
        else LidarParams(
            beams=lidar.beams,
            fov_deg=lidar.fov_deg,
            max_range_m=lidar.max_range_m,
            noise_m=lidar.noise_m,
        ),
        rng=rng,
    )


def _localisation(scenario: Scenario, grid: OccupancyGrid, rng: np.random.Generator) -> Any:
    """The filter of ``localisation`` (None for odometry), on the scan it prefers: the
    lidar where the robots carry one, else the ultrasonic ring."""
    cmd = _command(scenario)
    if cmd.localisation == "odometry":
        return None
    from firefleet.estimation.grid import GridSlamEstimation, MclEstimation

    scanners = _scanners(scenario)  # the schema checks a filter has one
    reading = "lidar_range_m" if "lidar_range_m" in scanners else "ultrasonic_range_m"
    scanner = scanners[reading]
    seed = int(rng.integers(2**31))
    if cmd.localisation == "mcl":
        return MclEstimation(grid, scanner, reading=reading, start="global", seed=seed)
    return GridSlamEstimation(grid, scanner, reading=reading, seed=seed)


def navigate_stages(scenario: Scenario, decider: Decider, rng: np.random.Generator) -> Stages:
    """The navigate kind's stages: the map, the range sensors, an ideal link, and the
    localisation of ``command.localisation`` beside the odometry (:class:`Tracked`).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet import load_scenario
    >>> from firefleet.sim.kinds.navigate import navigate_stages
    >>> from firefleet.sim.registry import task_kind
    >>> scenario = load_scenario("nav-doorway")
    >>> stages = navigate_stages(scenario, task_kind("navigate").decider, np.random.default_rng(0))
    >>> stages.names()["estimation"]
    'Tracked'
    """
    grid = _grid(scenario)
    return Stages(
        world=StaticWorld(torque_n_m=scenario.load.torque_n_m, start_s=scenario.load.start_s),
        sensors=_sensors(scenario, grid, rng),
        estimation=Tracked(_localisation(scenario, grid, rng)),
    )


# --- the decision --------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class NavigateParams:
    """The constants of the team's decision.

    Attributes
    ----------
    navigation : NavigationParams
        The navigation controller's (firefleet.control.navigation).
    geometry : RobotGeometry
        Nominal geometry, for the wheel references.
    bearings_rad : dict of str to ndarray
        Each range reading's beam bearings relative to the heading [rad], (B,).
    period_s : float
        The navigation controller runs every ``period_s`` (10 Hz, a lidar's scan rate);
        the wheel references hold in between.
    """

    navigation: Any
    geometry: RobotGeometry
    bearings_rad: dict[str, FloatArray]
    period_s: float = 0.1


@dataclass(frozen=True, eq=False)
class NavigateState:
    """The navigation controller's state and the command it holds until its next run."""

    navigation: Any
    v_m_s: FloatArray
    omega_rad_s: FloatArray
    next_s: float


_UNDER_WAY = ("moving", "waiting")
"""Navigation statuses of a robot still on its way (the others are final)."""


def _scanners(scenario: Scenario) -> dict[str, Any]:
    """The beams of each range reading (``firefleet.estimation.grid.Scanner``): the
    lidar's ``beams`` over ``fov_deg`` centred ahead, the ultrasonic ring's ``count``
    evenly round the robot."""
    spec = scenario.sensors
    if spec is None:
        return {}
    from firefleet.estimation.grid import Scanner

    out: dict[str, Any] = {}
    if spec.ultrasonic is not None:
        u = spec.ultrasonic
        out["ultrasonic_range_m"] = Scanner.ring(u.count, 360.0, u.max_range_m)
    if spec.lidar is not None:
        li = spec.lidar
        out["lidar_range_m"] = Scanner.ring(li.beams, li.fov_deg, li.max_range_m)
    return out


def reading_bearings(scenario: Scenario) -> dict[str, FloatArray]:
    """Each range reading's beam bearings relative to the heading [rad], (B,), by name.

    Examples
    --------
    >>> from firefleet import load_scenario
    >>> from firefleet.sim.kinds.navigate import reading_bearings
    >>> {k: v.shape for k, v in reading_bearings(load_scenario("nav-mcl-office")).items()}
    {'ultrasonic_range_m': (8,)}
    """
    return {name: np.asarray(s.bearings_rad) for name, s in _scanners(scenario).items()}


def reading_limits(scenario: Scenario) -> dict[str, float]:
    """Each range reading's maximum range [m], by name."""
    return {name: float(s.max_range_m) for name, s in _scanners(scenario).items()}


def _init(scenario: Scenario) -> tuple[Any, NavigateParams]:
    from firefleet.control.navigation import NavigationParams, navigation_init

    cmd = _command(scenario)
    nav = NavigationParams(robot_radius_m=cmd.robot_radius_m, goal_tolerance_m=cmd.goal_tolerance_m)
    state = navigation_init(_grid(scenario), scenario.initial_poses, np.array(cmd.goals_m), nav)
    zero = np.zeros(scenario.n_robots)
    return NavigateState(state, zero, zero, 0.0), NavigateParams(
        nav, scenario.robot, reading_bearings(scenario)
    )


def navigate_decide(
    state: NavigateState, inputs: DecideInputs, params: NavigateParams, dt_s: float
) -> tuple[NavigateState, WheelCommand]:
    """The team's decision at a tick: the navigation controller's (v, omega) as wheel
    references, from the pose estimate, the range readings and the teammates' positions.

    Parameters
    ----------
    state : NavigateState
        The navigation controller's state and the command it holds.
    inputs : DecideInputs
        ``pose_estimate`` (N, 3), the range readings, and the inbox's ``xy_m`` (N, 2):
        the positions the team broadcast at the last tick.
    params : NavigateParams
    dt_s : float
        Control period [s].

    Returns
    -------
    state : NavigateState
    command : WheelCommand
        Wheel references (N, 2) [rad/s]; ``done`` once no robot is under way.
    """
    from firefleet.control.navigation import NavigationInputs, navigation_step

    pose = inputs.pose_estimate
    if pose is None:
        raise InputError("navigate needs a pose estimate")
    teammates = np.asarray(inputs.inbox.get("xy_m", pose[:, :2]))
    ranges = {
        name: (inputs.readings[name], bearings)
        for name, bearings in params.bearings_rad.items()
        if name in inputs.readings
    }
    if inputs.t_s >= state.next_s - 1e-9:
        nav_inputs = NavigationInputs(
            pose=pose, ranges=ranges, teammates_xy_m=teammates, t_s=inputs.t_s
        )
        nav, v, omega = navigation_step(
            state.navigation, nav_inputs, params.navigation, params.period_s
        )
        state = NavigateState(nav, v, omega, state.next_s + params.period_s)
    v, omega = state.v_m_s, state.omega_rad_s
    status = tuple(state.navigation.status)
    series: dict[str, FloatArray] = {
        "v_ref_m_s": np.asarray(v, dtype=float),
        "omega_ref_rad_s": np.asarray(omega, dtype=float),
        "status": np.array([float(_STATUS_CODE[s]) for s in status]),
    }
    for name in RANGE_READINGS:
        if name in inputs.readings:
            series[name] = np.asarray(inputs.readings[name], dtype=np.float32)
    done = not any(s in _UNDER_WAY for s in status)
    command = WheelCommand(
        reference_rad_s=body_to_wheels(np.asarray(v), np.asarray(omega), params.geometry),
        series=series,
        outbox={"xy_m": pose[:, :2].copy()},
        done=done,
    )
    return state, command


_STATUS_CODE = {
    "moving": 0,
    "waiting": 1,
    "arrived": 2,
    "unreachable": 3,
    "start_blocked": 4,
    "goal_blocked": 5,
}
"""The navigation statuses as recorded in the ``status`` series (T, N)."""


def _figures(result: SimResult, metrics: dict[str, Any]) -> dict[str, bytes]:
    from firefleet.report.navigation import figures

    return figures(result)


KINDS = (
    TaskKind(
        name="navigate",
        metric_names=METRIC_NAMES,
        metrics=navigate_metrics,
        figures=_figures,
        decider=Decider(
            init=_init,
            decide=navigate_decide,
            series=("v_ref_m_s", "omega_ref_rad_s", "status", *RANGE_READINGS),
            uses_estimate=True,
        ),
        stages=navigate_stages,
    ),
)
"""The navigate kind."""
