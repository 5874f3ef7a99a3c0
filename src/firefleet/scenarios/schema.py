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
from collections.abc import Sequence
from dataclasses import field
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import pydantic
import yaml
from numpy.typing import NDArray

from firefleet.control.formation import FormationParams
from firefleet.control.pid import PidParams
from firefleet.errors import InputError, check_fields
from firefleet.models.encoder import EncoderParams
from firefleet.models.kinematics import RobotGeometry
from firefleet.models.motor import MotorParams
from firefleet.planning.paths import PolynomialPath

__all__ = [
    "Claim",
    "LoadStep",
    "PathFollowing",
    "Scenario",
    "VoltageStep",
    "WheelSpeedStep",
    "parse_scenario",
    "read_scenario_file",
]

_STRICT = pydantic.ConfigDict(extra="forbid")
_MAX_STEPS = 50_000_000
_CLAIM_OPS = ("<", "<=", ">", ">=", "~")


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class Claim:
    """A claim about one metric, checked after the run.

    Attributes
    ----------
    metric : str
        Metric name (a key of ``metrics.json``).
    op : {"<", "<=", ">", ">=", "~"}
        Comparison; ``"~"`` means within ``rel_tol`` (relative) of ``value``.
    value : float
        The bound or the target.
    rel_tol : float
        Relative tolerance of ``"~"``.
    source : str
        Where the claim comes from (the deliverable's section or the issue).
    robot : int, optional
        For a per-robot metric (a list in ``metrics.json``): the robot it is about,
        numbered from 1 as the deliverable numbers them. Without it, a claim on a
        per-robot metric must hold for every robot.

    Examples
    --------
    >>> from firefleet.scenarios import Claim
    >>> claim = Claim(metric="steady_speed_rad_s", op="~", value=1.3955, rel_tol=0.005)
    >>> claim.expected, claim.holds(1.40), claim.holds(1.45)
    ('1.3955 ± 0.00698', True, False)
    >>> per_robot = Claim(metric="wait_time_s", op="<", value=1.0, robot=2)
    >>> per_robot.label, per_robot.holds([5.0, 0.5])
    ('wait_time_s[robot 2]', True)
    """

    metric: str
    op: Literal["<", "<=", ">", ">=", "~"]
    value: float
    rel_tol: float = 0.0
    source: str = ""
    robot: int | None = None

    def __post_init__(self) -> None:
        if self.robot is not None and self.robot < 1:
            raise InputError(f"claim on {self.metric}: robot is numbered from 1, got {self.robot}")
        if self.op == "~" and not self.rel_tol > 0:
            raise InputError(f"claim on {self.metric}: op '~' needs rel_tol > 0")
        if self.op != "~" and self.rel_tol != 0:
            raise InputError(f"claim on {self.metric}: rel_tol is only for op '~'")

    @property
    def label(self) -> str:
        """The metric as claimed, e.g. ``"wait_time_s"`` or ``"wait_time_s[robot 2]"``."""
        return self.metric if self.robot is None else f"{self.metric}[robot {self.robot}]"

    def select(self, measured: float | Sequence[float] | None) -> float | list[float] | None:
        """The part of a metric's value this claim is about (the robot's entry, if any)."""
        if self.robot is None or measured is None:
            return None if measured is None else _plain(measured)
        if isinstance(measured, int | float):
            return None
        return float(measured[self.robot - 1]) if self.robot <= len(measured) else None

    @property
    def expected(self) -> str:
        """The claim as a person reads it, in the metric's own unit, e.g. ``"< 0.2"`` or
        ``"1.3955 +- 0.00698"`` (the tolerance ``rel_tol |value|``, in the value's unit)."""
        if self.op == "~":
            return f"{self.value:g} \u00b1 {self.rel_tol * abs(self.value):.3g}"
        return f"{self.op} {self.value:g}"

    def holds(self, measured: float | Sequence[float] | None) -> bool:
        """Whether the metric's value satisfies the claim.

        ``measured`` is the whole metric (a number, or one number per robot); a missing
        or NaN value does not satisfy any claim, and a per-robot list satisfies it only
        if every robot's entry does (or the claimed robot's, with ``robot``).
        """
        value = self.select(measured)
        if isinstance(value, list):
            return bool(value) and all(self._holds_one(v) for v in value)
        return self._holds_one(value)

    def _holds_one(self, measured: float | None) -> bool:
        if measured is None or math.isnan(measured):
            return False
        if self.op == "~":
            return abs(measured - self.value) <= self.rel_tol * abs(self.value)
        compare = {
            "<": measured < self.value,
            "<=": measured <= self.value,
            ">": measured > self.value,
            ">=": measured >= self.value,
        }
        return bool(compare[self.op])


