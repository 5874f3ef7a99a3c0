"""The scenario schema: typed, frozen, strict.

A scenario file is YAML; an unknown key, a wrong type, a bad value or a duplicate key
is an :class:`~firefleet.errors.InputError` naming the field (as a dotted path), the
value and what was expected, with a suggestion for a misspelt key. Units follow the
key's suffix (``_s``, ``_m``, ``_v``, ``_n_m``, ``_rad_s``); headings are typed in
degrees (``heading_deg``) and converted to radians here, at the edge.

Numbers are checked strictly: ``"1.0"`` (a string) or ``true`` where a number belongs
is an error, not a conversion.
"""

from __future__ import annotations

import dataclasses
import difflib
import json
import math
import re
import types
import typing
from dataclasses import field
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import pydantic
import yaml
from numpy.typing import NDArray

from firefleet.control.pid import PidParams
from firefleet.errors import InputError
from firefleet.models.encoder import EncoderParams
from firefleet.models.kinematics import RobotGeometry
from firefleet.models.motor import MotorParams
from firefleet.scenarios._claims import _STRICT, Claim
from firefleet.scenarios._commands import (
    CircleObstacle,
    Command,
    Formation,
    LeaderPath,
    PathFollowing,
    RobotFailure,
    VoltageStep,
    WheelSpeedStep,
)
from firefleet.scenarios._network import LinkSpec, MotorFault
from firefleet.scenarios._world import (
    LidarSpec,
    Navigate,
    SensorsSpec,
    UltrasonicSpec,
    WorldSpec,
    check_world,
)

__all__ = [
    "CircleObstacle",
    "Claim",
    "Command",
    "Formation",
    "LeaderPath",
    "LidarSpec",
    "LinkSpec",
    "LoadStep",
    "MotorFault",
    "Navigate",
    "PathFollowing",
    "RobotFailure",
    "Scenario",
    "SensorsSpec",
    "UltrasonicSpec",
    "VoltageStep",
    "WheelSpeedStep",
    "WorldSpec",
    "parse_scenario",
    "read_scenario_file",
]


_MAX_STEPS = 50_000_000


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class LoadStep:
    """Load torque on every wheel motor, stepping from 0 to ``torque_n_m`` at ``start_s``.

    Examples
    --------
    >>> from firefleet.scenarios import LoadStep
    >>> LoadStep(torque_n_m=0.5, start_s=5.0).torque_n_m
    0.5
    """

    torque_n_m: float = 0.0
    start_s: float = 0.0


