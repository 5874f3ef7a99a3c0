"""The on-board configuration: which robot this is, its role, its hardware, its link.

A YAML file (``examples/robot-fake.yaml`` runs on any machine with ``--fake``)::

    scenario: coop-different-paths   # the team's scenario (built-in name or a YAML path,
                                     # relative to this file): its geometry, motors,
                                     # controllers and this robot's role in it
    robot: 0                         # which of its robots this is (0-based)
    duration_s: 30.0                 # optional: stop sooner than the scenario does
    hardware:
      motors: {adapter: arduino, port: /dev/ttyACM0}        # or {adapter: fake}
      thermal: {adapter: lepton, spi_bus: 0, spi_device: 0, i2c_bus: 1, rate_hz: 9.0}
      pt100: {adapter: max31865, spi_bus: 0, spi_device: 1, wires: 3, rate_hz: 1.0}
      ultrasonic: {adapter: hcsr04, trigger_gpio: 23, echo_gpio: 24, max_distance_m: 4.0}
      webcams: {adapter: v4l2, left: /dev/video0, right: /dev/video2, rate_hz: 2.0}
    safety:
      overrun_streak: 10             # this many late periods in a row: e-stop, exit 1
    link:                            # the team link (absent: the robot runs alone)
      team: true                     # publish this robot's progress, hear its teammates'
      run_id: "0000000000000001"     # the run's id (16 hex digits), the plant's --run-id
      timeout_s: 1.0                 # no teammate's message this long: lost-link e-stop
      rearm_s: 0.5                   # the link back this long: the e-stop released
      listen: tcp/127.0.0.1:0        # --fake: the zenoh endpoints of the link (with
      connect: []                    # --sim, the plant's endpoint is the link's)

Unknown keys, wrong types and out-of-range values are errors naming the key
(``robot.yaml: hardware.motors.adapter: ...``), as for scenarios.
"""

from __future__ import annotations

import difflib
import json
from dataclasses import field, fields, is_dataclass
from pathlib import Path
from typing import Any, Literal, get_type_hints

import pydantic
import yaml

from firefleet.errors import InputError

__all__ = ["HardwareConfig", "LinkConfig", "RobotConfig", "parse_robot_config", "read_robot_config"]

_STRICT = pydantic.ConfigDict(extra="forbid", strict=True)


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class MotorsConfig:
    """The motor board: ``arduino`` on a serial port, or ``fake`` (a simulated board)."""

    adapter: Literal["arduino", "fake"] = "fake"
    port: str = "/dev/ttyACM0"
    baud: int = pydantic.Field(default=115_200, gt=0)


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class ThermalConfig:
    """The thermal camera: a Lepton on SPI and I2C, ``fake``, or ``none``."""

    adapter: Literal["lepton", "fake", "none"] = "none"
    lepton: Literal[2, 3] = 2
    spi_bus: int = pydantic.Field(default=0, ge=0)
    spi_device: int = pydantic.Field(default=0, ge=0)
    i2c_bus: int = pydantic.Field(default=1, ge=0)
    rate_hz: float = pydantic.Field(default=9.0, gt=0.0, le=27.0)


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class Pt100Config:
    """The air-temperature probe: a PT100 on a MAX31865, ``fake``, or ``none``."""

    adapter: Literal["max31865", "fake", "none"] = "none"
    spi_bus: int = pydantic.Field(default=0, ge=0)
    spi_device: int = pydantic.Field(default=1, ge=0)
    wires: Literal[2, 3, 4] = 3
    mains_hz: Literal[50, 60] = 50
    rate_hz: float = pydantic.Field(default=1.0, gt=0.0, le=50.0)


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class UltrasonicConfig:
    """The range finder: an HC-SR04 on two GPIO pins (BCM numbers), ``fake``, or ``none``.

    ``fake_distance_m`` is the wall the fake sees (``--fake``), in air at the fake
    PT100's temperature.
    """

    adapter: Literal["hcsr04", "fake", "none"] = "none"
    trigger_gpio: int = pydantic.Field(default=23, ge=2, le=27)
    echo_gpio: int = pydantic.Field(default=24, ge=2, le=27)
    max_distance_m: float = pydantic.Field(default=4.0, gt=0.0, le=4.0)
    shots: int = pydantic.Field(default=5, ge=1, le=50)
    air_temperature_c: float = pydantic.Field(default=20.0, ge=-40.0, le=85.0)
    rate_hz: float = pydantic.Field(default=10.0, gt=0.0, le=100.0)
    fake_distance_m: float = pydantic.Field(default=1.5, gt=0.0)


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class WebcamsConfig:
    """The webcams (``left`` and, for stereo, ``right``: ``/dev/videoN`` or a video file)
    through OpenCV's V4L2 capture, or ``none``.

    ``fake_left``/``fake_right`` are the video files that stand in for the cameras with
    ``--fake`` (relative to the working directory); without them ``--fake`` runs with
    no webcams. ``calibration``: the pair's stereo calibration (``firefleet stereo
    calibrate``'s YAML); with it each pair becomes a range scan (nearest obstacle).
    """

    adapter: Literal["v4l2", "none"] = "none"
    left: str = "/dev/video0"
    right: str | None = "/dev/video2"
    width: int = pydantic.Field(default=640, gt=0)
    height: int = pydantic.Field(default=480, gt=0)
    rate_hz: float = pydantic.Field(default=2.0, gt=0.0, le=30.0)
    fake_left: str | None = None
    fake_right: str | None = None
    calibration: str | None = None


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class HardwareConfig:
    """Each device's adapter."""

    motors: MotorsConfig = field(default_factory=MotorsConfig)
    thermal: ThermalConfig = field(default_factory=ThermalConfig)
    pt100: Pt100Config = field(default_factory=Pt100Config)
    ultrasonic: UltrasonicConfig = field(default_factory=UltrasonicConfig)
    webcams: WebcamsConfig = field(default_factory=WebcamsConfig)


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class SafetyConfig:
    """When the robot stops by itself."""

    overrun_streak: int = pydantic.Field(default=10, ge=1)


