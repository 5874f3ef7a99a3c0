"""Permanent-magnet DC motor with exact zero-order-hold discretisation.

The electrical and mechanical equations (deliverable Table 2 parameters)::

    L di/dt = V - R i - Ke w
    J dw/dt = Kt i - B w - tau_load

with state ``x = (i, w)`` (current [A], shaft speed [rad/s]) and input
``u = (V, tau_load)`` (voltage [V], load torque [N m]). The shaft angle ``phi`` with
``dphi/dt = w`` is carried along in the discretisation so the angle turned during a
step is exact too (the encoder and the kinematics need it).

The electrical time constant of the Table 2 motor is about 14 ms, the step 10 ms:
explicit Euler would be wrong, so the step uses ``expm`` of the augmented matrix
(Van Loan), exact for inputs held constant over the step.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numba
import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError, check_fields

__all__ = ["DiscreteMotor", "MotorParams", "discretise_motor", "motor_step", "motor_step_one"]

MotorCoefficients = tuple[
    float, float, float, float, float, float, float, float, float, float, float, float
]
"""The twelve numbers of a :class:`DiscreteMotor` for :func:`motor_step_one`."""


@dataclass(frozen=True)
class MotorParams:
    """DC motor parameters (deliverable Table 2).

    Attributes
    ----------
    resistance_ohm : float
        Armature resistance R [ohm].
    inductance_h : float
        Armature inductance L [H]. Table 2 prints the unit "mh" next to 0.04; 0.04 H
        is the value that gives the deliverable's Figure 24 (a 40 uH armature would
        make the current peak 30 times sharper than the figure shows).
    inertia_kg_m2 : float
        Rotor plus reflected load inertia J [kg m^2].
    damping_n_m_s : float
        Viscous friction B [N m s/rad].
    back_emf_v_s : float
        Back-EMF constant Ke [V s/rad].
    torque_n_m_a : float
        Torque constant Kt [N m/A].
    supply_v : float
        Supply voltage [V]: the limit of the speed controller's output.

    Examples
    --------
    >>> from firefleet.models import MotorParams
    >>> p = MotorParams()
    >>> round(p.speed_gain_rad_s_per_v, 4)
    1.3955
    >>> current_a, speed_rad_s = p.steady_state(12.0)
    >>> round(speed_rad_s, 4), round(12.0 * p.speed_gain_rad_s_per_v, 4)
    (16.7459, 16.7459)
    """

    resistance_ohm: float = 3.07
    inductance_h: float = 0.04
    inertia_kg_m2: float = 0.0294
    damping_n_m_s: float = 0.0141
    back_emf_v_s: float = 0.65
    torque_n_m_a: float = 0.65
    supply_v: float = 12.0

    def __post_init__(self) -> None:
        check_fields(
            self,
            "motor",
            positive=(
                "resistance_ohm",
                "inductance_h",
                "inertia_kg_m2",
                "back_emf_v_s",
                "torque_n_m_a",
                "supply_v",
            ),
            non_negative=("damping_n_m_s",),
        )

    @property
    def a_matrix(self) -> FloatArray:
        """Continuous state matrix A (2, 2) of ``dx/dt = A x + B u``, x = (i, w)."""
        R, L, J = self.resistance_ohm, self.inductance_h, self.inertia_kg_m2
        return np.array(
            [[-R / L, -self.back_emf_v_s / L], [self.torque_n_m_a / J, -self.damping_n_m_s / J]]
        )

    @property
    def b_matrix(self) -> FloatArray:
        """Continuous input matrix B (2, 2), u = (V, tau_load)."""
        return np.array([[1.0 / self.inductance_h, 0.0], [0.0, -1.0 / self.inertia_kg_m2]])

    @property
    def speed_gain_rad_s_per_v(self) -> float:
        """Steady speed per volt with no load, Kt / (R B + Ke Kt) [rad/s/V]."""
        return self.torque_n_m_a / (
            self.resistance_ohm * self.damping_n_m_s + self.back_emf_v_s * self.torque_n_m_a
        )

    @property
    def time_constants_s(self) -> tuple[float, float]:
        """The two time constants -1/lambda of A, slow (mechanical) first [s]."""
        eig = np.linalg.eigvals(self.a_matrix)
        if np.any(np.abs(eig.imag) > 0):
            raise InputError("motor is underdamped: its poles are complex, no real time constants")
        taus = sorted((-1.0 / eig.real).tolist(), reverse=True)
        return float(taus[0]), float(taus[1])

    def steady_state(self, voltage_v: float, load_torque_n_m: float = 0.0) -> tuple[float, float]:
        """Steady current [A] and speed [rad/s] for a constant voltage and load."""
        x = np.linalg.solve(self.a_matrix, -self.b_matrix @ np.array([voltage_v, load_torque_n_m]))
        return float(x[0]), float(x[1])


@dataclass(frozen=True)
class DiscreteMotor:
    """Exact zero-order-hold discretisation of :class:`MotorParams` at step ``dt_s``.

    ``x[k+1] = ad @ x[k] + bd @ u[k]`` and the angle turned during the step
    ``dphi = c_ad @ x[k] + c_bd @ u[k]``.

    Examples
    --------
    >>> from firefleet.models import MotorParams, discretise_motor
    >>> m = discretise_motor(MotorParams(), 0.01)
    >>> m.ad.shape, m.bd.shape, m.c_ad.shape, m.c_bd.shape
    ((2, 2), (2, 2), (2,), (2,))
    """

    params: MotorParams
    dt_s: float
    ad: FloatArray = field(repr=False)
    bd: FloatArray = field(repr=False)
    c_ad: FloatArray = field(repr=False)
    c_bd: FloatArray = field(repr=False)

    @property
    def coefficients(self) -> MotorCoefficients:
        """``ad`` (row by row), ``bd`` (row by row), ``c_ad``, ``c_bd``: 12 floats.

        What :func:`motor_step_one` takes (a tuple of floats passes into compiled code
        by value, without the reference counting of arrays).
        """
        a, b, c, d = self.ad, self.bd, self.c_ad, self.c_bd
        return (
            float(a[0, 0]),
            float(a[0, 1]),
            float(a[1, 0]),
            float(a[1, 1]),
            float(b[0, 0]),
            float(b[0, 1]),
            float(b[1, 0]),
            float(b[1, 1]),
            float(c[0]),
            float(c[1]),
            float(d[0]),
            float(d[1]),
        )


@functools.lru_cache(maxsize=64)
def discretise_motor(params: MotorParams, dt_s: float) -> DiscreteMotor:
    """Discretise the motor exactly for inputs held over ``dt_s`` (zero-order hold).

    Parameters
    ----------
    params : MotorParams
        The motor.
    dt_s : float
        Step [s], > 0.

    Returns
    -------
    DiscreteMotor
        Matrices for :func:`motor_step`.

    Notes
    -----
    Cached per (params, dt_s): the result is immutable, and ``expm`` is the costliest
    part of a short run. Van Loan's method: with the shaft angle appended to the state
    (``dphi/dt = w``), ``expm([[A3, B3], [0, 0]] dt) = [[Ad3, Bd3], [0, I]]``.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.models import MotorParams, discretise_motor
    >>> p = MotorParams()
    >>> m = discretise_motor(p, 10.0)
    >>> x_inf = np.linalg.solve(np.eye(2) - m.ad, m.bd @ [12.0, 0.0])
    >>> np.allclose(x_inf, p.steady_state(12.0))
    True
    """
    if not (np.isfinite(dt_s) and dt_s > 0):
        raise InputError(f"dt_s must be > 0, got {dt_s}")
    m = np.zeros((5, 5))
    m[:2, :2] = params.a_matrix
    m[:2, 3:] = params.b_matrix
    m[2, 1] = 1.0  # dphi/dt = w
    e = scipy.linalg.expm(m * dt_s)
    blocks = [e[:2, :2].copy(), e[:2, 3:].copy(), e[2, :2].copy(), e[2, 3:].copy()]
    for block in blocks:
        block.flags.writeable = False  # shared by every caller through the cache
    return DiscreteMotor(
        params=params, dt_s=float(dt_s), ad=blocks[0], bd=blocks[1], c_ad=blocks[2], c_bd=blocks[3]
    )


def motor_step(
    current_a: ArrayLike,
    speed_rad_s: ArrayLike,
    voltage_v: ArrayLike,
    load_torque_n_m: ArrayLike,
    motor: DiscreteMotor,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Advance every motor one step with voltage and load held constant.

    Parameters
    ----------
    current_a, speed_rad_s : array_like, shape (...)
        State: armature current [A] and shaft speed [rad/s], any common shape
        (``(N, 2)`` for a team: right, left wheel).
    voltage_v, load_torque_n_m : array_like, broadcastable to the state's shape
        Inputs held over the step: voltage [V] and load torque [N m].
    motor : DiscreteMotor
        From :func:`discretise_motor`.

    Returns
    -------
    current_a, speed_rad_s : ndarray
        State after the step.
    dphi_rad : ndarray
        Angle turned during the step [rad], exact.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.models import MotorParams, discretise_motor, motor_step
    >>> p = MotorParams()
    >>> m = discretise_motor(p, 5.0)
    >>> i, w, dphi = motor_step(np.zeros(2), np.zeros(2), 12.0, 0.0, m)
    >>> np.round(w, 3).tolist(), round(p.steady_state(12.0)[1], 3)
    ([16.746, 16.746], 16.746)
    """
    i = np.asarray(current_a, dtype=np.float64)
    w = np.asarray(speed_rad_s, dtype=np.float64)
    v = np.asarray(voltage_v, dtype=np.float64)
    tl = np.asarray(load_torque_n_m, dtype=np.float64)
    ad, bd, cad, cbd = motor.ad, motor.bd, motor.c_ad, motor.c_bd
    i_next = ad[0, 0] * i + ad[0, 1] * w + bd[0, 0] * v + bd[0, 1] * tl
    w_next = ad[1, 0] * i + ad[1, 1] * w + bd[1, 0] * v + bd[1, 1] * tl
    dphi = cad[0] * i + cad[1] * w + cbd[0] * v + cbd[1] * tl
    return i_next, w_next, dphi


@numba.njit(cache=True)
def motor_step_one(
    current_a: float,
    speed_rad_s: float,
    voltage_v: float,
    load_torque_n_m: float,
    coefficients: MotorCoefficients,
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """:func:`motor_step` of one motor, compiled (numba) for the simulator's kernels.

    The same products summed in the same order as the array form: the same result bit
    for bit (tests/models/test_motor.py).

    Parameters
    ----------
    current_a, speed_rad_s : float
        State: armature current [A] and shaft speed [rad/s].
    voltage_v, load_torque_n_m : float
        Inputs held over the step: voltage [V] and load torque [N m].
    coefficients : tuple of 12 float
        :attr:`DiscreteMotor.coefficients`.

    Returns
    -------
    current_a, speed_rad_s, dphi_rad : float
        State after the step and the angle turned during it [rad].
    """
    a00, a01, a10, a11, b00, b01, b10, b11, c0, c1, d0, d1 = coefficients
    i, w, v, tl = current_a, speed_rad_s, voltage_v, load_torque_n_m
    return (
        a00 * i + a01 * w + b00 * v + b01 * tl,
        a10 * i + a11 * w + b10 * v + b11 * tl,
        c0 * i + c1 * w + d0 * v + d1 * tl,
    )