def _metric_names(kind: str) -> tuple[str, ...]:
    """The metrics a command kind declares (its task kind, ``firefleet.sim.registry``)."""
    from firefleet.sim.registry import task_kind  # lazy: the simulator imports this module

    return task_kind(kind).metric_names


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class Scenario:
    """One experiment: the team, its hardware, the command, and the claims to check.

    Attributes
    ----------
    name : str
        Short name (letters, digits, ``-``).
    title : str
        One line for listings and the report.
    command : VoltageStep or WheelSpeedStep
        What drives the wheels.
    duration_s : float
        Simulated time [s].
    dt_s : float
        Fixed step [s] (the deliverable's 0.01 s by default).
    seed : int
        Seed of the run's random generator (encoder phases).
    poses : tuple of (x_m, y_m, heading_deg)
        Start pose of each robot; the team size is their number.
    robot, motor, encoder, speed_pid
        Hardware and low-level control; defaults from the deliverable's Table 2.
    load : LoadStep
        Load torque on the wheel motors.
    faults : tuple of MotorFault
        Motor faults (a robot's motors at a fraction of their voltage for a while).
    link : LinkSpec, optional
        The team's wireless link (``firefleet.sim.link``); None: ideal.
    world : WorldSpec, optional
        The building (a map); None: an empty plane.
    sensors : SensorsSpec, optional
        The range sensors each robot carries; None: none.
    reproduces : str
        The deliverable's figure(s) this scenario reproduces ("" for none).
    deliverable_says : str
        What the deliverable reports for it, quoted or summarised.
    claims : tuple of Claim
        Checked against the metrics after the run.

    Examples
    --------
    >>> from firefleet import load_scenario
    >>> scenario = load_scenario("motor-open-loop")
    >>> scenario.n_steps, scenario.command.kind, len(scenario.poses)
    (1000, 'voltage-step', 1)
    """

    name: str
    title: str
    command: Command
    duration_s: float
    dt_s: float = 0.01
    seed: int = 0
    poses: tuple[tuple[float, float, float], ...] = ((0.0, 0.0, 0.0),)
    robot: RobotGeometry = field(default_factory=RobotGeometry)
    motor: MotorParams = field(default_factory=MotorParams)
    encoder: EncoderParams = field(default_factory=EncoderParams)
    speed_pid: PidParams = field(default_factory=PidParams)
    load: LoadStep = field(default_factory=LoadStep)
    faults: tuple[MotorFault, ...] = ()
    link: LinkSpec | None = None
    world: WorldSpec | None = None
    sensors: SensorsSpec | None = None
    reproduces: str = ""
    deliverable_says: str = ""
    claims: tuple[Claim, ...] = ()

    def __post_init__(self) -> None:
        if not self.name or not all(c.isalnum() or c in "-_" for c in self.name):
            raise InputError(f"name must be letters, digits, '-' or '_', got {self.name!r}")
        if not (math.isfinite(self.dt_s) and self.dt_s > 0):
            raise InputError(f"dt_s must be > 0, got {self.dt_s}")
        if not (math.isfinite(self.duration_s) and self.duration_s >= self.dt_s):
            raise InputError(f"duration_s must be >= dt_s ({self.dt_s}), got {self.duration_s}")
        if self.duration_s / self.dt_s > _MAX_STEPS:
            raise InputError(
                f"duration_s / dt_s = {self.duration_s / self.dt_s:.3g} steps, "
                f"more than {_MAX_STEPS:,}"
            )
        if not self.poses:
            raise InputError("poses must list at least one robot")
        if not all(math.isfinite(v) for pose in self.poses for v in pose):
            raise InputError("poses must be finite numbers")
        if self.speed_pid.output_limit > self.motor.supply_v:
            raise InputError(
                f"speed_pid.output_limit ({self.speed_pid.output_limit} V) exceeds "
                f"motor.supply_v ({self.motor.supply_v} V)"
            )
        if self.seed < 0:
            raise InputError(f"seed must be >= 0, got {self.seed}")
        for fault in self.faults:
            if fault.robot > self.n_robots:
                raise InputError(
                    f"faults.robot = {fault.robot}, but the scenario has {self.n_robots} "
                    "robot(s) (poses)"
                )
        self.command.check_team(self.n_robots, self.duration_s)  # each command's own rule
        check_world(self.world, self.sensors, self.poses, self.command)
        known = _metric_names(self.command.kind)
        for claim in self.claims:
            if claim.metric not in known:
                raise InputError(
                    f"claims: unknown metric {claim.metric!r} for a {self.command.kind} "
                    f"scenario{_suggest(claim.metric, known)}; known: {', '.join(known)}"
                )
            if claim.robot is not None and claim.robot > self.n_robots:
                raise InputError(
                    f"claims: robot {claim.robot} in the claim on {claim.metric}, but the "
                    f"scenario has {self.n_robots} robot(s) (poses)"
                )

    @property
    def n_robots(self) -> int:
        """Team size N."""
        return len(self.poses)

    @property
    def n_steps(self) -> int:
        """Number of steps, ``round(duration_s / dt_s)``."""
        return round(self.duration_s / self.dt_s)

    @property
    def initial_poses(self) -> NDArray[np.float64]:
        """Start poses (N, 3): x [m], y [m], theta [rad]."""
        p = np.array(self.poses, dtype=np.float64).reshape(-1, 3)
        p[:, 2] = np.deg2rad(p[:, 2])
        return p

    @property
    def metric_names(self) -> tuple[str, ...]:
        """The metrics this scenario's run produces."""
        return _metric_names(self.command.kind)


