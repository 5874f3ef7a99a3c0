"""A landmark world and a simulated drive for localisation and SLAM (seed section 2.7.3).

One robot of the foundation's stack drives a closed loop (a rounded rectangle, 100 m by
default) among heat-source landmarks, on the world loop (:func:`firefleet.sim.loop.
run_staged`). Every control period (10 ms): a ground-truth pose sensor
(:class:`~firefleet.sim.loop.TruePose`: the drive makes a data set, so it steers on the
true pose), odometry (dead reckoning of the encoder counts), the steering law (pure
pursuit) -> ``models.kinematics.body_to_wheels`` -> the wheel stack of
:mod:`firefleet.sim.drive` (``control.pid.pid_step -> models.motor.motor_step ->
models.encoder.encoder_step -> models.kinematics.diff_drive_step``).

The camera's observations are drawn after the drive, from the recorded true poses (the
random stream: landmarks, encoder phases, the wheels' slip step by step, then the
observations frame by frame).

The true robot is not the one its odometry believes in: its wheels' effective radii
differ slightly from the nominal one and from each other, its axle is slightly longer,
and each wheel slips a little (Borenstein and Feng's systematic and non-systematic
odometry errors). The odometry integrates the encoder counts with the nominal geometry,
so dead reckoning drifts as a real robot's does.

At each camera frame a range-bearing sensor with the FLIR Lepton's field of view (51
degrees horizontal) reports the landmarks inside its view and range, each detected with
a probability below one, with Gaussian noise, plus Poisson clutter (spurious hot spots,
landmark id -1). The simulator records the ground truth and writes a
:class:`~firefleet.estimation.logs.SlamLog` (firefleet's log format, see
:mod:`firefleet.estimation.logs`): the estimators never step the simulator.

References
----------
J. Borenstein, L. Feng, "Measurement and correction of systematic odometry errors in
mobile robots", IEEE Trans. Robotics and Automation 12(6), 1996.
R. C. Coulter, "Implementation of the pure pursuit path tracking algorithm",
CMU-RI-TR-92-01, 1992.
FLIR Lepton 2.5 datasheet: 80 x 60 pixels, 51 degrees horizontal field of view, < 9 Hz.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from firefleet._typing import FloatArray
from firefleet.control.pid import PidParams
from firefleet.errors import InputError, check_fields
from firefleet.estimation.logs import SlamLog, read_log
from firefleet.estimation.particle_filter import (
    OdometryNoise,
    odometry_covariance,
    predict_range_bearing,
    relative_pose,
)
from firefleet.models.encoder import EncoderParams
from firefleet.models.kinematics import RobotGeometry, body_to_wheels, wrap_angle
from firefleet.models.motor import MotorParams
from firefleet.sim.drive import discretise_drive, drive_init, encoder_phase
from firefleet.sim.loop import (
    DecideInputs,
    Odometry,
    Stages,
    StaticWorld,
    TruePose,
    WheelCommand,
    run_staged,
)

__all__ = [
    "SIM_LOOP",
    "DriveParams",
    "DriveResult",
    "RangeBearingSensor",
    "load_or_simulate_log",
    "loop_landmarks",
    "loop_path",
    "simulate_drive",
]

ProgressCallback = Callable[[int, int], None]


@dataclass(frozen=True)
class RangeBearingSensor:
    """A heat-source detector with the thermal camera's view, giving range and bearing.

    Attributes
    ----------
    fov_deg : float
        Horizontal field of view [deg] (FLIR Lepton 2.5: 51 degrees), centred ahead.
    max_range_m : float
        Detection range [m].
    range_sigma_m : float
        Range noise standard deviation [m] (range from the stereo pair or ultrasound).
    bearing_sigma_deg : float
        Bearing noise standard deviation [deg]; 0.5 deg is about one Lepton 2.5 pixel
        (51 deg / 80 px = 0.64 deg).
    detection_probability : float
        Chance that a landmark in view is reported, in (0, 1].
    clutter_per_frame : float
        Mean number of spurious detections per frame (Poisson), uniform over the view.
    frame_steps : int
        Control periods per camera frame (12 at 10 ms: 8.3 Hz, under the Lepton's 8.7 Hz).

    Examples
    --------
    >>> import math
    >>> from firefleet.sim.world import RangeBearingSensor
    >>> sensor = RangeBearingSensor(range_sigma_m=0.1, bearing_sigma_deg=1.0)
    >>> round(sensor.fov_rad, 4), sensor.covariance.shape
    (0.8901, (2, 2))
    >>> bool(sensor.covariance[1, 1] == math.radians(1.0) ** 2)
    True
    """

    fov_deg: float = 51.0
    max_range_m: float = 12.0
    range_sigma_m: float = 0.1
    bearing_sigma_deg: float = 0.5
    detection_probability: float = 0.95
    clutter_per_frame: float = 0.05
    frame_steps: int = 12

    def __post_init__(self) -> None:
        check_fields(
            self,
            "sensor",
            positive=("fov_deg", "max_range_m", "range_sigma_m", "bearing_sigma_deg"),
            non_negative=("clutter_per_frame",),
        )
        if not 0.0 < self.detection_probability <= 1.0:
            raise InputError(
                f"sensor.detection_probability must be in (0, 1], got {self.detection_probability}"
            )
        if self.frame_steps < 1:
            raise InputError(f"sensor.frame_steps must be >= 1, got {self.frame_steps}")

    @property
    def fov_rad(self) -> float:
        """Field of view [rad]."""
        return math.radians(self.fov_deg)

    @property
    def covariance(self) -> FloatArray:
        """Observation covariance (2, 2) of (range [m], bearing [rad])."""
        return np.diag([self.range_sigma_m**2, math.radians(self.bearing_sigma_deg) ** 2])


@dataclass(frozen=True)
class DriveParams:
    """The loop, the robot and its odometry errors.

    Attributes
    ----------
    straight_x_m, straight_y_m : float
        Lengths of the loop's straight sides [m]; with ``corner_radius_m`` they make the
        perimeter (100.0 m by default: 2 (25 + 15.575) + 2 pi 3).
    corner_radius_m : float
        Radius of the four corners [m].
    laps : float
        Laps to drive (> 0); one lap comes back to the start, closing the loop.
    speed_m_s : float
        Cruise speed [m/s].
    lookahead_m : float
        Pure-pursuit look-ahead distance [m].
    dt_s : float
        Control period [s].
    geometry : RobotGeometry
        The nominal geometry the odometry uses.
    wheel_radius_scale : tuple of float
        True radius / nominal radius of the right and left wheels.
    axle_scale : float
        True axle length / nominal.
    slip_variance_m : float
        k^2 of each wheel's random travel error, variance per metre travelled [m].
    odometry_noise : OdometryNoise
        The error model written into the log (the estimator's belief).
    landmark_spacing_m : float
        Distance along the loop between landmarks [m].
    landmark_offset_m : tuple of float
        Range of the landmarks' distance from the path [m], alternating sides.

    Examples
    --------
    >>> from firefleet.sim.world import DriveParams
    >>> round(DriveParams().loop_length_m, 3)  # 2 (25 + 15.575) + 2 pi 3
    100.0
    """

    straight_x_m: float = 25.0
    straight_y_m: float = 15.575
    corner_radius_m: float = 3.0
    laps: float = 1.0
    speed_m_s: float = 0.5
    lookahead_m: float = 1.0
    dt_s: float = 0.01
    geometry: RobotGeometry = field(default_factory=RobotGeometry)
    wheel_radius_scale: tuple[float, float] = (1.0005, 0.9995)
    axle_scale: float = 1.01
    slip_variance_m: float = 2e-6
    odometry_noise: OdometryNoise = field(
        default_factory=lambda: OdometryNoise(
            wheel_variance_m=1e-5, floor_sigma_xy_m=1e-3, floor_sigma_theta_rad=1e-3
        )
    )
    landmark_spacing_m: float = 2.0
    landmark_offset_m: tuple[float, float] = (0.5, 2.5)
    motor: MotorParams = field(default_factory=MotorParams)
    pid: PidParams = field(default_factory=PidParams)
    encoder: EncoderParams = field(default_factory=EncoderParams)
    sensor: RangeBearingSensor = field(default_factory=RangeBearingSensor)

    def __post_init__(self) -> None:
        check_fields(
            self,
            "drive",
            positive=(
                "straight_x_m",
                "straight_y_m",
                "corner_radius_m",
                "laps",
                "speed_m_s",
                "lookahead_m",
                "dt_s",
                "axle_scale",
                "landmark_spacing_m",
            ),
            non_negative=("slip_variance_m",),
        )
        if min(self.wheel_radius_scale) <= 0.0:
            raise InputError(f"drive.wheel_radius_scale must be > 0, got {self.wheel_radius_scale}")

    @property
    def loop_length_m(self) -> float:
        """Perimeter of the loop [m]."""
        return 2.0 * (self.straight_x_m + self.straight_y_m) + 2.0 * math.pi * self.corner_radius_m


def loop_path(params: DriveParams, *, spacing_m: float = 0.02) -> FloatArray:
    """Points ``(K, 2)`` every ``spacing_m`` along the loop, counter-clockwise from (0, 0).

    The loop starts at the middle of its bottom side heading +x, so the robot starts at
    the origin of the log's frame.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.world import DriveParams, loop_path
    >>> path = loop_path(DriveParams(), spacing_m=0.5)
    >>> path.shape, path[0].tolist(), path[1].tolist()
    ((200, 2), [0.0, 0.0], [0.5, 0.0])
    """
    a, b, rc = params.straight_x_m, params.straight_y_m, params.corner_radius_m
    s = np.arange(0.0, params.loop_length_m, spacing_m)
    seg = [a / 2, math.pi * rc / 2, b, math.pi * rc / 2, a, math.pi * rc / 2, b]
    seg += [math.pi * rc / 2, a / 2]
    ends = np.cumsum(seg)
    xy = np.empty((s.size, 2))
    # corner centres and the heading at the start of each piece
    cx, cy = a / 2, b / 2
    pieces = [
        ("line", (0.0, -cy - rc), 0.0),
        ("arc", (cx, -cy), -math.pi / 2),
        ("line", (cx + rc, -cy), math.pi / 2),
        ("arc", (cx, cy), 0.0),
        ("line", (cx, cy + rc), math.pi),
        ("arc", (-cx, cy), math.pi / 2),
        ("line", (-cx - rc, cy), -math.pi / 2),
        ("arc", (-cx, -cy), math.pi),
        ("line", (-cx, -cy - rc), 0.0),
    ]
    starts = np.concatenate([[0.0], ends[:-1]])
    for (kind, (px, py), ang), s0, s1 in zip(pieces, starts, ends, strict=True):
        sel = (s >= s0) & (s < s1)
        u = s[sel] - s0
        if kind == "line":
            xy[sel, 0] = px + u * math.cos(ang)
            xy[sel, 1] = py + u * math.sin(ang)
        else:
            phi = ang + u / rc
            xy[sel, 0] = px + rc * np.cos(phi)
            xy[sel, 1] = py + rc * np.sin(phi)
    xy[:, 1] += cy + rc  # start at the origin
    return xy


def loop_landmarks(params: DriveParams, rng: np.random.Generator) -> FloatArray:
    """Landmarks ``(L, 2)`` along the loop, alternately inside and outside it [m].

    One every ``landmark_spacing_m`` of path, at a distance drawn uniformly in
    ``landmark_offset_m`` from the path, on alternating sides.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.world import DriveParams, loop_landmarks
    >>> loop_landmarks(DriveParams(landmark_spacing_m=2.0), np.random.default_rng(0)).shape
    (50, 2)
    """
    path = loop_path(params, spacing_m=0.02)
    step = max(round(params.landmark_spacing_m / 0.02), 1)
    idx = np.arange(step // 2, path.shape[0], step)
    tangent = path[(idx + 1) % path.shape[0]] - path[idx - 1]
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    normal = np.stack([-tangent[:, 1], tangent[:, 0]], axis=1)  # to the left (inside)
    side = np.where(np.arange(idx.size) % 2 == 0, 1.0, -1.0)
    lo, hi = params.landmark_offset_m
    offset = rng.uniform(lo, hi, size=idx.size)
    return np.asarray(path[idx] + normal * (side * offset)[:, None], dtype=np.float64)


@dataclass(frozen=True)
class DriveResult:
    """A simulated drive.

    Attributes
    ----------
    log : SlamLog
        What the robot recorded (odometry, observations) with the ground truth.
    landmarks : ndarray, shape (L, 2)
        The true landmarks [m] (ids 0..L-1).
    t_s : ndarray, shape (T,)
        Time of each camera frame [s].
    truth : ndarray, shape (T, 3)
        True pose at each frame.
    odometry_pose : ndarray, shape (T, 3)
        Dead-reckoned pose from the encoders at each frame.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.world import DriveParams, simulate_drive
    >>> small = DriveParams(straight_x_m=2.0, straight_y_m=1.0, corner_radius_m=1.0, laps=0.1)
    >>> drive = simulate_drive(np.random.default_rng(0), params=small)
    >>> drive.truth.shape == drive.odometry_pose.shape == (drive.t_s.size, 3)
    True
    """

    log: SlamLog
    landmarks: FloatArray
    t_s: FloatArray
    truth: FloatArray
    odometry_pose: FloatArray


def _pure_pursuit(
    pose: FloatArray, path: FloatArray, near: int, lookahead_pts: int, window: int
) -> tuple[float, int]:
    """Curvature command [1/m] toward the look-ahead point, and the nearest path index."""
    k = path.shape[0]
    cand = (near + np.arange(window)) % k
    d2 = np.sum((path[cand] - pose[:2]) ** 2, axis=1)
    near = int(cand[int(np.argmin(d2))])
    target = path[(near + lookahead_pts) % k]
    dx, dy = target[0] - pose[0], target[1] - pose[1]
    alpha = math.atan2(dy, dx) - pose[2]
    ld2 = dx * dx + dy * dy
    return 2.0 * math.sin(alpha) / math.sqrt(ld2), near


@dataclass(frozen=True, eq=False)
class _Pursuit:
    """The steering law's constants: the loop (K, 2), its look-ahead and search window
    (in path points), the speed [m/s] and the nominal geometry."""

    path: FloatArray
    lookahead_pts: int
    window: int
    speed_m_s: float
    geometry: RobotGeometry


def _pursuit_decide(
    near: int, inputs: DecideInputs, params: _Pursuit, dt_s: float
) -> tuple[int, WheelCommand]:
    """Pure pursuit on the true pose (``readings["pose"]``) at constant speed; records the
    odometry. The state is the index of the path point nearest the robot."""
    curvature, near = _pure_pursuit(
        inputs.readings["pose"][0], params.path, near, params.lookahead_pts, params.window
    )
    v = params.speed_m_s
    ref = body_to_wheels(np.array([v]), np.array([v * curvature]), params.geometry)
    odometry = inputs.pose_estimate
    assert odometry is not None  # the Odometry stage
    return near, WheelCommand(reference_rad_s=ref, series={"odometry_pose": odometry})


def simulate_drive(
    rng: np.random.Generator,
    *,
    params: DriveParams | None = None,
    landmarks: FloatArray | None = None,
    progress: ProgressCallback | None = None,
) -> DriveResult:
    """Drive the loop once (or ``params.laps`` times) and record a SLAM log.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws the landmarks (when not given), wheel slip, detections and noise.
    params : DriveParams, optional
    landmarks : ndarray, shape (L, 2), optional
        The landmarks; :func:`loop_landmarks` by default.
    progress : callable(done, total), optional

    Returns
    -------
    DriveResult

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.world import DriveParams, simulate_drive
    >>> small = DriveParams(straight_x_m=2.0, straight_y_m=1.0, corner_radius_m=1.0, laps=0.1)
    >>> drive = simulate_drive(np.random.default_rng(0), params=small)
    >>> drive.truth[0].tolist(), drive.landmarks.shape[1]
    ([0.0, 0.0, 0.0], 2)
    """
    prm = params or DriveParams()
    sensor = prm.sensor
    lms = loop_landmarks(prm, rng) if landmarks is None else np.asarray(landmarks, dtype=float)
    path = loop_path(prm)
    spacing = 0.02
    look = max(round(prm.lookahead_m / spacing), 1)
    window = max(round(4.0 * prm.speed_m_s * prm.dt_s / spacing) + 20, 20)
    n_steps = math.ceil(prm.laps * prm.loop_length_m / prm.speed_m_s / prm.dt_s)
    nominal = prm.geometry
    # the true robot: its wheels' radii, its axle and its slip, as DriveParams says
    stack = discretise_drive(
        nominal,
        prm.motor,
        prm.pid,
        prm.encoder,
        prm.dt_s,
        wheel_radius_scale=prm.wheel_radius_scale,
        axle_scale=prm.axle_scale,
        slip_variance_m=prm.slip_variance_m,
    )
    # an ideal encoder draws nothing here (the log of a seed stays the same)
    phase = encoder_phase(prm.encoder, 1, rng) if prm.encoder.counts_per_rev else np.zeros((1, 2))
    drive = drive_init(np.zeros((1, 3)), phase, stack)
    stages = Stages(world=StaticWorld(), sensors=TruePose(), estimation=Odometry())
    pursuit = _Pursuit(
        path=path, lookahead_pts=look, window=window, speed_m_s=prm.speed_m_s, geometry=nominal
    )
    rec = run_staged(
        drive,
        stack,
        stages,
        _pursuit_decide,
        0,
        pursuit,
        np.arange(0, n_steps + 1, sensor.frame_steps),
        n_steps,
        progress=progress,
        rng=rng,  # draws the wheels' slip, step by step
    )
    truth = rec.pose[:, 0].copy()
    odo_pose = rec.series["odometry_pose"][:, 0].copy()
    t = rec.t_s
    log = _record(truth, odo_pose, t, lms, prm, rng)
    return DriveResult(log=log, landmarks=lms, t_s=t, truth=truth, odometry_pose=odo_pose)


def _record(
    truth: FloatArray,
    odo_pose: FloatArray,
    t: FloatArray,
    lms: FloatArray,
    prm: DriveParams,
    rng: np.random.Generator,
) -> SlamLog:
    """The log: odometry between frames, detections at each frame, the ground truth."""
    sensor = prm.sensor
    n = truth.shape[0]
    deltas = relative_pose(odo_pose[:-1], odo_pose[1:])
    cov = odometry_covariance(deltas, prm.geometry, prm.odometry_noise)
    half = 0.5 * sensor.fov_rad
    sig = np.array([sensor.range_sigma_m, math.radians(sensor.bearing_sigma_deg)])
    steps: list[int] = []
    ids: list[int] = []
    zs: list[FloatArray] = []
    for k in range(n):
        z = predict_range_bearing(truth[k], lms)
        seen = (z[:, 0] <= sensor.max_range_m) & (np.abs(z[:, 1]) <= half)
        seen &= rng.random(lms.shape[0]) < sensor.detection_probability
        for j in np.flatnonzero(seen):
            noisy = z[j] + sig * rng.standard_normal(2)
            noisy[1] = wrap_angle(noisy[1])
            steps.append(k)
            ids.append(int(j))
            zs.append(noisy)
        for _ in range(int(rng.poisson(sensor.clutter_per_frame))):
            fake = np.array([rng.uniform(1.0, sensor.max_range_m), rng.uniform(-half, half)])
            steps.append(k)
            ids.append(-1)
            zs.append(fake)
    m = len(steps)
    return SlamLog(
        name="simulated loop",
        pose_ids=np.arange(n, dtype=np.int64),
        odometry=deltas,
        odometry_cov=cov,
        obs_step=np.array(steps, dtype=np.int64),
        obs_landmark=np.array(ids, dtype=np.int64),
        obs_z=np.array(zs, dtype=np.float64).reshape(m, 2),
        obs_cov=np.tile(sensor.covariance, (m, 1, 1)),
        sensor_fov_rad=sensor.fov_rad,
        sensor_max_range_m=sensor.max_range_m,
        truth_time_s=t,
        truth_pose=truth,
        truth_landmark_ids=np.arange(lms.shape[0], dtype=np.int64),
        truth_landmarks=lms,
    )


SIM_LOOP = "sim-loop"
"""Name that stands for a freshly simulated drive of the default loop."""


def load_or_simulate_log(name: str, *, seed: int = 0) -> SlamLog:
    """Read the log at path ``name``, or simulate the default loop for ``"sim-loop"``.

    Parameters
    ----------
    name : str
        A log path (see :func:`firefleet.estimation.logs.read_log`) or :data:`SIM_LOOP`.
    seed : int
        Seed of the simulated drive.
    """
    if name == SIM_LOOP:
        return simulate_drive(np.random.default_rng(seed)).log
    return read_log(name)
