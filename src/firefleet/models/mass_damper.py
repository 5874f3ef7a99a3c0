"""Spring-mass-damper robot (deliverable section 2.2.3, eq. 5).

Each robot is a point mass driven by a planar force::

    M x'' + B x' = f_x - k_d x'
    M y'' + B y' = f_y - k_d y'

State ``(N, 4)``: x [m], y [m], vx [m/s], vy [m/s]; force ``(N, 2)`` [N]. The step is
exact for a force held over the step (each axis is the linear system
``v' = -c/M v + f/M`` with ``c = B + k_d``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError, as_float_array, check_fields

__all__ = ["MassDamperParams", "mass_damper_step"]


@dataclass(frozen=True)
class MassDamperParams:
    """Parameters of eq. 5.

    Attributes
    ----------
    mass_kg : float
        M [kg].
    damping_n_s_m : float
        B [N s/m].
    kd_n_s_m : float
        k_d [N s/m], the extra damping that shapes the transient response.

    Examples
    --------
    >>> from firefleet.models import MassDamperParams
    >>> MassDamperParams(mass_kg=2.0, damping_n_s_m=1.0, kd_n_s_m=3.0).time_constant_s
    0.5
    """

    mass_kg: float = 1.0
    damping_n_s_m: float = 1.0
    kd_n_s_m: float = 1.0

    def __post_init__(self) -> None:
        check_fields(self, "", positive=("mass_kg",), non_negative=("damping_n_s_m", "kd_n_s_m"))
        if self.damping_n_s_m + self.kd_n_s_m <= 0:
            raise InputError("damping_n_s_m + kd_n_s_m must be > 0")

    @property
    def time_constant_s(self) -> float:
        """Velocity time constant M / (B + k_d) [s]."""
        return self.mass_kg / (self.damping_n_s_m + self.kd_n_s_m)


def mass_damper_step(
    state: ArrayLike, force_n: ArrayLike, dt_s: float, params: MassDamperParams
) -> FloatArray:
    """Advance point-mass robots one step under forces held over the step (eq. 5).

    Parameters
    ----------
    state : array_like, shape (N, 4)
        x [m], y [m], vx [m/s], vy [m/s].
    force_n : array_like, shape (N, 2)
        f_x, f_y [N].
    dt_s : float
        Step [s].
    params : MassDamperParams

    Returns
    -------
    ndarray, shape (N, 4)
        State after the step.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.models import MassDamperParams, mass_damper_step
    >>> p = MassDamperParams(mass_kg=1.0, damping_n_s_m=1.0, kd_n_s_m=1.0)
    >>> s = mass_damper_step([[0.0, 0.0, 0.0, 0.0]], [[2.0, 0.0]], 100.0, p)
    >>> np.round(s[0, 2:], 4).tolist()
    [1.0, 0.0]
    """
    s = as_float_array(state, "state", (None, 4))
    f = as_float_array(force_n, "force_n", (s.shape[0], 2))
    tau = params.time_constant_s
    c = params.damping_n_s_m + params.kd_n_s_m
    decay = np.exp(-dt_s / tau)
    v0 = s[:, 2:]
    v_inf = f / c  # terminal velocity under the held force
    v1 = v_inf + (v0 - v_inf) * decay
    x1 = s[:, :2] + v_inf * dt_s + (v0 - v_inf) * tau * (1.0 - decay)
    return np.concatenate([x1, v1], axis=1)
