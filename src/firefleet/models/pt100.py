"""PT100 air-temperature probe: the sheath's first-order lag, the Callendar-Van Dusen
resistance, and the MAX31865 converter's 15-bit reading.

The deliverable's robot carries a PT100 "to measure the outer temperature" (section
2.7.2.7). A platinum resistance thermometer is three things in a row, each modelled as
the device works:

1. the probe's sheath takes the air's temperature with a first-order lag of time
   constant ``tau`` (a 3 mm sheathed probe in moving air: about 10 s; IEC 60751 asks
   it be stated, and manufacturers give 5-30 s in air at 1-3 m/s)::

       T_probe(t + dt) = T_air + (T_probe(t) - T_air) exp(-dt / tau)

   (exact for air constant over the step);
2. platinum's resistance at the probe's temperature, the Callendar-Van Dusen equation
   with IEC 60751's coefficients (R0 = 100 ohm):
   ``R = R0 (1 + A t + B t^2 + C (t - 100) t^3)``, the C term below 0 C only;
3. the converter: a MAX31865 (the usual PT100 front end of an Arduino or Raspberry Pi)
   gives ``code = floor(2^15 R / R_ref)`` with ``R_ref`` = 430 ohm, a step of 0.0131 ohm
   (about 0.034 C); the reading is the inverse Callendar-Van Dusen of the code's
   resistance.

The probe's temperature is physics (heat flowing into the sheath) and is stepped with
the world; the reading is the sensor's.
The robot's adapter for the real converter (:mod:`firefleet.robot`, SPI) reads its codes
through the same Callendar-Van Dusen functions.

References
----------
IEC 60751:2022, Industrial platinum resistance thermometers and platinum temperature
sensors (the coefficients and the R(t) table). Maxim Integrated, MAX31865 RTD-to-Digital
Converter data sheet, rev. 5 (2015): the ADC code and R_ref.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError

__all__ = [
    "Pt100Params",
    "pt100_read",
    "pt100_resistance_ohm",
    "pt100_step",
    "pt100_temperature_c",
]

A = 3.9083e-3
"""IEC 60751 Callendar-Van Dusen coefficient A [1/C]."""
B = -5.775e-7
"""IEC 60751 Callendar-Van Dusen coefficient B [1/C^2]."""
C = -4.183e-12
"""IEC 60751 Callendar-Van Dusen coefficient C [1/C^4] (below 0 C only)."""
R0_OHM = 100.0
"""A PT100's resistance at 0 C [ohm]."""


@dataclass(frozen=True)
class Pt100Params:
    """A PT100 probe read by a MAX31865.

    Attributes
    ----------
    time_constant_s : float
        The sheath's first-order time constant in air [s] (> 0).
    ref_ohm : float
        The converter's reference resistor [ohm] (430 on the usual PT100 boards).
    adc_bits : int
        The converter's resolution (15 for the MAX31865); 0: an ideal reading.

    Examples
    --------
    >>> from firefleet.models.pt100 import Pt100Params
    >>> round(Pt100Params().resolution_ohm, 5)
    0.01312
    """

    time_constant_s: float = 10.0
    ref_ohm: float = 430.0
    adc_bits: int = 15

    def __post_init__(self) -> None:
        if not self.time_constant_s > 0.0:
            raise InputError(
                f"sensors.pt100.time_constant_s: expected > 0, got {self.time_constant_s}"
            )
        if not self.ref_ohm > 0.0:
            raise InputError(f"sensors.pt100.ref_ohm: expected > 0, got {self.ref_ohm}")
        if not 0 <= self.adc_bits <= 24:
            raise InputError(f"sensors.pt100.adc_bits: expected 0 to 24, got {self.adc_bits}")

    @property
    def resolution_ohm(self) -> float:
        """One converter step [ohm] (0 for an ideal reading)."""
        return self.ref_ohm / 2.0**self.adc_bits if self.adc_bits else 0.0


