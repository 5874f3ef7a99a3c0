"""Discrete PID speed controller for every wheel of the team at once.

The low-level loop of the deliverable (section 2.4, Figure 9; results in 2.6.4.1,
Figure 25): each wheel motor's voltage is set so that its measured speed tracks the
reference from the high-level controller.

The law, in the parallel form with setpoint weighting (a two-degree-of-freedom PID,
Astrom and Hagglund, *Advanced PID Control*, 2006, sec. 3.4)::

    u = kp (b r - y) + I + D,          u_sat = clip(u, -u_max, u_max)
    I <- I + ki dt (r - y) + dt (u_sat - u) / T_t          (back-calculation anti-windup)
    D = -kd s / (1 + T_f s) y   (filtered derivative of the measurement, backward Euler)

The derivative acts on the measurement, not the error, so a reference step gives no
derivative kick; ``b < 1`` softens the proportional kick of a step while the integral
(which sees the full error) still removes every steady error and load.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError, check_fields

__all__ = ["PidParams", "PidState", "pid_init", "pid_step", "pid_step_one"]

PidGains = tuple[float, float, float, float, float, float, float]
"""kp, ki, kd, derivative_filter_s, setpoint_weight, tracking_time_s, output_limit."""


@dataclass(frozen=True)
class PidParams:
    """Gains and limits of the speed PID (defaults: the Table 2 motor at dt = 0.01 s).

    The defaults were chosen for the Table 2 motor (poles at -5.5 and -71.7 rad/s), a
    2048-count encoder whose counts are differenced over 20 ms, read every 10 ms, a
    12 V supply and a 0.5 N m load step, by searching a grid of
    gains for the smallest worst case, over 32 random encoder phases, of the four
    ratios rise time / 0.2 s, settling time / 0.5 s, overshoot / 5 % and load
    recovery / 0.5 s (the deliverable's and the foundation issue's bounds):

    - ``kp = 2.5 V s/rad`` and ``ki = 25 V/rad`` put the integral zero at
      ki / kp = 10 rad/s, a little faster than the slow mechanical pole (5.5 rad/s):
      cancelling that pole exactly would leave a 0.18 s tail in the response to a load
      torque, too slow to recover within 0.5 s; a larger kp amplifies the encoder's
      quantisation (one count in 20 ms is 0.15 rad/s, so kp = 2.5 turns it into
      0.38 V of chatter, which the 0.18 s mechanical time constant filters to well
      inside the 2 % band).
    - ``kd = 0.005 V s^2/rad`` with ``T_f = 0.01 s``: a small, filtered derivative adds
      damping to the loop; a larger one only differentiates quantisation noise (the
      filter caps its high-frequency gain at kd / T_f = 0.5 V s/rad).

    Worst case of that search: rise time 0.10 s, settling time 0.24 s, overshoot 3.2 %,
    recovery 0.28 s (all at most 0.64 of their bounds).
    - ``setpoint_weight = 0.5`` keeps the overshoot of a speed step near 2 %.
    - ``tracking_time_s = 0.1`` (about sqrt(Ti Td) rounded up) unwinds the integral
      within a few steps when the voltage saturates.

    Attributes
    ----------
    kp : float
        Proportional gain [V s/rad].
    ki : float
        Integral gain [V/rad].
    kd : float
        Derivative gain [V s^2/rad].
    derivative_filter_s : float
        Time constant T_f of the derivative's first-order filter [s], > 0.
    setpoint_weight : float
        b, the share of the reference in the proportional term, in [0, 1].
    tracking_time_s : float
        Back-calculation time constant T_t of the anti-windup [s], > 0.
    output_limit : float
        Output saturation |u| <= output_limit (the motor supply voltage) [V].

    Examples
    --------
    >>> from firefleet.control.pid import PidParams
    >>> p = PidParams()
    >>> p.ki / p.kp
    10.0
    >>> len(p.gains)
    7
    """

    kp: float = 2.5
    ki: float = 25.0
    kd: float = 0.005
    derivative_filter_s: float = 0.01
    setpoint_weight: float = 0.5
    tracking_time_s: float = 0.1
    output_limit: float = 12.0

    def __post_init__(self) -> None:
        check_fields(
            self,
            "speed_pid",
            positive=("derivative_filter_s", "tracking_time_s", "output_limit"),
            non_negative=("kp", "ki", "kd"),
        )
        if not 0.0 <= self.setpoint_weight <= 1.0:
            raise InputError(
                f"speed_pid.setpoint_weight must be in [0, 1], got {self.setpoint_weight}"
            )

    @property
    def gains(self) -> PidGains:
        """The seven numbers :func:`pid_step_one` takes, in its order (:data:`PidGains`)."""
        return (
            float(self.kp),
            float(self.ki),
            float(self.kd),
            float(self.derivative_filter_s),
            float(self.setpoint_weight),
            float(self.tracking_time_s),
            float(self.output_limit),
        )


@dataclass(frozen=True)
class PidState:
    """PID memory for controllers of shape S (``(N, 2)`` for a team).

    Attributes
    ----------
    integral : ndarray, shape S
        Integral term I [V].
    derivative : ndarray, shape S
        Filtered derivative term D [V].
    last_measurement : ndarray, shape S
        The previous measurement y [rad/s].

    Examples
    --------
    >>> from firefleet.control.pid import pid_init
    >>> s = pid_init([[1.0, 2.0]])
    >>> s.integral.tolist(), s.last_measurement.tolist()
    ([[0.0, 0.0]], [[1.0, 2.0]])
    """

    integral: FloatArray
    derivative: FloatArray
    last_measurement: FloatArray


def pid_init(measurement: ArrayLike) -> PidState:
    """Controller memory at rest, with ``measurement`` as the previous measurement.

    Examples
    --------
    >>> from firefleet.control.pid import pid_init
    >>> s = pid_init([0.0, 5.0])
    >>> s.derivative.tolist(), s.last_measurement.tolist()
    ([0.0, 0.0], [0.0, 5.0])
    """
    y = np.array(measurement, dtype=np.float64)
    return PidState(integral=np.zeros_like(y), derivative=np.zeros_like(y), last_measurement=y)


def pid_step(
    state: PidState,
    reference: ArrayLike,
    measurement: ArrayLike,
    params: PidParams,
    dt_s: float,
) -> tuple[PidState, FloatArray]:
    """One control period for every controller.

    Parameters
    ----------
    state : PidState
    reference : array_like, broadcastable to S
        Speed reference r [rad/s].
    measurement : array_like, shape S
        Measured speed y [rad/s] (from the encoder).
    params : PidParams
    dt_s : float
        Control period [s].

    Returns
    -------
    state : PidState
        The memory for the next period.
    output : ndarray, shape S
        Saturated output u_sat [V], to be held over the period.

    Examples
    --------
    >>> from firefleet.control.pid import PidParams, pid_init, pid_step
    >>> p = PidParams(kp=2.0, ki=10.0, kd=0.0, setpoint_weight=1.0)
    >>> state, u = pid_step(pid_init([0.0]), [3.0], [0.0], p, 0.01)
    >>> u.tolist(), state.integral.round(4).tolist()
    ([6.0], [0.3])
    >>> pid_step(pid_init([0.0]), [100.0], [0.0], p, 0.01)[1].tolist()
    [12.0]
    """
    r = np.asarray(reference, dtype=np.float64)
    y = np.asarray(measurement, dtype=np.float64)
    tf = params.derivative_filter_s
    d = (tf * state.derivative - params.kd * (y - state.last_measurement)) / (tf + dt_s)
    u = params.kp * (params.setpoint_weight * r - y) + state.integral + d
    u_sat = np.clip(u, -params.output_limit, params.output_limit)
    integral = state.integral + dt_s * (params.ki * (r - y) + (u_sat - u) / params.tracking_time_s)
    return PidState(integral=integral, derivative=d, last_measurement=y.copy()), u_sat


@numba.njit(cache=True)
def pid_step_one(
    integral: float,
    derivative: float,
    last_measurement: float,
    reference: float,
    measurement: float,
    gains: PidGains,
    dt_s: float,
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """:func:`pid_step` of one controller, compiled (numba) for the simulator's kernels.

    The same operations in the same order as the array form, the clip written as two
    comparisons: the same result bit for bit (tests/control/test_pid.py).

    Parameters
    ----------
    integral, derivative, last_measurement : float
        The controller's memory (:class:`PidState`'s fields) [V], [V], [rad/s].
    reference, measurement : float
        r and y of this period [rad/s].
    gains : tuple of 7 float
        :attr:`PidParams.gains`.
    dt_s : float
        Control period [s].

    Returns
    -------
    integral, derivative, output : float
        The new integral and filtered derivative [V] (the new last measurement is
        ``measurement``) and the saturated output u_sat [V].

    Examples
    --------
    >>> from firefleet.control.pid import PidParams, pid_init, pid_step, pid_step_one
    >>> p = PidParams()
    >>> integral, derivative, u = pid_step_one(0.0, 0.0, 0.0, 10.0, 1.0, p.gains, 0.01)
    >>> u == float(pid_step(pid_init(0.0), 10.0, 1.0, p, 0.01)[1])
    True
    """
    kp, ki, kd, tf, b, tt, lim = gains
    d = (tf * derivative - kd * (measurement - last_measurement)) / (tf + dt_s)
    u = kp * (b * reference - measurement) + integral + d
    u_sat = -lim if u < -lim else (lim if u > lim else u)
    new_integral = integral + dt_s * (ki * (reference - measurement) + (u_sat - u) / tt)
    return new_integral, d, u_sat
