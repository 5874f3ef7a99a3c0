"""The differential-drive wheel stack, one control period for a batch of robots.

Every differential-drive robot of the simulator runs the same low-level stack (the
deliverable's section 2.4, Figure 9), for N robots at once (batch-first arrays)::

    wheel speed references (N, 2)
      -> control.pid          voltages from the encoders' measured speeds   (N, 2)
      -> models.motor         exact zero-order hold: currents, speeds, angle turned
      -> models.kinematics    true poses (N, 3), with the true wheel radii and axle
      -> models.encoder       counts and measured speeds                     (N, 2)
      -> models.kinematics    dead reckoning from the counts, nominal geometry (N, 3)

:func:`speed_control` is the first line, :func:`drive_step` the rest: a caller records
what it needs (the voltages it holds over the period) between the two, or skips the PID
and gives voltages of its own (an open-loop run).

The true robot need not be the one its odometry believes in (Borenstein and Feng's
odometry errors): :func:`discretise_drive` takes each wheel's true radius over the
nominal one, the true axle over the nominal one, and a random wheel slip whose variance
grows with the distance travelled. With none of them (the defaults) the pose moves with
the nominal geometry and the wheels turn exactly as the motors do.

References
----------
J. Borenstein, L. Feng, "Measurement and correction of systematic odometry errors in
mobile robots", IEEE Trans. Robotics and Automation 12(6), 1996.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.control.pid import PidParams, PidState, pid_init, pid_step
from firefleet.errors import InputError, check_fields
from firefleet.models.encoder import EncoderParams, EncoderState, encoder_init, encoder_step
from firefleet.models.kinematics import RobotGeometry, _arc_step, diff_drive_step
from firefleet.models.motor import DiscreteMotor, MotorParams, discretise_motor, motor_step

__all__ = [
    "DriveStack",
    "DriveState",
    "dead_reckoning",
    "discretise_drive",
    "drive_init",
    "drive_step",
    "encoder_phase",
    "speed_control",
]


@dataclass(frozen=True)
class DriveStack:
    """The constants of a discretised wheel stack (build it with :func:`discretise_drive`).

    Attributes
    ----------
    geometry : RobotGeometry
        Nominal geometry: what the odometry (and a caller's wheel references) assume.
    true_geometry : RobotGeometry
        Geometry the true pose moves with: the nominal wheel radius and the true axle
        length (the wheels' true radii enter through ``wheel_radius_scale``).
    motor : DiscreteMotor
        Both wheel motors, discretised exactly at the control period ``motor.dt_s``.
    pid : PidParams
        The wheel speed controller.
    encoder : EncoderParams
        The wheel encoders.
    wheel_radius_scale : tuple of float, or None
        True radius / nominal radius of the right and left wheels; None for the nominal
        wheels (the turned angles are not multiplied at all).
    slip_variance_m : float
        k^2 of each wheel's random travel error, variance per metre travelled [m]; the
        slip is drawn only when :func:`drive_step` is given a generator.

    Examples
    --------
    >>> import math
    >>> from firefleet.control.pid import PidParams
    >>> from firefleet.models import EncoderParams, MotorParams, RobotGeometry
    >>> from firefleet.sim.drive import discretise_drive
    >>> stack = discretise_drive(RobotGeometry(), MotorParams(), PidParams(), EncoderParams(), 0.01)
    >>> stack.dt_s, stack.count_angle_rad == 2 * math.pi / 2048
    (0.01, True)
    """

    geometry: RobotGeometry
    true_geometry: RobotGeometry
    motor: DiscreteMotor
    pid: PidParams
    encoder: EncoderParams
    wheel_radius_scale: tuple[float, float] | None = None
    slip_variance_m: float = 0.0

    def __post_init__(self) -> None:
        check_fields(self, "drive", non_negative=("slip_variance_m",))
        scale = self.wheel_radius_scale
        if scale is not None and not (len(scale) == 2 and all(v > 0.0 for v in scale)):
            raise InputError(
                f"drive.wheel_radius_scale must be two numbers > 0 (right, left), got {scale}"
            )

    @property
    def dt_s(self) -> float:
        """Control period [s]."""
        return self.motor.dt_s

    @property
    def count_angle_rad(self) -> float:
        """Wheel angle of one encoder count [rad]; 1.0 for an ideal encoder (counts are angles)."""
        cpr = self.encoder.counts_per_rev
        return 2.0 * math.pi / cpr if cpr else 1.0


def discretise_drive(
    geometry: RobotGeometry,
    motor: MotorParams,
    pid: PidParams,
    encoder: EncoderParams,
    dt_s: float,
    *,
    wheel_radius_scale: tuple[float, float] | None = None,
    axle_scale: float = 1.0,
    slip_variance_m: float = 0.0,
) -> DriveStack:
    """The wheel stack of robots with this hardware, at control period ``dt_s``.

    Parameters
    ----------
    geometry : RobotGeometry
        Nominal geometry (wheel radius [m], axle length [m]).
    motor : MotorParams
        The wheel motors (deliverable Table 2), discretised exactly (zero-order hold).
    pid : PidParams
        The speed controller.
    encoder : EncoderParams
        The encoders.
    dt_s : float
        Control period [s], > 0.
    wheel_radius_scale : (float, float), optional
        True / nominal radius of the right and left wheels; None (default): nominal.
    axle_scale : float
        True / nominal axle length, > 0.
    slip_variance_m : float
        Variance of each wheel's travel error per metre travelled [m], >= 0.

    Returns
    -------
    DriveStack

    Examples
    --------
    >>> from firefleet.control.pid import PidParams
    >>> from firefleet.models import EncoderParams, MotorParams, RobotGeometry
    >>> from firefleet.sim.drive import discretise_drive
    >>> hardware = (RobotGeometry(axle_length_m=0.2), MotorParams(), PidParams(), EncoderParams())
    >>> stack = discretise_drive(*hardware, 0.01, axle_scale=1.1)
    >>> stack.geometry.axle_length_m, round(stack.true_geometry.axle_length_m, 12)
    (0.2, 0.22)
    """
    if not (math.isfinite(axle_scale) and axle_scale > 0.0):
        raise InputError(f"drive.axle_scale must be > 0, got {axle_scale}")
    true_geometry = geometry
    if axle_scale != 1.0:
        true_geometry = RobotGeometry(
            wheel_radius_m=geometry.wheel_radius_m,
            axle_length_m=geometry.axle_length_m * axle_scale,
        )
    return DriveStack(
        geometry=geometry,
        true_geometry=true_geometry,
        motor=discretise_motor(motor, dt_s),
        pid=pid,
        encoder=encoder,
        wheel_radius_scale=wheel_radius_scale,
        slip_variance_m=slip_variance_m,
    )


@dataclass(frozen=True)
class DriveState:
    """State of N robots' wheel stacks.

    Attributes
    ----------
    pose : ndarray, shape (N, 3)
        True poses: x [m], y [m], theta [rad].
    current_a : ndarray, shape (N, 2)
        Motor currents [A], right and left wheel.
    speed_rad_s : ndarray, shape (N, 2)
        True wheel speeds [rad/s].
    measured_rad_s : ndarray, shape (N, 2)
        Wheel speeds measured by the encoders [rad/s] (what the PID sees).
    pid : PidState
        The speed controllers' memory, shape (N, 2).
    encoder : EncoderState
        The encoders' angles and count history, shape (N, 2).
    odometry : ndarray, shape (N, 3), or None
        Dead-reckoned poses from the encoder counts and the nominal geometry, or None
        when not integrated (see :func:`drive_init`).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.pid import PidParams
    >>> from firefleet.models import EncoderParams, MotorParams, RobotGeometry
    >>> from firefleet.sim.drive import discretise_drive, drive_init
    >>> stack = discretise_drive(RobotGeometry(), MotorParams(), PidParams(), EncoderParams(), 0.01)
    >>> state = drive_init(np.zeros((3, 3)), np.zeros((3, 2)), stack, odometry=True)
    >>> state.pose.shape, state.speed_rad_s.shape, state.odometry.shape
    ((3, 3), (3, 2), (3, 3))
    """

    pose: FloatArray
    current_a: FloatArray
    speed_rad_s: FloatArray
    measured_rad_s: FloatArray
    pid: PidState
    encoder: EncoderState
    odometry: FloatArray | None = None


def encoder_phase(encoder: EncoderParams, n_robots: int, rng: np.random.Generator) -> FloatArray:
    """Each wheel's unknown angle from its encoder's zero, uniform within one count.

    Parameters
    ----------
    encoder : EncoderParams
    n_robots : int
    rng : numpy.random.Generator
        Gives (n_robots, 2) uniform draws, also for an ideal encoder (all phases 0), so
        that the random stream does not depend on the encoder.

    Returns
    -------
    ndarray, shape (n_robots, 2)
        Phases [rad] in [0, 2 pi / counts_per_rev).

    Examples
    --------
    >>> import math
    >>> import numpy as np
    >>> from firefleet.models import EncoderParams
    >>> from firefleet.sim.drive import encoder_phase
    >>> phase = encoder_phase(EncoderParams(counts_per_rev=2048), 4, np.random.default_rng(0))
    >>> phase.shape, bool(np.all((0 <= phase) & (phase < 2 * math.pi / 2048)))
    ((4, 2), True)
    >>> encoder_phase(EncoderParams(counts_per_rev=0), 2, np.random.default_rng(0)).tolist()
    [[0.0, 0.0], [0.0, 0.0]]
    """
    cpr = encoder.counts_per_rev
    return rng.uniform(0.0, 2.0 * math.pi / cpr if cpr else 0.0, size=(n_robots, 2))


def drive_init(
    pose: ArrayLike, encoder_phase_rad: ArrayLike, stack: DriveStack, *, odometry: bool = False
) -> DriveState:
    """Robots at rest at ``pose``: no current, no speed, the PIDs' memory cleared.

    Parameters
    ----------
    pose : array_like, shape (N, 3)
        Start poses: x [m], y [m], theta [rad].
    encoder_phase_rad : array_like, shape (N, 2)
        Each wheel's angle relative to its encoder's zero [rad]: a value drawn within
        one count models the unknown phase of the code wheel.
    stack : DriveStack
    odometry : bool
        Also integrate the dead-reckoned pose, from the start pose (default: no).

    Returns
    -------
    DriveState

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.pid import PidParams
    >>> from firefleet.models import EncoderParams, MotorParams, RobotGeometry
    >>> from firefleet.sim.drive import discretise_drive, drive_init
    >>> stack = discretise_drive(RobotGeometry(), MotorParams(), PidParams(), EncoderParams(), 0.01)
    >>> state = drive_init([[1.0, 2.0, 0.5]], np.zeros((1, 2)), stack)
    >>> state.pose.tolist(), state.current_a.tolist(), state.odometry is None
    ([[1.0, 2.0, 0.5]], [[0.0, 0.0]], True)
    """
    p = np.array(pose, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise InputError(f"pose must have shape (N, 3), got {p.shape}")
    n = p.shape[0]
    phase = np.asarray(encoder_phase_rad, dtype=np.float64)
    if phase.shape != (n, 2):
        raise InputError(f"encoder_phase_rad must have shape ({n}, 2), got {phase.shape}")
    measured = np.zeros((n, 2))
    return DriveState(
        pose=p,
        current_a=np.zeros((n, 2)),
        speed_rad_s=np.zeros((n, 2)),
        measured_rad_s=measured,
        pid=pid_init(measured),
        encoder=encoder_init(phase, stack.encoder),
        odometry=p.copy() if odometry else None,
    )


def speed_control(
    state: DriveState, reference_rad_s: ArrayLike, stack: DriveStack
) -> tuple[DriveState, FloatArray]:
    """The wheel speed PIDs: voltages from the references and the measured speeds.

    Parameters
    ----------
    state : DriveState
    reference_rad_s : array_like, broadcastable to (N, 2)
        Wheel speed references [rad/s], right and left.
    stack : DriveStack

    Returns
    -------
    state : DriveState
        With the PIDs' memory for the next period (nothing else changes).
    voltage_v : ndarray, shape (N, 2)
        Saturated motor voltages [V], to be held over the period (:func:`drive_step`).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.pid import PidParams
    >>> from firefleet.models import EncoderParams, MotorParams, RobotGeometry
    >>> from firefleet.sim.drive import discretise_drive, drive_init, speed_control
    >>> stack = discretise_drive(RobotGeometry(), MotorParams(), PidParams(), EncoderParams(), 0.01)
    >>> state = drive_init(np.zeros((1, 3)), np.zeros((1, 2)), stack)
    >>> state, voltage = speed_control(state, [[4.0, 4.0]], stack)
    >>> voltage.tolist()  # at rest: kp * b * r = 2.5 * 0.5 * 4 V
    [[5.0, 5.0]]
    """
    pid, voltage = pid_step(state.pid, reference_rad_s, state.measured_rad_s, stack.pid, stack.dt_s)
    return (
        DriveState(
            pose=state.pose,
            current_a=state.current_a,
            speed_rad_s=state.speed_rad_s,
            measured_rad_s=state.measured_rad_s,
            pid=pid,
            encoder=state.encoder,
            odometry=state.odometry,
        ),
        voltage,
    )


def dead_reckoning(
    pose: FloatArray, counts_before: FloatArray, counts_after: FloatArray, stack: DriveStack
) -> FloatArray:
    """Odometry: the poses moved by the wheels' count differences, nominal geometry.

    Parameters
    ----------
    pose : ndarray, shape (N, 3)
        Dead-reckoned poses before: x [m], y [m], theta [rad].
    counts_before, counts_after : ndarray, shape (N, 2)
        The encoders' counts (angles [rad] for an ideal encoder) at the two samples.
    stack : DriveStack

    Returns
    -------
    ndarray, shape (N, 3)
        The poses after: an arc per period (:func:`firefleet.models.kinematics.diff_drive_step`).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.pid import PidParams
    >>> from firefleet.models import EncoderParams, MotorParams, RobotGeometry
    >>> from firefleet.sim.drive import dead_reckoning, discretise_drive
    >>> ideal = EncoderParams(counts_per_rev=0)  # counts are angles [rad]
    >>> stack = discretise_drive(RobotGeometry(), MotorParams(), PidParams(), ideal, 0.01)
    >>> pose = dead_reckoning(np.zeros((1, 3)), np.zeros((1, 2)), np.full((1, 2), 10.0), stack)
    >>> pose.round(12).tolist()  # 10 rad of a 0.045 m wheel: 0.45 m straight ahead
    [[0.45, 0.0, 0.0]]
    """
    counted = (counts_after - counts_before) * stack.count_angle_rad
    return diff_drive_step(pose, counted, stack.geometry)


def _wheels_arc(pose: FloatArray, dphi_rad: FloatArray, geometry: RobotGeometry) -> FloatArray:
    """:func:`diff_drive_step` on arrays already checked: the same arithmetic, unvalidated.

    ``pose`` (N, 3) and ``dphi_rad`` (N, 2) float64 arrays, as :func:`drive_step` holds
    them; the 100 Hz loop skips the input checks of the public function (a third of its
    cost at 3 robots).
    """
    r, axle = geometry.wheel_radius_m, geometry.axle_length_m
    ds = r * (dphi_rad[:, 0] + dphi_rad[:, 1]) / 2.0
    dtheta = r * (dphi_rad[:, 0] - dphi_rad[:, 1]) / axle
    return _arc_step(pose, ds, dtheta)


def drive_step(
    state: DriveState,
    voltage_v: ArrayLike,
    stack: DriveStack,
    *,
    load_torque_n_m: ArrayLike = 0.0,
    rng: np.random.Generator | None = None,
) -> DriveState:
    """Advance the robots one control period with the motor voltages held.

    Parameters
    ----------
    state : DriveState
    voltage_v : array_like, broadcastable to (N, 2)
        Motor voltages [V] held over the period.
    stack : DriveStack
    load_torque_n_m : array_like, broadcastable to (N, 2)
        Load torque on each motor [N m], held over the period.
    rng : numpy.random.Generator, optional
        Draws each wheel's slip, ``N(0, slip_variance_m * travel)`` [m] with ``travel``
        the wheel's true travel in the period [m] (one standard normal (N, 2) per call,
        whatever the variance); None: no slip.

    Returns
    -------
    DriveState
        The motors (exact zero-order hold), the true poses (an arc per period, with the
        true wheel radii, the true axle and the slip), the encoders (counts and measured
        speeds), and the odometry (the count differences with the nominal geometry).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.pid import PidParams
    >>> from firefleet.models import EncoderParams, MotorParams, RobotGeometry
    >>> from firefleet.sim.drive import discretise_drive, drive_init, drive_step
    >>> motor = MotorParams()
    >>> stack = discretise_drive(RobotGeometry(), motor, PidParams(), EncoderParams(), 0.01)
    >>> state = drive_init(np.zeros((1, 3)), np.zeros((1, 2)), stack)
    >>> for _ in range(300):  # 3 s at 12 V: the open-loop steady speed
    ...     state = drive_step(state, 12.0, stack)
    >>> state.speed_rad_s.round(3).tolist(), round(motor.steady_state(12.0)[1], 3)
    ([[16.746, 16.746]], 16.746)
    """
    current, speed, dphi = motor_step(
        state.current_a, state.speed_rad_s, voltage_v, load_torque_n_m, stack.motor
    )
    encoder, counts, measured = encoder_step(state.encoder, dphi, stack.encoder, stack.dt_s)
    turned = dphi
    scale = None if stack.wheel_radius_scale is None else np.array(stack.wheel_radius_scale)
    if scale is not None:
        turned = dphi * scale
    if rng is not None:
        radius = stack.geometry.wheel_radius_m
        travel = np.abs(dphi) * radius
        if scale is not None:
            travel = travel * scale
        slip = rng.standard_normal(dphi.shape) * np.sqrt(stack.slip_variance_m * travel)
        turned = turned + slip / radius
    pose = _wheels_arc(state.pose, np.asarray(turned, dtype=np.float64), stack.true_geometry)
    odometry = state.odometry
    if odometry is not None:
        counted = (counts - state.encoder.history[-1]) * stack.count_angle_rad
        odometry = _wheels_arc(odometry, counted, stack.geometry)  # dead_reckoning's
    return DriveState(
        pose=pose,
        current_a=current,
        speed_rad_s=speed,
        measured_rad_s=measured,
        pid=state.pid,
        encoder=encoder,
        odometry=odometry,
    )
