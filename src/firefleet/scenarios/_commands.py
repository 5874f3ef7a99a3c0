"""The commands a scenario gives its team, one per task kind: motor steps, path
following (section 2.6), formation (section 2.3); and their union ``Command``."""

from __future__ import annotations

import math
from dataclasses import field
from typing import Annotated, Literal

import pydantic

from firefleet.control.formation import FormationParams
from firefleet.errors import InputError, check_fields
from firefleet.planning.paths import PolynomialPath
from firefleet.scenarios._claims import _STRICT
from firefleet.scenarios._mission import Mission
from firefleet.scenarios._world import Navigate


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
    coordination : {"closed", "clock"}
        ``closed``: each robot broadcasts its progress and no robot's desired point
        runs more than ``lead_segments`` ahead of the slowest progress it has heard
        (``firefleet.sim.kinds.path_following``); ``clock`` (the default): the
        open-loop common release schedule alone (2.6.3).
    lead_segments : int
        The closed law's bound [segments].
    """

    kind: Literal["path-following"]
    paths: tuple[PolynomialPath, ...]
    trajectory_s: float
    pieces: int = 200
    arrival_radius_m: float = 0.05
    controller_fis: str = ""
    lambda_fis: str = ""
    coordination: Literal["closed", "clock"] = "clock"
    lead_segments: int = 10

    def __post_init__(self) -> None:
        if self.lead_segments < 1:
            raise InputError(f"command.lead_segments must be >= 1, got {self.lead_segments}")
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
    VoltageStep | WheelSpeedStep | PathFollowing | Formation | Navigate | Mission,
    pydantic.Field(discriminator="kind"),
]