def _plain(value: float | Sequence[float]) -> float | list[float]:
    return float(value) if isinstance(value, int | float) else [float(v) for v in value]


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class VoltageStep:
    """Open loop: every motor gets ``voltage_v`` from ``start_s`` on (0 V before).

    Examples
    --------
    >>> from firefleet.scenarios import VoltageStep
    >>> VoltageStep(kind="voltage-step", voltage_v=1.0).start_s
    0.0
    """

    kind: Literal["voltage-step"]
    voltage_v: float
    start_s: float = 0.0

    def check_team(self, n_robots: int, duration_s: float) -> None:
        """Every team and run length suits a motor step (nothing to check)."""


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class WheelSpeedStep:
    """Closed loop: every wheel's speed reference steps to ``speed_rad_s`` at ``start_s``.

    Examples
    --------
    >>> from firefleet.scenarios import WheelSpeedStep
    >>> WheelSpeedStep(kind="wheel-speed-step", speed_rad_s=10.0, start_s=0.5).speed_rad_s
    10.0
    """

    kind: Literal["wheel-speed-step"]
    speed_rad_s: float
    start_s: float = 0.0

    def check_team(self, n_robots: int, duration_s: float) -> None:
        """Every team and run length suits a motor step (nothing to check)."""


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class PathFollowing:
    """Cooperative path following (section 2.6): each robot follows its own path.

    Attributes
    ----------
    paths : tuple of PolynomialPath
        One per robot, in the order of ``poses``: ``coefficients`` c0..c5 of
        ``y = sum c_k x^k``, ``x_start_m``, ``x_end_m``.
    trajectory_s : float
        When every robot's last desired point falls due [s] (2.6.3).
    pieces : int
        Number of pieces every path is cut into (the same for the whole team).
    arrival_radius_m : float
        A robot has arrived when it is this close to its path's end [m].
    controller_fis, lambda_fis : str
        MATLAB ``.fis`` files of the main system and of the lambda correction; empty
        for the built-in ones (``firefleet.control.path_following``).
    """

    kind: Literal["path-following"]
    paths: tuple[PolynomialPath, ...]
    trajectory_s: float
    pieces: int = 200
    arrival_radius_m: float = 0.05
    controller_fis: str = ""
    lambda_fis: str = ""

    def __post_init__(self) -> None:
        if not self.paths:
            raise InputError("paths: at least one path")
        if not (math.isfinite(self.trajectory_s) and self.trajectory_s > 0):
            raise InputError(f"trajectory_s must be > 0, got {self.trajectory_s}")
        if self.pieces < 1:
            raise InputError(f"pieces must be >= 1, got {self.pieces}")
        if not (math.isfinite(self.arrival_radius_m) and self.arrival_radius_m > 0):
            raise InputError(f"arrival_radius_m must be > 0, got {self.arrival_radius_m}")

    def check_team(self, n_robots: int, duration_s: float) -> None:
        """One path per robot, and the trajectory due within the run.

        Raises
        ------
        InputError
            Naming the counts or the times.
        """
        if len(self.paths) != n_robots:
            raise InputError(
                f"command.paths: one path per robot, got {len(self.paths)} "
                f"paths for {n_robots} poses"
            )
        if self.trajectory_s > duration_s:
            raise InputError(
                f"command.trajectory_s ({self.trajectory_s} s) is longer than "
                f"duration_s ({duration_s} s)"
            )


