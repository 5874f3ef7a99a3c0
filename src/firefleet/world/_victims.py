"""People in the building: where they are, what they have breathed, whether they live.

A victim's survival clock is the fractional effective dose of ISO 13571 (Purser's FED
model), summed over the time it spends in heat and smoke; incapacitation, and with no
rescue death in this model, comes when a dose reaches 1:

* convective heat: ``dFED_heat/dt = 1 / t_I(T)`` with ``t_I = 5e7 T^-3.4`` min (T in deg C,
  lightly clothed), counted above 40 deg C only (below it the body copes for hours);
* asphyxiant gas: ``dFED_CO/dt = C_CO / 35,000`` per minute, ``C_CO`` in ppm. The world
  carries smoke as optical density K [1/m], not CO; with a flaming fire's mass optical
  density of soot (sigma_m = 7.6 m^2/g, Mulholland) and CO yield equal to the soot yield
  (both 0.01-0.1 g/g for well-ventilated furnishing fires, Tewarson), the CO mass
  concentration is ``K / sigma_m`` [g/m^3] and 1 g/m^3 of CO is 873 ppm at 25 deg C, so
  ``C_CO = 115 K`` ppm.

A body radiates at 37 deg C (the thermal camera sees it; :data:`BODY_C`).

References
----------
ISO 13571:2012, Life-threatening components of fire: guidelines for the estimation of
time to compromised tenability in fires.
D. A. Purser, "Assessment of hazards to occupants from smoke, toxic gases and heat",
SFPE Handbook of Fire Protection Engineering.
G. W. Mulholland, "Smoke production and properties", SFPE Handbook.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import BoolArray, FloatArray
from firefleet.errors import InputError, check_fields

__all__ = ["BODY_C", "VictimParams", "VictimState", "victim_dose_rate", "victim_step"]

BODY_C = 37.0
"""Body surface temperature a thermal camera sees [deg C] (skin under clothes, 33-37)."""


@dataclass(frozen=True)
class VictimParams:
    """Constants of the survival clock (module notes).

    Attributes
    ----------
    heat_threshold_c : float
        Air temperature below which heat adds no dose [deg C].
    co_ppm_per_od : float
        CO concentration per unit smoke optical density [ppm m].
    co_dose_ppm_min : float
        CO exposure that incapacitates [ppm min] (ISO 13571: 35,000).
    """

    heat_threshold_c: float = 40.0
    co_ppm_per_od: float = 115.0
    co_dose_ppm_min: float = 35_000.0

    def __post_init__(self) -> None:
        check_fields(self, "victims", positive=("co_ppm_per_od", "co_dose_ppm_min"))


@dataclass(frozen=True)
class VictimState:
    """The victims at one instant.

    Attributes
    ----------
    position_m : ndarray, shape (V, 2)
        Where each lies [m].
    dose : ndarray, shape (V,)
        Fractional effective dose so far (heat plus CO); >= 1: dead.
    """

    position_m: FloatArray
    dose: FloatArray

    @property
    def alive(self) -> BoolArray:
        """Whose dose is below 1, (V,)."""
        return np.asarray(self.dose < 1.0)


def victim_dose_rate(
    temperature_c: ArrayLike, smoke_od_m: ArrayLike, params: VictimParams
) -> FloatArray:
    """Dose per second at the given air temperatures and smoke densities [1/s].

    Examples
    --------
    >>> from firefleet.world import VictimParams, victim_dose_rate
    >>> rate = victim_dose_rate([20.0, 100.0, 20.0], [0.0, 0.0, 2.0], VictimParams())
    >>> [round(1.0 / r / 60.0, 1) if r else None for r in rate.tolist()]  # minutes to FED 1
    [None, 7.9, 152.2]
    """
    t = np.asarray(temperature_c, dtype=float)
    k = np.asarray(smoke_od_m, dtype=float)
    if t.shape != k.shape:
        raise InputError(f"victims: temperature {t.shape} and smoke {k.shape} must match")
    hot = t > params.heat_threshold_c
    t_safe = np.where(hot, t, params.heat_threshold_c)
    heat_per_min = np.where(hot, t_safe**3.4 / 5e7, 0.0)
    co_per_min = np.maximum(k, 0.0) * params.co_ppm_per_od / params.co_dose_ppm_min
    out: FloatArray = (heat_per_min + co_per_min) / 60.0
    return out


def victim_step(
    state: VictimState,
    temperature_c: ArrayLike,
    smoke_od_m: ArrayLike,
    params: VictimParams,
    dt_s: float,
) -> VictimState:
    """The victims ``dt_s`` later, having breathed the air at their positions.

    Parameters
    ----------
    state : VictimState
    temperature_c, smoke_od_m : array_like, shape (V,)
        Air temperature [deg C] and smoke optical density [1/m] at each victim.
    params : VictimParams
    dt_s : float
        Step [s].

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import VictimParams, VictimState, victim_step
    >>> v = VictimState(position_m=np.zeros((1, 2)), dose=np.zeros(1))
    >>> for _ in range(10):  # ten minutes at 100 deg C
    ...     v = victim_step(v, [100.0], [0.0], VictimParams(), 60.0)
    >>> bool(v.alive[0]), round(float(v.dose[0]), 2)
    (False, 1.26)
    """
    rate = victim_dose_rate(temperature_c, smoke_od_m, params)
    if rate.shape != state.dose.shape:
        raise InputError(f"victims: {rate.shape[0]} readings for {state.dose.shape[0]} victims")
    return VictimState(position_m=state.position_m, dose=state.dose + rate * dt_s)