def _run_id(value: str) -> str:
    try:
        ok = len(value) == 16 and int(value, 16) >= 0
    except ValueError:
        ok = False
    if not ok:
        raise ValueError(f"expected 16 hex digits, got {value!r}")
    return value.lower()


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class LinkConfig:
    """The team link over zenoh: this robot's progress out, its teammates' in, and the
    lost-link e-stop (see :mod:`firefleet.robot._teamlink`)."""

    team: bool = True
    run_id: str = "0000000000000001"
    timeout_s: float = pydantic.Field(default=1.0, gt=0.0, le=60.0)
    rearm_s: float = pydantic.Field(default=0.5, ge=0.0, le=60.0)
    listen: str = "tcp/127.0.0.1:0"
    connect: list[str] = field(default_factory=list)

    @pydantic.field_validator("run_id")
    @classmethod
    def _check_run_id(cls, value: str) -> str:
        return _run_id(value)


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class RobotConfig:
    """One robot's on-board configuration (module notes)."""

    scenario: str
    robot: int = pydantic.Field(default=0, ge=0)
    duration_s: float | None = pydantic.Field(default=None, gt=0.0)
    hardware: HardwareConfig = field(default_factory=HardwareConfig)
    safety: SafetyConfig = field(default_factory=SafetyConfig)
    link: LinkConfig | None = None


def _type_at(loc: tuple[Any, ...]) -> Any:
    tp: Any = RobotConfig
    for key in loc:
        if not (is_dataclass(tp) and isinstance(key, str)):
            return None
        tp = get_type_hints(tp).get(key)
    return tp


def _describe(error: Any, origin: str) -> str:
    loc = tuple(error["loc"])
    where = ".".join(str(k) for k in loc) or "config"
    if error["type"] in ("unexpected_keyword_argument", "extra_forbidden"):
        parent = _type_at(loc[:-1])
        names = [f.name for f in fields(parent)] if is_dataclass(parent) else []
        close = difflib.get_close_matches(str(loc[-1]), names, n=1, cutoff=0.6)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        return f"{origin}: {where}: unknown key{hint}"
    if error["type"] in ("missing", "missing_argument"):
        return f"{origin}: {where}: required, missing"
    value = json.dumps(error.get("input"), default=str)[:60]
    return f"{origin}: {where}: {error['msg']}, got {value}"


def parse_robot_config(data: Any, *, origin: str = "config") -> RobotConfig:
    """Validate a robot configuration given as plain data.

    Examples
    --------
    >>> from firefleet.robot import parse_robot_config
    >>> config = parse_robot_config({"scenario": "coop-different-paths", "robot": 2})
    >>> config.robot, config.hardware.motors.adapter, config.safety.overrun_streak
    (2, 'fake', 10)
    >>> try:
    ...     parse_robot_config({"scenario": "x", "hardware": {"motor": {}}}, origin="r.yaml")
    ... except ValueError as error:
    ...     print(error)
    r.yaml: hardware.motor: unknown key; did you mean 'motors'?
    """
    if not isinstance(data, dict):
        raise InputError(f"{origin}: a robot configuration must be a mapping")
    try:
        return pydantic.TypeAdapter(RobotConfig).validate_json(json.dumps(data), strict=True)
    except pydantic.ValidationError as exc:
        raise InputError("\n".join(_describe(e, origin) for e in exc.errors())) from None
    except (TypeError, ValueError) as exc:
        raise InputError(f"{origin}: not plain data: {exc}") from None


def read_robot_config(path: str | Path) -> tuple[RobotConfig, Path]:
    """Read a configuration file; also the folder its relative paths resolve against."""
    p = Path(path)
    try:
        data = yaml.safe_load(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"{p}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{p}: cannot read: {exc}") from None
    except yaml.YAMLError as exc:
        raise InputError(f"{p}: not valid YAML: {exc}".replace("\n", " ")) from None
    return parse_robot_config(data, origin=str(p)), p.parent
