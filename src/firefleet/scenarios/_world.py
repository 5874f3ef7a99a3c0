"""The scenario's building and range sensors (``world:``, ``sensors:``) and the
``navigate`` command that drives a team through the building.

::

    world:
      map: office                 # built-in name, or a map_server YAML path
    sensors:
      ultrasonic: {count: 8, fov_deg: 15.0, max_range_m: 4.0, noise_m: 0.01}
      lidar: {beams: 90, fov_deg: 360.0, max_range_m: 10.0, noise_m: 0.01}
    command:
      kind: navigate
      goals_m: [[18.0, 7.0], [18.0, 2.0]]   # one goal per robot
      goal_tolerance_m: 0.2
      localisation: odometry                 # or mcl, or slam
"""

from __future__ import annotations

import functools
import math
from typing import Literal

import numpy as np
import pydantic

from firefleet.errors import InputError, check_fields
from firefleet.scenarios._claims import _STRICT
from firefleet.scenarios._mission import (
    FireSpec,
    FuelSpec,
    Mission,
    Pt100Spec,
    ThermalSpec,
    VictimSpec,
)
from firefleet.world import BUILTIN_MAPS, OccupancyGrid, load_map

__all__ = ["LidarSpec", "Navigate", "SensorsSpec", "UltrasonicSpec", "WorldSpec", "check_world"]


