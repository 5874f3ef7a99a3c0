"""The firefighting mission's scenario keys: fires, victims and fuel in ``world:``, the
thermal camera in ``sensors:``, and the ``mission`` command.

::

    world:
      map: office
      fires: [{x_m: 15.0, y_m: 8.0, start_s: 0.0}]
      victims: [{x_m: 12.0, y_m: 3.0}]
      fuel: {default: 1.0, regions: [{x_m: [0, 4], y_m: [0, 4], load: 2.0}]}
      field_cell_m: 0.25          # the fire, heat and smoke grids' cell
    sensors: {thermal: {}, ultrasonic: {count: 8}}
    command:
      kind: mission
      robots: true                # false: the same world without the team (the baseline)
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import pydantic

from firefleet.errors import InputError, check_fields
from firefleet.models.pt100 import Pt100Params
from firefleet.scenarios._claims import _STRICT

__all__ = ["FireSpec", "FuelRegion", "FuelSpec", "Mission", "ThermalSpec", "VictimSpec"]


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class FireSpec:
    """A fire that starts at ``(x_m, y_m)`` at ``start_s`` (the cell there ignites)."""

    x_m: float
    y_m: float
    start_s: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.x_m) and math.isfinite(self.y_m)):
            raise InputError(f"world.fires: position ({self.x_m}, {self.y_m}) must be finite")
        if not (math.isfinite(self.start_s) and self.start_s >= 0.0):
            raise InputError(f"world.fires: start_s must be >= 0, got {self.start_s}")


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class VictimSpec:
    """A person at ``(x_m, y_m)`` (at 37 C, breathing the air there)."""

    x_m: float
    y_m: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.x_m) and math.isfinite(self.y_m)):
            raise InputError(f"world.victims: position ({self.x_m}, {self.y_m}) must be finite")


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class FuelRegion:
    """A rectangle ``x_m: [x0, x1]``, ``y_m: [y0, y1]`` of relative fuel load ``load``."""

    x_m: tuple[float, float]
    y_m: tuple[float, float]
    load: float

    def __post_init__(self) -> None:
        if not (self.x_m[0] < self.x_m[1] and self.y_m[0] < self.y_m[1]):
            raise InputError(
                f"world.fuel.regions: x_m {list(self.x_m)} and y_m {list(self.y_m)} must "
                "each be [low, high]"
            )
        if not (math.isfinite(self.load) and self.load >= 0.0):
            raise InputError(f"world.fuel.regions: load must be >= 0, got {self.load}")


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class FuelSpec:
    """Relative fuel load of the open cells (1: an office's furnishings; walls 0), and
    the fuel's relative smoke yield ``smoke_yield`` (1: the default smoke production,
    :data:`firefleet.world.SMOKE`; foams and plastics yield about ten times the soot of
    wood, Tewarson, SFPE Handbook, 3rd ed., 2002, section 3 ch. 4)."""

    default: float = 1.0
    regions: tuple[FuelRegion, ...] = ()
    smoke_yield: float = 1.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.default) and self.default >= 0.0):
            raise InputError(f"world.fuel.default must be >= 0, got {self.default}")
        if not (math.isfinite(self.smoke_yield) and self.smoke_yield >= 0.0):
            raise InputError(f"world.fuel.smoke_yield must be >= 0, got {self.smoke_yield}")


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class ThermalSpec:
    """The Lepton on every robot (deliverable section 2.7.1: 80 x 60, 51 deg, 9 Hz).

    Attributes
    ----------
    rate_hz : float
        Frames per second (the Lepton's 8.7 Hz export rate, rounded).
    supersample : int
        Rays per pixel along each axis of the simulated frame.
    netd_k : float
        Temporal noise, 1 sigma [K].
    """

    rate_hz: float = 9.0
    supersample: int = 2
    netd_k: float = 0.05

    def __post_init__(self) -> None:
        check_fields(self, "sensors.thermal", positive=("rate_hz", "supersample"))
        check_fields(self, "sensors.thermal", non_negative=("netd_k",))


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class Pt100Spec:
    """The PT100 air-temperature probe on every robot (deliverable section 2.7.2.7),
    read by a MAX31865 (:mod:`firefleet.models.pt100`).

    Attributes
    ----------
    time_constant_s : float
        The sheath's first-order time constant in air [s].
    ref_ohm : float
        The converter's reference resistor [ohm].
    adc_bits : int
        The converter's resolution (0: an ideal reading).
    """

    time_constant_s: float = 10.0
    ref_ohm: float = 430.0
    adc_bits: int = 15

    def __post_init__(self) -> None:
        self.params()  # checks the values, naming sensors.pt100's keys

    def params(self) -> Pt100Params:
        """The probe's model parameters."""
        return Pt100Params(
            time_constant_s=self.time_constant_s, ref_ohm=self.ref_ohm, adc_bits=self.adc_bits
        )


def _one_or_more(value: object) -> object:
    """``[x, y]`` as ``((x, y),)`` and a list of points as a tuple of tuples (the strict
    schema's form): ``refill_m`` takes one point or a list of them.

    Examples
    --------
    >>> _one_or_more([1.0, 2]), _one_or_more([[1.0, 2.0], [3.0, 4.0]])
    (((1.0, 2),), ((1.0, 2.0), (3.0, 4.0)))
    """
    if not isinstance(value, list | tuple):
        return value
    if len(value) == 0:
        raise ValueError("give a point [x_m, y_m] or a list of them, got []")
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in value):
        return (tuple(value),)
    return tuple(tuple(p) if isinstance(p, list | tuple) else p for p in value)


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class Mission:
    """The firefighting mission: explore, find fires and people, put the fires out.

    Attributes
    ----------
    robots : bool
        Whether the team takes part; false runs the same world alone (the baseline).
    standoff_m : float
        Distance from a fire's edge at which its robots ring it [m].
    tank_l : float
        Each robot's water tank [L].
    flow_l_s : float
        Its pump's flow while spraying [L/s].
    spray_range_m : float
        Reach of its jet [m].
    rating_c : float
        Air temperature a robot survives; hotter air damages it and it stops [C]
        (electronics in a sealed, insulated and water-cooled shell, as firefighting
        robots are built: a few hundred degrees for minutes).
    robot_radius_m : float
        Radius of the robot's disc [m].
    world_step_s : float
        Step of the fire, heat, smoke and victims [s].
    record_s : float
        Recording period [s] (poses and the fields; about 1 Hz).
    perception : {"thermal", "stereo"}
        The team's eyes for people and fires: the thermal camera (``sensors.thermal``)
        or, for a team without one, the stereo pair's visible-light camera, which the
        smoke blinds (docs/mission.md, "Smoke and the stereo-only team").
    stereo_team : bool
        Also run a stereo-only team in the same world (map, fires, people, seed) and
        report its ``stereo_victims_found`` and ``stereo_fires_detected``.
    arrive_s : float
        When the team enters [s]: until then the robots wait at their poses while the
        fire burns (a fire brigade arrives minutes after the ignition).
    refill_m : (x_m, y_m), list of (x_m, y_m), or None
        Where tanks are refilled [m]: a standpipe's hose valve or a fire hose cabinet
        on the floor (building codes place them so that a hose reaches every point of
        the storey: NFPA 14, EN 671), or several of them (an empty tank goes to the one
        nearest by travel). ``None``: the centroid of the start poses (the brigade's
        water at the entrance). Off the map or in a wall: refused.

    Examples
    --------
    >>> from firefleet.scenarios._mission import Mission
    >>> Mission(kind="mission").tank_l
    20.0
    """

    kind: Literal["mission"]
    robots: bool = True
    standoff_m: float = 2.0
    tank_l: float = 20.0
    flow_l_s: float = 0.5
    spray_range_m: float = 3.5
    rating_c: float = 300.0
    robot_radius_m: float = 0.15
    world_step_s: float = 0.1
    record_s: float = 1.0
    perception: Literal["thermal", "stereo"] = "thermal"
    stereo_team: bool = False
    arrive_s: float = 0.0
    refill_m: Annotated[
        tuple[tuple[float, float], ...] | None, pydantic.BeforeValidator(_one_or_more)
    ] = None

    def __post_init__(self) -> None:
        check_fields(
            self,
            "command",
            positive=(
                "standoff_m",
                "tank_l",
                "flow_l_s",
                "spray_range_m",
                "rating_c",
                "robot_radius_m",
                "world_step_s",
                "record_s",
            ),
            non_negative=("arrive_s",),
        )
        if self.refill_m is not None:
            try:
                points = _one_or_more(self.refill_m)
            except ValueError as exc:
                raise InputError(f"command.refill_m: {exc}") from None
            refill = tuple((float(x), float(y)) for x, y in points)  # type: ignore[attr-defined]
            object.__setattr__(self, "refill_m", refill)

    @property
    def refill_points_m(self) -> tuple[tuple[float, float], ...]:
        """The refill points [m] (empty: the start poses' centroid)."""
        return self.refill_m or ()

    def check_team(self, n_robots: int, duration_s: float) -> None:
        """The record and world steps must fit the duration."""
        if self.arrive_s >= duration_s:
            raise InputError(
                f"command.arrive_s {self.arrive_s:g} must be before duration_s {duration_s:g}"
            )
        if self.record_s > duration_s:
            raise InputError(
                f"command.record_s {self.record_s:g} is longer than duration_s {duration_s:g}"
            )
