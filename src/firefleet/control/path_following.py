"""The deliverable's fuzzy path-following and cooperative controller (section 2.6.2).

Two Takagi-Sugeno systems, shipped as MATLAB ``.fis`` files in ``control/data/``:

``lambda_correction.fis`` (2.6.2.5, Figures 20-21)
    ``y_err`` [m] -> ``lambda`` [deg]. Seven membership functions from -3 m to 3 m
    (nVeryFar, nFar, nClose, VeryClose, Close, Far, VeryFar; peaks at -3, -1.5, -0.5, 0,
    0.5, 1.5 and 3 m), consequents -40, -25, -10, 0, 10, 25, 40 deg: lambda grows with
    y_err, so a robot parallel to its path turns towards it.
``path_following.fis`` (2.6.2.1-2.6.2.7, Table 1, Figures 14-17, 22-23)
    ``D_rp`` [m], ``x_err`` [m], ``alpha`` [deg] (with lambda added) -> ``v`` [m/s],
    ``omega`` [deg/s]; the eleven rules of Table 1, product AND, weighted average.

    * D_rp: VeryClose, Close, Medium peak at 0, 0.15, 0.35 m (dense near the point:
      slow and precise), Far and VeryFar at 0.8 and 2 m and beyond (wide: fast);
      consequents VeryVerySlow 0.02, VerySlow 0.16, Slow 0.36, Fast 0.8, VeryFast
      1.0 m/s. With Table 1's alpha rules (all VeryVerySlow) averaged in, v grows
      about linearly with D_rp, ``v ~ 0.01 + D_rp / 2`` m/s up to 0.8 m, so robots
      whose points are farther apart (longer paths) go faster (2.6.2.6).
    * x_err: Negative (zmf) and Positive (smf) crossing over -5 cm .. 25 cm; Negative
      fires rule 11 alone: v = omega = 0, the robot waits (2.6.2.4). The crossing is
      wide enough that a robot starting off its path, just behind its point, sets off
      smoothly instead of lurching and stopping each time the point moves on. At the
      built-in scenarios' speeds (0.2-0.36 m/s) a robot tracking its path lags its point
      by 0.4-0.7 m, where x_err is all Positive.
    * alpha: mNeg, Small, mPos peak at -20, 0, 20 deg, BigNegative and BigPositive
      from 60 deg out; consequents -180, -60, 0, 60, 180 deg/s, so omega is about
      1.5 alpha per second for small errors and dominated by alpha (Figure 17).

    The deliverable's figures, which held the exact parameters, are lost; these are
    designed to its text and tuned on its experiments (``firefleet reproduce``).

Inputs (eqs. 9-11), from the robot's pose ``(x, y, phi)`` and its desired point
``(x_d, y_d)`` with the path's heading ``xi_d`` there::

    D_rp  = sqrt((x_d - x)^2 + (y_d - y)^2)                               (9)
    y_err = -sin(phi) (x_d - x) + cos(phi) (y_d - y)                      (10)
    alpha = atan2(y_d - y, x_d - x) - phi, wrapped to [-pi, pi)           (10, 11)
    x_err = cos(xi_d) (x_d - x) + sin(xi_d) (y_d - y)

``x_err`` is measured along the *path* at the desired point, where eq. 10 measures it
along the robot's heading. The two agree for a robot that faces along its path, which is
the case 2.6.2.4 discusses ("x_i > x_di => x_err < 0"). They differ for a robot turned
away from its path: with eq. 10, robot 1 of experiment 2 (heading -pi/2, its path above
it) sees its point behind it for good, so rule 11 would stop it for ever. Along the
path, a robot waits only while it is truly ahead of its point, and turns towards the
path once the point has passed it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet._typing import FloatArray
from firefleet.control.fuzzy import SugenoSystem, evaluate, read_fis
from firefleet.control.fuzzy_kernel import FisTables, compile_system
from firefleet.errors import InputError, as_float_array
from firefleet.models.kinematics import wrap_angle

if TYPE_CHECKING:
    from firefleet.scenarios.schema import PathFollowing

__all__ = [
    "PathFollowingController",
    "arrival",
    "builtin_fis_path",
    "controller_inputs",
]


MAIN_INPUTS = ("D_rp", "x_err", "alpha")
MAIN_OUTPUTS = ("v", "omega")


def builtin_fis_path(name: str) -> Path:
    """Path of a shipped ``.fis`` file: ``"path_following"`` or ``"lambda_correction"``.

    Examples
    --------
    >>> from firefleet.control.path_following import builtin_fis_path
    >>> builtin_fis_path("lambda_correction").name
    'lambda_correction.fis'
    """
    path = Path(str(resources.files("firefleet.control").joinpath(f"data/{name}.fis")))
    if not path.is_file():
        raise InputError(f"no built-in fuzzy system {name!r}")
    return path


def controller_inputs(pose: ArrayLike, desired: ArrayLike) -> FloatArray:
    """The controller's inputs for a team (eqs. 9-11, ``x_err`` along the path).

    Parameters
    ----------
    pose : array_like, shape (N, 3)
        Robot poses x [m], y [m], phi [rad] (the odometry estimate on a robot).
    desired : array_like, shape (N, 3)
        Desired points x_d [m], y_d [m] and the path's heading there xi_d [rad].

    Returns
    -------
    ndarray, shape (N, 4)
        ``D_rp`` [m], ``x_err`` [m], ``y_err`` [m], ``alpha`` [rad] in [-pi, pi).

    Examples
    --------
    >>> from firefleet.control.path_following import controller_inputs
    >>> d_rp, x_err, y_err, alpha = controller_inputs([[0.0, 0.0, 0.0]], [[3.0, 4.0, 0.0]])[0]
    >>> float(d_rp), float(x_err), float(y_err), round(float(alpha), 4)  # alpha = atan2(4, 3)
    (5.0, 3.0, 4.0, 0.9273)
    """
    p = as_float_array(pose, "pose", (None, 3))
    d = as_float_array(desired, "desired", (p.shape[0], 3))
    dx = d[:, 0] - p[:, 0]
    dy = d[:, 1] - p[:, 1]
    phi = p[:, 2]
    d_rp = np.hypot(dx, dy)
    x_err = np.cos(d[:, 2]) * dx + np.sin(d[:, 2]) * dy
    y_err = -np.sin(phi) * dx + np.cos(phi) * dy
    raw = np.arctan2(dy, dx) - phi
    alpha = np.where(d_rp > 0.0, wrap_angle(raw), 0.0)
    return np.stack([d_rp, x_err, y_err, alpha], axis=1)


def arrival(
    arrived: NDArray[np.bool_],
    pose: ArrayLike,
    end: ArrayLike,
    release_index: int,
    pieces: int,
) -> NDArray[np.bool_]:
    """The stop rule: which robots have arrived at their path's end (they then stay).

    A robot arrives once the schedule has released its path's last point
    (``release_index >= pieces``) and its pose is past the end along the path's end
    tangent; from then on its set points are ``v = omega = 0`` for good.

    Parameters
    ----------
    arrived : ndarray of bool, shape (N,)
        Which robots had arrived before.
    pose : array_like, shape (N, 3)
        Poses x [m], y [m], phi [rad] (the odometry estimate on a robot).
    end : array_like, shape (N, 3)
        Each path's end point x [m], y [m] and its heading there [rad].
    release_index : int
        The schedule's release index (:meth:`firefleet.planning.Trajectory.release_index`).
    pieces : int
        Number of pieces of every path.

    Returns
    -------
    ndarray of bool, shape (N,)
        Which robots have arrived now.

    Examples
    --------
    >>> import numpy as np
    >>> arrival(np.zeros(2, bool), [[5.1, 0, 0], [4.9, 0, 0]], [[5, 0, 0]] * 2, 50, 50)
    array([ True, False])
    """
    p = as_float_array(pose, "pose", (None, 3))
    e = as_float_array(end, "end", (p.shape[0], 3))
    past_end = (e[:, 0] - p[:, 0]) * np.cos(e[:, 2]) + (e[:, 1] - p[:, 1]) * np.sin(e[:, 2])
    return np.asarray(arrived | ((release_index >= pieces) & (past_end <= 0.0)))


@dataclass(frozen=True, eq=False)
class PathFollowingController:
    """The two fuzzy systems of the controller.

    Attributes
    ----------
    main : SugenoSystem
        Inputs ``D_rp`` [m], ``x_err`` [m], ``alpha`` [deg]; outputs ``v`` [m/s],
        ``omega`` [deg/s] (the deliverable's units, as a MATLAB user designs them).
    correction : SugenoSystem
        Input ``y_err`` [m], output ``lambda`` [deg].

    Examples
    --------
    >>> from firefleet.control.path_following import PathFollowingController, controller_inputs
    >>> controller = PathFollowingController.builtin()
    >>> [variable.name for variable in controller.main.inputs]
    ['D_rp', 'x_err', 'alpha']
    >>> inputs = controller_inputs([[0.0, 0.0, 0.0]] * 3, [[1.0, 0.0, 0.0]] * 3)
    >>> v, omega, lam = controller.command(inputs)
    >>> v.shape, omega.shape, lam.shape
    ((3,), (3,), (3,))
    """

    main: SugenoSystem
    correction: SugenoSystem

    def __post_init__(self) -> None:
        names = tuple(v.name for v in self.main.inputs)
        outs = tuple(v.name for v in self.main.outputs)
        if names != MAIN_INPUTS or outs != MAIN_OUTPUTS:
            raise InputError(
                f"the path-following system needs inputs {', '.join(MAIN_INPUTS)} and "
                f"outputs {', '.join(MAIN_OUTPUTS)}, got inputs {', '.join(names)} and "
                f"outputs {', '.join(outs)}"
            )
        if len(self.correction.inputs) != 1 or len(self.correction.outputs) != 1:
            raise InputError("the lambda correction system needs one input and one output")

    @classmethod
    def builtin(cls) -> PathFollowingController:
        """The controller shipped with firefleet (``control/data/*.fis``)."""
        return cls(
            main=read_fis(builtin_fis_path("path_following")),
            correction=read_fis(builtin_fis_path("lambda_correction")),
        )

    @classmethod
    def from_command(cls, command: PathFollowing) -> PathFollowingController:
        """The systems a scenario's command names (the built-in ones by default)."""
        return cls.from_files(command.controller_fis or None, command.lambda_fis or None)

    @classmethod
    def from_files(
        cls, main: str | Path | None = None, correction: str | Path | None = None
    ) -> PathFollowingController:
        """Read the systems from ``.fis`` files (the built-in one where None)."""
        return cls(
            main=read_fis(main if main else builtin_fis_path("path_following")),
            correction=read_fis(
                correction if correction else builtin_fis_path("lambda_correction")
            ),
        )

    @cached_property
    def main_tables(self) -> FisTables:
        """The main system flattened for the compiled simulator."""
        return compile_system(self.main)

    @cached_property
    def lambda_tables(self) -> FisTables:
        """The lambda correction flattened for the compiled simulator."""
        return compile_system(self.correction)

    def command(self, inputs: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Velocity set points of a team from its inputs.

        Parameters
        ----------
        inputs : array_like, shape (N, 4)
            ``D_rp`` [m], ``x_err`` [m], ``y_err`` [m], ``alpha`` [rad] (as
            :func:`controller_inputs` gives them).

        Returns
        -------
        v : ndarray, shape (N,)
            Linear velocity [m/s].
        omega : ndarray, shape (N,)
            Angular velocity [rad/s].
        lam : ndarray, shape (N,)
            The lambda correction added to alpha [rad].
        """
        x = as_float_array(inputs, "inputs", (None, 4))
        lam_deg = evaluate(self.correction, x[:, 2:3])[:, 0]
        alpha_deg = np.clip(np.degrees(x[:, 3]) + lam_deg, -180.0, 180.0)
        out = evaluate(self.main, np.stack([x[:, 0], x[:, 1], alpha_deg], axis=1))
        return out[:, 0], np.radians(out[:, 1]), np.radians(lam_deg)