@functools.cache
def _builtin_grid(name: str) -> OccupancyGrid:
    """A built-in map, read once (its arrays are read-only)."""
    return load_map(name)


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class WorldSpec:
    """The building: ``map`` is a built-in map's name (``office``, ``warehouse``,
    ``maze``) or the path of a ``map_server`` YAML file; for a mission, its ``fires``,
    ``victims`` and ``fuel`` (:mod:`firefleet.scenarios._mission`) and the cell of the
    fire, heat and smoke grids, ``field_cell_m`` (a whole number of the map's cells;
    default: the fewest map cells that make at least 0.25 m), and
    the fire's spread rate ``spread_m_s`` (its front speed along a one-cell strip of fuel;
    over an open floor, with more burning neighbours, the front runs about 3.7 times
    faster, measured: 4 mm/s gives some 1.5 cm/s, a metre a minute, the lateral flame
    spread over furnishings (Quintiere 2016, ch. 8), not a flashover).

    Examples
    --------
    >>> from firefleet.scenarios.schema import WorldSpec
    >>> WorldSpec(map="office").grid().shape
    (200, 400)
    """

    map: str
    fires: tuple[FireSpec, ...] = ()
    victims: tuple[VictimSpec, ...] = ()
    fuel: FuelSpec = pydantic.Field(default_factory=FuelSpec)
    field_cell_m: float | None = None
    spread_m_s: float = 0.004

    def __post_init__(self) -> None:
        if not (math.isfinite(self.spread_m_s) and self.spread_m_s > 0.0):
            raise InputError(f"world.spread_m_s must be > 0, got {self.spread_m_s}")
        try:  # an unknown name or a bad file is an error here, naming world.map
            grid = self.grid()
        except InputError as exc:
            text = str(exc)
            named = text if text.startswith("world.map") else f"world.map: {text}"
            raise InputError(named) from None
        factor = self.field_factor(grid)
        if self.field_cell_m is not None and not (
            factor >= 1 and abs(self.field_cell_m / grid.resolution_m - factor) < 1e-6
        ):
            raise InputError(
                f"world.field_cell_m: {self.field_cell_m:g} must be a whole number (>= 1) "
                f"of the map's {grid.resolution_m:g} m cells"
            )
        points: tuple[tuple[str, tuple[FireSpec | VictimSpec, ...]], ...] = (
            ("fires", self.fires),
            ("victims", self.victims),
        )
        for key, items in points:
            for i, item in enumerate(items):
                why = _where_blocked(grid, (item.x_m, item.y_m))
                if why is not None:
                    raise InputError(
                        f"world.{key}[{i}]: ({item.x_m:g}, {item.y_m:g}) {why} of map {self.map!r}"
                    )
        x0, x1, y0, y1 = grid.extent_m
        for i, region in enumerate(self.fuel.regions):
            if (
                region.x_m[1] <= x0
                or region.x_m[0] >= x1
                or region.y_m[1] <= y0
                or region.y_m[0] >= y1
            ):
                raise InputError(
                    f"world.fuel.regions[{i}]: x_m {list(region.x_m)}, y_m {list(region.y_m)} "
                    f"lies outside map {self.map!r} (x {x0:g}..{x1:g} m, y {y0:g}..{y1:g} m)"
                )

    def field_factor(self, grid: OccupancyGrid) -> int:
        """Map cells per side of a field cell: ``field_cell_m`` over the map's resolution,
        or, without the key, the fewest that make a field cell of at least 0.25 m."""
        if self.field_cell_m is None:
            return max(1, math.ceil(0.25 / grid.resolution_m - 1e-9))
        return max(0, round(self.field_cell_m / grid.resolution_m))

    def grid(self) -> OccupancyGrid:
        """The map's occupancy grid (:func:`firefleet.world.load_map`)."""
        if self.map in BUILTIN_MAPS:
            return _builtin_grid(self.map)
        return load_map(self.map)


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class UltrasonicSpec:
    """A ring of ``count`` ultrasonic rangers (HC-SR04-like), evenly spaced about the
    robot: cone ``fov_deg`` wide, returns up to ``max_range_m``, noise ``noise_m`` (1 sigma)."""

    count: int = 8
    fov_deg: float = 15.0
    max_range_m: float = 4.0
    noise_m: float = 0.01

    def __post_init__(self) -> None:
        if self.count < 1:
            raise InputError(f"sensors.ultrasonic.count must be >= 1, got {self.count}")
        check_fields(
            self,
            "sensors.ultrasonic",
            positive=("fov_deg", "max_range_m"),
            non_negative=("noise_m",),
        )


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class LidarSpec:
    """A planar lidar: ``beams`` over ``fov_deg`` centred ahead, up to ``max_range_m``,
    noise ``noise_m`` (1 sigma)."""

    beams: int = 90
    fov_deg: float = 360.0
    max_range_m: float = 10.0
    noise_m: float = 0.01

    def __post_init__(self) -> None:
        if self.beams < 1:
            raise InputError(f"sensors.lidar.beams must be >= 1, got {self.beams}")
        check_fields(
            self, "sensors.lidar", positive=("fov_deg", "max_range_m"), non_negative=("noise_m",)
        )
        if self.fov_deg > 360.0:
            raise InputError(f"sensors.lidar.fov_deg must be <= 360, got {self.fov_deg}")


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class SensorsSpec:
    """The sensors every robot carries (each optional): range sensors and, for a
    mission, the thermal camera and the PT100 (without ``pt100`` a mission's robots
    carry the default probe)."""

    ultrasonic: UltrasonicSpec | None = None
    lidar: LidarSpec | None = None
    thermal: ThermalSpec | None = None
    pt100: Pt100Spec | None = None


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class Navigate:
    """Navigation through the building: each robot to its own goal.

    Attributes
    ----------
    goals_m : tuple of (x_m, y_m)
        One goal per robot, in the order of ``poses``.
    goal_tolerance_m : float
        A robot has arrived when it is this close to its goal [m].
    localisation : {"odometry", "mcl", "slam"}
        Where the robots' poses come from: dead reckoning; Monte Carlo localisation on
        the known map; grid SLAM (mapping as they go). ``mcl`` and ``slam`` need a range
        sensor (``sensors.ultrasonic`` or ``sensors.lidar``).
    robot_radius_m : float
        Radius of the robot's disc, for collisions, inflation and the sensors [m].

    Examples
    --------
    >>> from firefleet.scenarios.schema import Navigate
    >>> Navigate(kind="navigate", goals_m=((1.0, 2.0),)).localisation
    'odometry'
    """

    kind: Literal["navigate"]
    goals_m: tuple[tuple[float, float], ...]
    goal_tolerance_m: float = 0.2
    localisation: Literal["odometry", "mcl", "slam"] = "odometry"
    robot_radius_m: float = 0.15

    def __post_init__(self) -> None:
        if not self.goals_m:
            raise InputError("command.goals_m: at least one goal")
        check_fields(self, "command", positive=("goal_tolerance_m", "robot_radius_m"))

    def check_team(self, n_robots: int, duration_s: float) -> None:
        """One goal per robot.

        Raises
        ------
        InputError
            Naming the counts.
        """
        if len(self.goals_m) != n_robots:
            raise InputError(
                f"command.goals_m: one goal per robot, got {len(self.goals_m)} goals for "
                f"{n_robots} poses"
            )