_ADAPTER = pydantic.TypeAdapter(Scenario)
# the ``kind`` tags of the command union: pydantic puts them in error locations
_COMMAND_TAGS = frozenset(
    typing.get_args(typing.get_type_hints(member)["kind"])[0]
    for member in typing.get_args(typing.get_args(Command)[0])
)


def _suggest(word: str, choices: typing.Iterable[str]) -> str:
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f"; did you mean {close[0]!r}?" if close else ""


def _optional(tp: Any) -> Any:
    """``X`` for ``X | None`` (an optional section such as ``world``), else ``tp``."""
    if typing.get_origin(tp) in (types.UnionType, typing.Union):
        members = [m for m in typing.get_args(tp) if m is not type(None)]
        if len(members) == 1:
            return members[0]
    return tp


def _type_at(root: Any, loc: tuple[int | str, ...]) -> Any:
    """The declared type at ``loc`` below ``root`` (None where it cannot be told)."""
    tp = root
    for key in loc:
        tp = _optional(tp)
        origin = typing.get_origin(tp)
        if origin is Annotated:
            tp = typing.get_args(tp)[0]
            origin = typing.get_origin(tp)
        if dataclasses.is_dataclass(tp) and isinstance(key, str):
            hints = typing.get_type_hints(tp, include_extras=True)
            if key not in hints:
                return None
            tp = hints[key]
        elif origin in (types.UnionType, typing.Union) and isinstance(key, str):
            members = [m for m in typing.get_args(tp) if dataclasses.is_dataclass(m)]
            matching = [
                m
                for m in members
                if typing.get_args(typing.get_type_hints(m).get("kind", None)) == (key,)
            ]
            if not matching:
                return None
            tp = matching[0]
        elif origin is tuple and isinstance(key, int):
            args = typing.get_args(tp)
            tp = args[0] if len(args) == 2 and args[1] is Ellipsis else args[key]
        else:
            return None
    return _optional(tp)


def _where(loc: tuple[int | str, ...]) -> str:
    """Dotted path of a location, without the tags of tagged unions."""
    parts: list[str] = []
    for key in loc:
        if isinstance(key, int):
            parts.append(f"[{key}]")
        elif key not in _COMMAND_TAGS:
            parts.append(("." if parts else "") + key)
    return "".join(parts) or "scenario"


def _describe(error: Any) -> str:
    loc = tuple(error["loc"])
    kind = error["type"]
    where = _where(loc)
    if kind in ("unexpected_keyword_argument", "extra_forbidden"):
        parent = _type_at(Scenario, loc[:-1])
        names = [f.name for f in dataclasses.fields(parent)] if parent is not None else []
        return f"{where}: unknown key{_suggest(str(loc[-1]), names)}"
    if kind == "missing" or kind == "missing_argument":
        return f"{where}: required, missing"
    if kind == "value_error":
        message = str(error["msg"]).removeprefix("Value error, ")
        return message if loc == () or message.startswith(where) else f"{where}: {message}"
    value = json.dumps(error.get("input"), default=str)
    if len(value) > 60:
        value = value[:57] + "..."
    return f"{where}: {error['msg']}, got {value}"