def pt100_resistance_ohm(t_c: ArrayLike) -> FloatArray:
    """Platinum's resistance at ``t_c`` (IEC 60751 Callendar-Van Dusen).

    Parameters
    ----------
    t_c : array_like, shape (...)
        Temperature [C], -200 to 850.

    Returns
    -------
    ndarray, shape (...)
        Resistance [ohm].

    Examples
    --------
    >>> from firefleet.models.pt100 import pt100_resistance_ohm
    >>> [round(float(r), 2) for r in pt100_resistance_ohm([-100.0, 0.0, 100.0, 300.0])]
    [60.26, 100.0, 138.51, 212.05]
    """
    t = np.asarray(t_c, dtype=float)
    cold = np.where(t < 0.0, C * (t - 100.0) * t**3, 0.0)
    r: FloatArray = R0_OHM * (1.0 + A * t + B * t * t + cold)
    return r


def pt100_temperature_c(r_ohm: ArrayLike) -> FloatArray:
    """The temperature whose PT100 resistance is ``r_ohm`` (the inverse of
    :func:`pt100_resistance_ohm`).

    At and above 100 ohm (0 C) the quadratic's root; below it, Newton's iterations on the
    full equation from that root (converged to 1e-9 C in a few).

    Parameters
    ----------
    r_ohm : array_like, shape (...)
        Resistance [ohm].

    Returns
    -------
    ndarray, shape (...)
        Temperature [C].

    Examples
    --------
    >>> from firefleet.models.pt100 import pt100_resistance_ohm, pt100_temperature_c
    >>> t = pt100_temperature_c(pt100_resistance_ohm([-150.0, 25.0, 600.0]))
    >>> [round(float(x), 9) for x in t]
    [-150.0, 25.0, 600.0]
    """
    r = np.asarray(r_ohm, dtype=float)
    t = (-A + np.sqrt(A * A - 4.0 * B * (1.0 - r / R0_OHM))) / (2.0 * B)
    cold = r < R0_OHM
    if np.any(cold):
        tc = t[cold]
        for _ in range(8):
            f = R0_OHM * (1.0 + A * tc + B * tc * tc + C * (tc - 100.0) * tc**3) - r[cold]
            df = R0_OHM * (A + 2.0 * B * tc + C * (4.0 * tc**3 - 300.0 * tc * tc))
            tc = tc - f / df
        t = np.array(t, dtype=float)
        t[cold] = tc
    out: FloatArray = np.asarray(t, dtype=float)
    return out


def pt100_step(
    probe_c: ArrayLike, air_c: ArrayLike, params: Pt100Params, dt_s: float
) -> FloatArray:
    """The probes' temperatures after ``dt_s`` in air at ``air_c`` (the sheath's lag).

    Parameters
    ----------
    probe_c : array_like, shape (N,)
        Each robot's probe temperature now [C].
    air_c : array_like, shape (N,)
        The air at each probe over the step [C].
    params : Pt100Params
    dt_s : float
        Step [s].

    Returns
    -------
    ndarray, shape (N,)
        The probes' temperatures [C].

    Examples
    --------
    >>> from firefleet.models.pt100 import Pt100Params, pt100_step
    >>> p = Pt100Params(time_constant_s=10.0)
    >>> round(float(pt100_step([20.0], [120.0], p, 10.0)[0]), 2)  # 1 - 1/e of the way
    83.21
    """
    probe = np.asarray(probe_c, dtype=float)
    air = np.asarray(air_c, dtype=float)
    decay = np.exp(-dt_s / params.time_constant_s)
    out: FloatArray = air + (probe - air) * decay
    return out


def pt100_read(probe_c: ArrayLike, params: Pt100Params) -> FloatArray:
    """What the converter reports for probes at ``probe_c``.

    Parameters
    ----------
    probe_c : array_like, shape (N,)
        The probes' temperatures [C].
    params : Pt100Params

    Returns
    -------
    ndarray, shape (N,)
        The readings [C]: the inverse Callendar-Van Dusen of the quantised resistance
        (the code saturates at the converter's full scale, ``ref_ohm``).

    Examples
    --------
    >>> from firefleet.models.pt100 import Pt100Params, pt100_read
    >>> round(float(pt100_read([25.0], Pt100Params())[0]), 2)  # within a step below
    24.99
    """
    r = pt100_resistance_ohm(probe_c)
    if params.adc_bits:
        full = 2**params.adc_bits
        code = np.clip(np.floor(r / params.ref_ohm * full), 0, full - 1)
        r = code * params.resolution_ohm
    return pt100_temperature_c(r)