def _where_blocked(grid: OccupancyGrid, xy: tuple[float, float]) -> str | None:
    """Why a robot cannot stand at ``xy`` (off the map, in a wall, unknown), or None."""
    point = np.asarray(xy, dtype=float)
    if not bool(grid.contains(point)):
        x0, x1, y0, y1 = grid.extent_m
        return f"is off the map (x {x0:g}..{x1:g} m, y {y0:g}..{y1:g} m)"
    row, col = (int(v) for v in grid.cell_of(point))
    if grid.occupied[row, col]:
        return "is inside a wall"
    if not grid.free[row, col]:
        return "is on an unknown cell"
    return None


def check_world(
    world: WorldSpec | None,
    sensors: SensorsSpec | None,
    poses: tuple[tuple[float, float, float], ...],
    command: object,
) -> None:
    """Check the poses (and a navigate command's goals and sensors) against the map.

    Raises
    ------
    InputError
        A pose or goal off the map, inside a wall or on an unknown cell; a navigate
        command without ``world``; a localisation without the range sensor it needs.

    Examples
    --------
    >>> from firefleet.errors import InputError
    >>> from firefleet.scenarios._world import WorldSpec, check_world
    >>> try:
    ...     check_world(WorldSpec(map="office"), None, ((4.0, 2.0, 0.0),), None)
    ... except InputError as error:
    ...     print(error)
    poses[0]: (4, 2) is inside a wall of map 'office'
    """
    navigate = command if isinstance(command, Navigate) else None
    mission = command if isinstance(command, Mission) else None
    if world is None:
        if navigate is not None or mission is not None:
            kind = "navigate" if navigate is not None else "mission"
            raise InputError(f"world.map: a {kind} command needs a map (world: {{map: office}})")
        return
    thermal = mission is not None and mission.robots and mission.perception == "thermal"
    if thermal and (sensors is None or sensors.thermal is None):
        raise InputError(
            "sensors.thermal: a mission's robots find fires and people with their thermal "
            "cameras (sensors: {thermal: {}})"
        )
    grid = world.grid()
    for i, pose in enumerate(poses):
        why = _where_blocked(grid, (pose[0], pose[1]))
        if why is not None:
            raise InputError(f"poses[{i}]: ({pose[0]:g}, {pose[1]:g}) {why} of map {world.map!r}")
    if mission is not None and mission.refill_m is not None:
        points = mission.refill_points_m
        for k, (x, y) in enumerate(points):
            why = _where_blocked(grid, (x, y))
            if why is not None:
                where = "command.refill_m" + (f"[{k}]" if len(points) > 1 else "")
                raise InputError(f"{where}: ({x:g}, {y:g}) {why} of map {world.map!r}")
    if navigate is None:
        return
    for i, goal in enumerate(navigate.goals_m):
        if not all(math.isfinite(v) for v in goal):
            raise InputError(f"command.goals_m[{i}]: must be finite numbers, got {goal}")
        why = _where_blocked(grid, goal)
        if why is not None:
            raise InputError(
                f"command.goals_m[{i}]: ({goal[0]:g}, {goal[1]:g}) {why} of map {world.map!r}"
            )
    ranged = sensors is not None and (sensors.ultrasonic is not None or sensors.lidar is not None)
    if navigate.localisation in ("mcl", "slam") and not ranged:
        raise InputError(
            f"sensors: localisation {navigate.localisation!r} needs a range sensor "
            "(sensors.ultrasonic or sensors.lidar)"
        )