def parse_scenario(data: Any, *, origin: str = "scenario") -> Scenario:
    """Validate a scenario given as plain data (what YAML or JSON loads to).

    Parameters
    ----------
    data : dict
        The scenario's mapping.
    origin : str
        Named in error messages (a file name).

    Returns
    -------
    Scenario

    Raises
    ------
    InputError
        Naming every problem found, one per line.

    Examples
    --------
    >>> from firefleet.scenarios import parse_scenario
    >>> data = {"name": "one-volt", "title": "1 V step", "duration_s": 1.0,
    ...         "command": {"kind": "voltage-step", "voltage_v": 1.0}}
    >>> scenario = parse_scenario(data)
    >>> scenario.name, scenario.dt_s, scenario.n_steps
    ('one-volt', 0.01, 100)
    >>> try:
    ...     parse_scenario({**data, "duration_s": "long"}, origin="demo.yaml")
    ... except ValueError as error:
    ...     print(str(error).splitlines()[0])
    demo.yaml: duration_s: Input should be a valid number, got "long"
    """
    if not isinstance(data, dict):
        raise InputError(f"{origin}: a scenario must be a mapping, got {type(data).__name__}")
    if (where := _non_finite(data)) is not None:
        raise InputError(f"{origin}: {where} must be a finite number")
    try:
        text = json.dumps(data, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise InputError(
            f"{origin}: not plain data (numbers, strings, lists, maps): {exc}"
        ) from exc
    try:
        return _ADAPTER.validate_json(text, strict=True)
    except pydantic.ValidationError as exc:
        problems = "\n".join(f"{origin}: {_describe(e)}" for e in exc.errors())
        raise InputError(problems) from None


class _UniqueKeyLoader(yaml.SafeLoader):
    """YAML safe loader that rejects duplicate keys (PyYAML keeps the last silently).

    It also reads numbers as a person writes them: ``1e3`` and ``2E-4`` are floats (YAML
    1.1, PyYAML's dialect, needs ``1.0e+3`` and reads ``1e3`` as a string).
    """


# YAML 1.2's core-schema float, tried after PyYAML's own int and float resolvers (an int
# stays an int): it adds exponents without a dot or a sign, such as 1e3.
_UniqueKeyLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:\.[0-9]+|[0-9][0-9_]*(?:\.[0-9_]*)?)(?:[eE][-+]?[0-9]+)?$"),
    list("-+0123456789."),
)


def _non_finite(data: Any, where: str = "") -> str | None:
    """The key path of the first NaN or infinite number in ``data``, or None."""
    if isinstance(data, float) and not math.isfinite(data):
        return where
    items: Any = ()
    if isinstance(data, dict):
        items = ((f"{where}.{k}" if where else str(k), v) for k, v in data.items())
    elif isinstance(data, list | tuple):
        items = ((f"{where}[{i}]", v) for i, v in enumerate(data))
    for path, value in items:
        found = _non_finite(value, path)
        if found is not None:
            return found
    return None


def _construct_mapping(loader: yaml.SafeLoader, node: yaml.MappingNode) -> dict[Any, Any]:
    seen: set[Any] = set()
    for key_node, _ in node.value:
        key = loader.construct_object(key_node)
        if key in seen:
            raise InputError(f"line {key_node.start_mark.line + 1}: duplicate key {key!r}")
        seen.add(key)
    return dict(loader.construct_mapping(node))


_UniqueKeyLoader.add_constructor(
    yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG,
    _construct_mapping,
)


def read_scenario_file(path: str | Path) -> Scenario:
    """Read and validate a scenario YAML file.

    Raises
    ------
    InputError
        If the file is missing or unreadable, is not YAML, or is not a valid scenario.

    Examples
    --------
    >>> from firefleet.errors import InputError
    >>> from firefleet.scenarios import read_scenario_file
    >>> try:
    ...     read_scenario_file("no-such-scenario.yaml")
    ... except InputError as error:
    ...     print(error)
    no-such-scenario.yaml: no such file
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{p}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{p}: cannot read: {exc}") from None
    try:
        data = yaml.load(text, Loader=_UniqueKeyLoader)
    except InputError as exc:
        raise InputError(f"{p}: {exc}") from None
    except yaml.YAMLError as exc:
        raise InputError(f"{p}: not valid YAML: {exc}".replace("\n", " ")) from None
    world = data.get("world") if isinstance(data, dict) else None
    if isinstance(world, dict) and isinstance(world.get("map"), str):
        where = Path(world["map"])  # a map file relative to the scenario's folder
        if where.suffix.lower() in (".yaml", ".yml") and not where.is_absolute():
            data["world"] = {**world, "map": str(p.parent / where)}
    return parse_scenario(data, origin=str(p))
