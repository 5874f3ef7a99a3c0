"""The Dynamic Window Approach as the safety layer of the path follower (compiled).

Fox, Burgard, Thrun (1997) search the velocities a robot can reach within one control
period for the best trade-off of heading, clearance and speed. Here the *heading* term
is the fuzzy path follower's own command ``(v_ref, omega_ref)`` towards a point ahead on
the A* path, so DWA changes nothing while the way is clear and only bends or slows the
command near obstacles. Per robot and control period ``dt``:

1. The dynamic window, from each wheel's limits (a differential drive's wheels, not a
   box in ``(v, omega)``): ``|v - v0| + |omega - omega0| L / 2 <= a dt`` (each wheel
   changes its rim speed by at most ``a dt``) and ``|v| + |omega| L / 2 <= v_w`` (no
   wheel above its top rim speed), ``v >= 0``, around the last command ``(v0, omega0)``.
2. Candidates: ``n_v`` speeds across the window, ``n_omega`` turn rates across the
   interval each speed leaves, plus the reference projected into the window.
3. Each candidate's arc over ``horizon_s`` (closed form, ``n_steps`` points) against the
   obstacle points (the sensed ranges, radius 0) and teammates' discs: its clearance
   ``c`` (the least distance between the robot's disc and any of them over the arc) and
   the distance travelled before it first moves into contact (clearance < 0 and falling:
   a robot already touching may still move out).
4. Admissible: ``v <= sqrt(2 a d)``, the robot can stop before that contact (Fox's
   admissible velocities). Turning on the spot never moves a disc into contact, so the
   set is never empty once ``v0 <= a dt``; when it is, the slowest candidate (the
   clearest of those) brakes as hard as the window allows.
5. Score ``- ((v - v_ref) / v_max)^2 - ((omega - omega_ref) / omega_max)^2 +
   w_clear min(c, c_cap) / c_cap``: the reference itself wins when its arc keeps
   ``c >= c_cap``.

References
----------
D. Fox, W. Burgard, S. Thrun, "The dynamic window approach to collision avoidance",
IEEE Robotics & Automation Magazine 4(1), 1997.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import BoolArray, FloatArray
from firefleet.errors import InputError, as_float_array, check_fields
from firefleet.models.kinematics import RobotGeometry
from firefleet.models.motor import MotorParams, discretise_motor, motor_step

__all__ = ["DwaParams", "dwa_command", "dwa_limits_from_motor"]


def dwa_limits_from_motor(
    motor: MotorParams | None = None, geometry: RobotGeometry | None = None
) -> tuple[float, float]:
    """Top wheel rim speed [m/s] and rim acceleration [m/s^2] of the robot's own motors.

    The top speed is the motor's steady no-load speed at its supply voltage (Table 2:
    12 V) times the wheel radius. The acceleration is *measured* on the motor's exact
    (zero-order-hold) step response at that voltage: the mean acceleration over the
    first mechanical time constant, ``r w(tau) / tau`` (about 63 % of the top speed in
    ``tau``), the rate a full-voltage step actually delivers, inductance included.

    Examples
    --------
    >>> v_w, a_w = dwa_limits_from_motor()  # Table 2 at 12 V, 45 mm wheels
    >>> round(v_w, 3), round(a_w, 2)
    (0.754, 2.5)
    """
    m = motor if motor is not None else MotorParams()
    g = geometry if geometry is not None else RobotGeometry()
    _, w_top = m.steady_state(m.supply_v)
    tau = m.time_constants_s[0]
    dt = tau / 1000.0
    dm = discretise_motor(m, dt)
    i = np.zeros(1)
    w = np.zeros(1)
    for _ in range(1000):
        i, w, _ = motor_step(i, w, m.supply_v, 0.0, dm)
    return g.wheel_radius_m * w_top, g.wheel_radius_m * float(w[0]) / tau


@dataclass(frozen=True)
class DwaParams:
    """The dynamic window's limits and search.

    Attributes
    ----------
    wheel_speed_max_m_s : float
        Top wheel rim speed [m/s] (Table 2 at 12 V: :func:`dwa_limits_from_motor`).
    wheel_accel_m_s2 : float
        Wheel rim acceleration [m/s^2] (likewise).
    axle_length_m : float
        Distance between the wheels L [m].
    robot_radius_m : float
        The robot's disc [m].
    horizon_s : float
        How far ahead each candidate arc is simulated [s].
    n_v, n_omega, n_steps : int
        Speeds, turn rates per speed, and points per arc.
    clearance_cap_m : float
        Clearance beyond which no candidate scores better [m].
    clearance_weight : float
        Weight of the clearance term against tracking the reference.

    Examples
    --------
    >>> p = DwaParams()
    >>> round(p.v_max_m_s, 3), round(p.omega_max_rad_s, 2)  # v_w and 2 v_w / L
    (0.754, 7.54)
    """

    wheel_speed_max_m_s: float = 0.754
    wheel_accel_m_s2: float = 2.5
    axle_length_m: float = 0.2
    robot_radius_m: float = 0.15
    horizon_s: float = 1.5
    n_v: int = 9
    n_omega: int = 21
    n_steps: int = 15
    clearance_cap_m: float = 0.25
    clearance_weight: float = 0.1

    def __post_init__(self) -> None:
        check_fields(
            self,
            "dwa",
            positive=(
                "wheel_speed_max_m_s",
                "wheel_accel_m_s2",
                "axle_length_m",
                "robot_radius_m",
                "horizon_s",
                "clearance_cap_m",
            ),
        )
        for name in ("n_v", "n_omega", "n_steps"):
            if getattr(self, name) < 2:
                raise InputError(f"dwa.{name} must be >= 2, got {getattr(self, name)}")

    @classmethod
    def from_motor(
        cls, motor: MotorParams | None = None, geometry: RobotGeometry | None = None, **kw: float
    ) -> DwaParams:
        """Limits from the motors (:func:`dwa_limits_from_motor`); other fields by name."""
        g = geometry if geometry is not None else RobotGeometry()
        v_w, a_w = dwa_limits_from_motor(motor, g)
        return cls(
            wheel_speed_max_m_s=v_w,
            wheel_accel_m_s2=a_w,
            axle_length_m=g.axle_length_m,
            **kw,  # type: ignore[arg-type]
        )

    @property
    def v_max_m_s(self) -> float:
        """Top linear speed [m/s] (both wheels at top speed)."""
        return self.wheel_speed_max_m_s

    @property
    def omega_max_rad_s(self) -> float:
        """Top turn rate on the spot [rad/s]."""
        return 2.0 * self.wheel_speed_max_m_s / self.axle_length_m


@numba.njit(cache=True)
def _arc_xy(x: float, y: float, th: float, v: float, w: float, t: float) -> tuple[float, float]:
    if abs(w) < 1e-9:
        return x + v * t * math.cos(th), y + v * t * math.sin(th)
    return (
        x + v / w * (math.sin(th + w * t) - math.sin(th)),
        y - v / w * (math.cos(th + w * t) - math.cos(th)),
    )  # pragma: no cover - compiled


@numba.njit(cache=True)
def _evaluate(
    pose: FloatArray,
    v: float,
    w: float,
    obs: FloatArray,
    rad: FloatArray,
    reach0: FloatArray,
    radius: float,
    horizon: float,
    n_steps: int,
) -> tuple[float, float]:  # pragma: no cover - compiled
    """(clearance [m], distance before moving into contact [m]; inf if none).

    ``obs`` and ``rad`` sorted by ``reach0``, each obstacle's clearance from the arc's
    start (``|o - p0| - r_o``): a point of the arc ``s`` metres along it is at least
    ``reach0 - s - radius`` from an obstacle (triangle inequality; the chord is no
    longer than the arc), so the search of each point's nearest obstacle stops at the
    first whose bound exceeds the nearest found: the same minimum as the full search.
    """
    c0 = np.inf
    cmin = np.inf
    travel = np.inf
    for k in range(n_steps + 1):
        t = horizon * k / n_steps
        px, py = _arc_xy(pose[0], pose[1], pose[2], v, w, t)
        gone = abs(v) * t + radius + 1e-9  # how far the disc's edge can be from the start's
        c = np.inf
        for m in range(obs.shape[0]):
            if reach0[m] - gone > c:
                break
            d = math.hypot(obs[m, 0] - px, obs[m, 1] - py) - rad[m] - radius
            c = min(c, d)
        if k == 0:
            c0 = c
        cmin = min(cmin, c)
        if c < 0.0 and c < c0 - 1e-9 and travel == np.inf:
            travel = max(v * horizon * (k - 1) / n_steps, 0.0)
    return cmin, travel


@numba.njit(cache=True)
def _score(
    v: float,
    w: float,
    c: float,
    v_ref: float,
    w_ref: float,
    v_max: float,
    w_max: float,
    c_cap: float,
    c_weight: float,
) -> float:  # pragma: no cover - compiled
    """An admissible candidate's score: nearness to the reference, and its clearance
    ``c`` [m] up to ``c_cap``."""
    return float(
        -(((v - v_ref) / v_max) ** 2)
        - ((w - w_ref) / w_max) ** 2
        + c_weight * min(c, c_cap) / c_cap
    )


@numba.njit(cache=True)
def _dwa_one(
    pose: FloatArray,
    v0: float,
    w0: float,
    v_ref: float,
    w_ref: float,
    obs: FloatArray,
    rad: FloatArray,
    dt: float,
    vw: float,
    aw: float,
    axle: float,
    radius: float,
    horizon: float,
    n_v: int,
    n_w: int,
    n_steps: int,
    c_cap: float,
    c_weight: float,
    turn: bool,
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    half = axle / 2.0
    v_max = vw
    w_max = vw / half
    # the last command, clipped into the speed limits (v >= 0, |v| + |w| L/2 <= v_w)
    v0 = min(max(v0, 0.0), v_max)
    w_lim = (vw - v0) / half
    w0 = min(max(w0, -w_lim), w_lim)
    da = aw * dt
    v_lo = max(0.0, v0 - da)
    v_hi = min(v_max, v0 + da)
    # the reference projected into the window: speed first, then turn rate
    vr = min(max(v_ref, v_lo), v_hi)
    b = (da - abs(vr - v0)) / half
    lim = (vw - vr) / half
    lo = max(w0 - b, -lim)
    hi = min(w0 + b, lim)
    if lo > hi:
        vr = v0
        b = da / half
        lim = (vw - vr) / half
        lo = max(w0 - b, -lim)
        hi = min(w0 + b, lim)
    wr = min(max(w_ref, lo), hi)
    # the obstacles nearest the start first (see _evaluate)
    reach = np.empty(obs.shape[0])
    for m in range(obs.shape[0]):
        reach[m] = math.hypot(obs[m, 0] - pose[0], obs[m, 1] - pose[1]) - rad[m]
    order = np.argsort(reach, kind="mergesort")
    obs = obs[order]
    rad = rad[order]
    reach = reach[order]
    best = -np.inf
    best_v = v_lo
    best_w = w0
    best_c = -np.inf
    fb_score = -np.inf
    fb_v = v_lo
    fb_w = w0
    fb_c = -np.inf
    moving = False  # an admissible command with v > 0
    for iv in range(n_v + 1):
        if iv < n_v:
            v = v_lo + (v_hi - v_lo) * iv / (n_v - 1)
            b = (da - abs(v - v0)) / half
            lim = (vw - v) / half
            lo = max(w0 - b, -lim)
            hi = min(w0 + b, lim)
            if lo > hi + 1e-12:
                continue
            count = n_w
        else:
            v = vr
            count = 1
        for iw in range(count):
            w = (lo + (hi - lo) * iw / (count - 1) if hi > lo else lo) if iv < n_v else wr
            c, travel = _evaluate(pose, v, w, obs, rad, reach, radius, horizon, n_steps)
            if travel != np.inf and v > math.sqrt(2.0 * aw * travel) + 1e-12:
                # inadmissible; remembered in case nothing is: the slowest, then the
                # clearest
                fallback = -v * 1e6 + min(c, 1e3)
                if fallback > fb_score:
                    fb_score = fallback
                    fb_v = v
                    fb_w = w
                    fb_c = c
                continue
            score = _score(v, w, c, v_ref, w_ref, v_max, w_max, c_cap, c_weight)
            if score > best:
                best = score
                best_v = v
                best_w = w
                best_c = c
            if v > 0.0:
                moving = True
    if turn and not moving and v_lo == 0.0:
        # a stuck robot with no speed admissible, only turns in place: the asked turn,
        # clipped into the window, is tried too (``dwa_command``'s ``stuck``)
        b = (da - v0) / half  # the window's turn rates at v = 0 (v0 <= da here)
        w = min(max(w_ref, max(w0 - b, -w_max)), min(w0 + b, w_max))
        c, _ = _evaluate(pose, 0.0, w, obs, rad, reach, radius, horizon, n_steps)
        score = _score(0.0, w, c, v_ref, w_ref, v_max, w_max, c_cap, c_weight)
        if score > best:
            best = score
            best_v = 0.0
            best_w = w
            best_c = c
    if best == -np.inf:  # nothing admissible: brake as hard as the window allows
        return fb_v, fb_w, fb_c
    return best_v, best_w, best_c


@numba.njit(cache=True)
def _dwa_batch(
    pose: FloatArray,
    last: FloatArray,
    ref: FloatArray,
    obs: FloatArray,
    rad: FloatArray,
    dt: float,
    vw: float,
    aw: float,
    axle: float,
    radius: float,
    horizon: float,
    n_v: int,
    n_w: int,
    n_steps: int,
    c_cap: float,
    c_weight: float,
    turn: BoolArray,
) -> FloatArray:  # pragma: no cover - compiled
    out = np.empty((pose.shape[0], 3))
    for i in range(pose.shape[0]):
        v, w, c = _dwa_one(
            pose[i],
            last[i, 0],
            last[i, 1],
            ref[i, 0],
            ref[i, 1],
            obs[i],
            rad[i],
            dt,
            vw,
            aw,
            axle,
            radius,
            horizon,
            n_v,
            n_w,
            n_steps,
            c_cap,
            c_weight,
            bool(turn[i]),
        )
        out[i, 0] = v
        out[i, 1] = w
        out[i, 2] = c
    return out


def dwa_command(
    pose: ArrayLike,
    last_command: ArrayLike,
    reference: ArrayLike,
    obstacles_m: ArrayLike,
    obstacle_radius_m: ArrayLike,
    params: DwaParams,
    dt_s: float,
    stuck: ArrayLike | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Safe velocities for a team: each robot's reference bent around its obstacles.

    Parameters
    ----------
    pose : array_like, shape (N, 3)
        x [m], y [m], heading [rad].
    last_command : array_like, shape (N, 2)
        The previous command ``(v [m/s], omega [rad/s])``: the window's centre.
    reference : array_like, shape (N, 2)
        The desired command (the path follower's).
    obstacles_m : array_like, shape (N, M, 2)
        World points each robot must avoid [m] (pad with far points, e.g. 1e9).
    obstacle_radius_m : array_like, shape (N, M)
        Their radii [m] (0 for a range return, a teammate's radius for a teammate).
    params : DwaParams
    dt_s : float
        The control period [s]: the window is what the wheels reach in it.
    stuck : array_like of bool, shape (N,), optional
        Robots that have made no progress for a while (the navigation's stuck
        detector). One of them for which no speed is admissible, only turns in place,
        also tries the reference's turn rate clipped into the window: the grid's turn
        rates lie ``4 a dt / (L (n_omega - 1))`` apart (0.625 rad/s in the mission's
        window) and may score within a hair of each other, so a robot touching a door's
        jamb held the one nearest its last turn and never turned towards its path
        (apartment seed 3: 240 s). Default: none.

    Returns
    -------
    v_m_s, omega_rad_s : ndarray, shape (N,)
        The chosen command, inside the dynamic window.
    clearance_m : ndarray, shape (N,)
        The chosen arc's clearance [m] (``inf`` with no obstacle).

    Examples
    --------
    >>> import numpy as np
    >>> p = DwaParams()
    >>> far = np.full((1, 1, 2), 1e9)
    >>> v, w, c = dwa_command([[0, 0, 0]], [[0.3, 0.0]], [[0.3, 0.2]], far, [[0.0]], p, 0.1)
    >>> float(v[0]), float(w[0])  # nothing near: the reference, untouched
    (0.3, 0.2)
    >>> wall = np.array([[[0.35, 0.0]]])  # a point straight ahead, 0.2 m from the disc
    >>> v, w, c = dwa_command([[0, 0, 0]], [[0.3, 0.0]], [[0.3, 0.0]], wall, [[0.0]], p, 0.1)
    >>> bool(v[0] < 0.3), bool(c[0] > 0.0)  # slows down and bends away, no contact
    (True, True)
    """
    p = as_float_array(pose, "pose", (None, 3))
    n = p.shape[0]
    last = as_float_array(last_command, "last_command", (n, 2))
    ref = as_float_array(reference, "reference", (n, 2))
    obs = np.ascontiguousarray(np.asarray(obstacles_m, dtype=float))
    rad = np.ascontiguousarray(np.asarray(obstacle_radius_m, dtype=float))
    if obs.ndim != 3 or obs.shape[0] != n or obs.shape[2] != 2 or rad.shape != obs.shape[:2]:
        raise InputError(
            f"obstacles_m must be (N, M, 2) and obstacle_radius_m (N, M) with N = {n}, "
            f"got {obs.shape} and {rad.shape}"
        )
    if not (math.isfinite(dt_s) and dt_s > 0.0):
        raise InputError(f"dt_s must be > 0, got {dt_s!r}")
    obs = np.where(np.isfinite(obs), obs, 1e9)
    turn = np.zeros(n, dtype=bool) if stuck is None else np.asarray(stuck, dtype=bool)
    if turn.shape != (n,):
        raise InputError(f"stuck must be (N,) with N = {n}, got shape {turn.shape}")
    out = _dwa_batch(
        p,
        last,
        ref,
        obs,
        rad,
        float(dt_s),
        params.wheel_speed_max_m_s,
        params.wheel_accel_m_s2,
        params.axle_length_m,
        params.robot_radius_m,
        params.horizon_s,
        params.n_v,
        params.n_omega,
        params.n_steps,
        params.clearance_cap_m,
        params.clearance_weight,
        turn,
    )
    return out[:, 0].copy(), out[:, 1].copy(), out[:, 2].copy()


def in_window(
    command: ArrayLike, last_command: ArrayLike, params: DwaParams, dt_s: float
) -> BoolArray:
    """Whether commands (N, 2) lie in the dynamic window around ``last_command`` (N, 2)."""
    c = np.asarray(command, dtype=float)
    last = np.asarray(last_command, dtype=float)
    half = params.axle_length_m / 2.0
    step = np.abs(c[:, 0] - last[:, 0]) + np.abs(c[:, 1] - last[:, 1]) * half
    speed = np.abs(c[:, 0]) + np.abs(c[:, 1]) * half
    tol = 1e-9
    return np.asarray(
        (step <= params.wheel_accel_m_s2 * dt_s + tol)
        & (speed <= params.wheel_speed_max_m_s + tol)
        & (c[:, 0] >= -tol)
    )