# --- formation control (section 2.3): the command of the formation-* scenarios ---------------


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class CircleObstacle:
    """A circular obstacle: centre (``x_m``, ``y_m``) and ``radius_m`` [m]."""

    x_m: float
    y_m: float
    radius_m: float

    def __post_init__(self) -> None:
        check_fields(self, "obstacle", positive=("radius_m",))


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class LeaderPath:
    """The virtual leader: at ``waypoints_m[0]`` until ``start_s``, then along the
    polyline through the waypoints at ``speed_m_s`` (reached and left with
    ``accel_m_s2``), stopping at the last one."""

    waypoints_m: tuple[tuple[float, float], ...] = ((0.0, 0.0),)
    speed_m_s: float = 0.0
    accel_m_s2: float = 0.2
    start_s: float = 0.0

    def __post_init__(self) -> None:
        if not self.waypoints_m:
            raise InputError("leader.waypoints_m must list at least one point")
        if not all(math.isfinite(v) for w in self.waypoints_m for v in w):
            raise InputError("leader.waypoints_m must be finite numbers")
        check_fields(
            self, "leader", positive=("accel_m_s2",), non_negative=("speed_m_s", "start_s")
        )


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class RobotFailure:
    """Robot ``robot`` (numbered from 1) stops at ``time_s`` and leaves the formation."""

    robot: int
    time_s: float

    def __post_init__(self) -> None:
        if self.robot < 1:
            raise InputError(f"failure.robot is numbered from 1, got {self.robot}")
        check_fields(self, "failure", non_negative=("time_s",))


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class Formation:
    """Formation about a virtual leader (section 2.3; firefleet.control.formation).

    The team is ``Scenario.poses`` (its size, and the start headings of diff-drive
    robots). With ``scatter_m > 0`` the start positions are not the poses' but drawn,
    with the scenario's ``seed``, uniformly in the square of half-width ``scatter_m``
    about the leader's start, at least two body radii plus ``contact_range_m`` apart
    (the deliverable's "arbitrary" starts). Metrics on the formation's shape are taken
    from ``formed_by_s`` to the end (the formation must have formed by then).
    """

    kind: Literal["formation"]
    law: Literal["deliverable", "regular"] = "deliverable"
    robot_model: Literal["point-mass", "diff-drive"] = "point-mass"
    alpha_m: float = 3.0
    k_r: float = 10.0
    charge_c: float = 1.0
    attraction_gain: float = 1.0
    attraction_limit_n: float | None = 10.0
    spacing_stiffness_n_m: float = 20.0
    robot_radius_m: float = 0.15
    contact_gain: float = 0.05
    contact_range_m: float = 0.5
    mass_kg: float = 1.0
    damping_n_s_m: float = 1.0
    kd_n_s_m: float = 1.0
    look_ahead_m: float = 0.1
    max_speed_m_s: float = 0.5
    scatter_m: float = 0.0
    leader: LeaderPath = field(default_factory=LeaderPath)
    obstacles: tuple[CircleObstacle, ...] = ()
    failure: RobotFailure | None = None
    formed_by_s: float = 0.0

    def __post_init__(self) -> None:
        check_fields(
            self,
            "",
            positive=("look_ahead_m", "max_speed_m_s", "mass_kg"),
            non_negative=("scatter_m", "formed_by_s", "damping_n_s_m", "kd_n_s_m"),
        )
        if self.damping_n_s_m + self.kd_n_s_m <= 0:
            raise InputError("damping_n_s_m + kd_n_s_m must be > 0")
        _ = self.formation_params  # checks alpha_m, k_r, ... naming the field

    @property
    def body_radius_m(self) -> float:
        """Radius of the disc about each formation point that must stay clear [m]:
        the body, or for a diff-drive robot the body plus its look-ahead distance."""
        look = self.look_ahead_m if self.robot_model == "diff-drive" else 0.0
        return self.robot_radius_m + look

    def check_team(self, n_robots: int, duration_s: float) -> None:
        """Check the command against the team's size and the run's length.

        Raises
        ------
        InputError
            If ``failure.robot`` is not in the team, ``formed_by_s`` is after the end,
            or ``n_robots`` bodies of radius :attr:`body_radius_m` cannot stand on the
            circle of radius ``alpha_m`` (the regular polygon's side, ``2 alpha sin(pi /
            N)``, is shorter than a body's diameter).
        """
        if self.failure is not None and self.failure.robot > n_robots:
            raise InputError(
                f"command.failure.robot = {self.failure.robot}, but the team has "
                f"{n_robots} robot(s)"
            )
        if self.formed_by_s > duration_s:
            raise InputError(
                f"command.formed_by_s = {self.formed_by_s} s is after the end of the run "
                f"({duration_s} s)"
            )
        if n_robots < 2:
            return
        body = self.body_radius_m
        side = 2.0 * self.alpha_m * math.sin(math.pi / n_robots)
        if side < 2.0 * body:
            what = (
                "robot_radius_m + look_ahead_m"
                if self.robot_model == "diff-drive"
                else ("robot_radius_m")
            )
            raise InputError(
                f"command.alpha_m = {self.alpha_m} m is too small for {n_robots} robots of "
                f"radius {body:g} m ({what}): neighbours on the circle would be "
                f"{side:.3g} m apart, less than a body's diameter {2.0 * body:g} m; "
                f"alpha_m must be at least {body / math.sin(math.pi / n_robots):.4g} m"
            )

    @property
    def formation_params(self) -> FormationParams:
        """The law's parameters (firefleet.control.formation.FormationParams)."""
        return FormationParams(
            alpha_m=self.alpha_m,
            k_r=self.k_r,
            charge_c=self.charge_c,
            attraction_gain=self.attraction_gain,
            attraction_limit_n=(
                math.inf if self.attraction_limit_n is None else self.attraction_limit_n
            ),
            spacing_stiffness_n_m=self.spacing_stiffness_n_m,
            robot_radius_m=self.robot_radius_m,
            contact_gain=self.contact_gain,
            contact_range_m=self.contact_range_m,
        )


# --- end of formation control ------------------------------------------------------------


Command = Annotated[
    VoltageStep | WheelSpeedStep | PathFollowing | Formation, pydantic.Field(discriminator="kind")
]


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
        self.command.check_team(self.n_robots, self.duration_s)  # each command's own rule
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


def _type_at(root: Any, loc: tuple[int | str, ...]) -> Any:
    """The declared type at ``loc`` below ``root`` (None where it cannot be told)."""
    tp = root
    for key in loc:
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
    return tp


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
        return message if loc == () else f"{where}: {message}"
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
    return parse_scenario(data, origin=str(p))
