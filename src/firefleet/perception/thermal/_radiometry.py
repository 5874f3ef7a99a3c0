"""Radiometry: camera counts to temperature, Planck band radiance and its inverse."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet._typing import FloatArray
from firefleet.errors import InputError, check_fields

KELVIN = 273.15
_H_PLANCK = 6.62607015e-34  # J s (SI 2019, exact)
_C_LIGHT = 2.99792458e8  # m/s (exact)
_K_BOLTZMANN = 1.380649e-23  # J/K (exact)
_TABLE_MIN_C, _TABLE_MAX_C, _TABLE_STEP_K = -100.0, 2000.0, 0.25


@dataclass(frozen=True)
class LinearCalibration:
    """Counts to temperature: ``T [C] = gain * counts + offset``.

    Attributes
    ----------
    gain_c_per_count : float
        Kelvin per count (> 0). TLinear output: 0.01 (or 0.1 in low resolution).
    offset_c : float
        Temperature at zero counts [C]. TLinear: -273.15 (counts are centikelvin).
    max_count : int
        Largest valid count: 16383 for Raw14, 65535 for TLinear.

    Examples
    --------
    >>> from firefleet.perception.thermal import LinearCalibration
    >>> tlinear = LinearCalibration.parse("tlinear")
    >>> tlinear.gain_c_per_count, tlinear.offset_c, tlinear.max_count
    (0.01, -273.15, 65535)
    """

    gain_c_per_count: float
    offset_c: float
    max_count: int = 16383

    def __post_init__(self) -> None:
        check_fields(self, "calibration", positive=("gain_c_per_count", "max_count"))
        if not math.isfinite(self.offset_c):
            raise InputError(f"calibration.offset_c must be finite, got {self.offset_c}")

    @classmethod
    def tlinear(cls, resolution_k: float = 0.01) -> LinearCalibration:
        """The Lepton's TLinear radiometric output: counts in units of ``resolution_k`` kelvin."""
        return cls(gain_c_per_count=resolution_k, offset_c=-KELVIN, max_count=65535)

    @classmethod
    def parse(cls, text: str) -> LinearCalibration:
        """From ``"tlinear"``, ``"tlinear10"`` (0.1 K) or ``"GAIN,OFFSET"`` (C per count, C)."""
        key = text.strip().lower()
        if key == "tlinear":
            return cls.tlinear(0.01)
        if key == "tlinear10":
            return cls.tlinear(0.1)
        parts = key.split(",")
        try:
            gain, offset = (float(p) for p in parts)
        except ValueError:
            raise InputError(
                f"--counts must be 'tlinear', 'tlinear10' or 'GAIN,OFFSET', got {text!r}"
            ) from None
        if not (math.isfinite(gain) and gain > 0 and math.isfinite(offset)):
            raise InputError(
                f"--counts GAIN,OFFSET needs a finite GAIN > 0 (C per count) and a finite "
                f"OFFSET (C), got {text!r}"
            )
        return cls(gain_c_per_count=gain, offset_c=offset, max_count=65535)


def counts_to_celsius(counts: ArrayLike, calibration: LinearCalibration) -> FloatArray:
    """Temperature [C] of integer camera counts.

    Raises
    ------
    InputError
        If ``counts`` is not an integer array or holds values outside
        ``[0, calibration.max_count]``.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal import LinearCalibration, counts_to_celsius
    >>> counts_to_celsius(np.array([27315, 37315]), LinearCalibration.tlinear()).round(6).tolist()
    [0.0, 100.0]
    """
    arr = np.asarray(counts)
    if not np.issubdtype(arr.dtype, np.integer):
        raise InputError(f"counts must be integers, got dtype {arr.dtype}")
    if arr.size and (arr.min() < 0 or arr.max() > calibration.max_count):
        raise InputError(
            f"counts must lie in [0, {calibration.max_count}], got [{arr.min()}, {arr.max()}]"
        )
    return np.asarray(calibration.gain_c_per_count * arr + calibration.offset_c, dtype=np.float64)


def celsius_to_counts(temp_c: ArrayLike, calibration: LinearCalibration) -> NDArray[np.uint16]:
    """Nearest counts of temperatures [C], clipped to ``[0, max_count]`` (the inverse).

    Examples
    --------
    >>> from firefleet.perception.thermal import LinearCalibration, celsius_to_counts
    >>> celsius_to_counts([0.0, 36.6, 1000.0], LinearCalibration.tlinear()).tolist()
    [27315, 30975, 65535]
    """
    t = np.asarray(temp_c, dtype=np.float64)
    counts = np.rint((t - calibration.offset_c) / calibration.gain_c_per_count)
    return np.clip(counts, 0, calibration.max_count).astype(np.uint16)


def _planck_band(temp_k: FloatArray, band_um: tuple[float, float]) -> FloatArray:
    """Band radiance by 64-point Gauss-Legendre quadrature over wavelength [W m^-2 sr^-1]."""
    nodes, weights = np.polynomial.legendre.leggauss(64)
    lo, hi = band_um[0] * 1e-6, band_um[1] * 1e-6
    lam = 0.5 * (hi - lo) * nodes + 0.5 * (hi + lo)
    c1 = 2.0 * _H_PLANCK * _C_LIGHT**2
    c2 = _H_PLANCK * _C_LIGHT / _K_BOLTZMANN
    spectral = c1 / lam**5 / np.expm1(c2 / (lam * temp_k[:, None]))
    return np.asarray(0.5 * (hi - lo) * spectral @ weights, dtype=np.float64)


@functools.lru_cache(maxsize=4)
def _radiance_table(band_um: tuple[float, float]) -> tuple[FloatArray, FloatArray]:
    temps = np.arange(_TABLE_MIN_C, _TABLE_MAX_C + _TABLE_STEP_K / 2, _TABLE_STEP_K)
    rad = _planck_band(temps + KELVIN, band_um)
    temps.flags.writeable = False  # shared through the cache
    rad.flags.writeable = False
    return temps, rad


def band_radiance(temp_c: ArrayLike, *, band_um: tuple[float, float] = (8.0, 14.0)) -> FloatArray:
    """Black-body radiance in a wavelength band [W m^-2 sr^-1] (Planck's law).

    Parameters
    ----------
    temp_c : array_like
        Temperatures [C], within -100 to 2000 C.
    band_um : (float, float), keyword-only
        Band [um]; the Lepton's microbolometer integrates 8-14 um.

    Returns
    -------
    ndarray
        Radiance, same shape as ``temp_c``; linear interpolation in a 0.25 K table
        (relative error below 1e-6).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal import band_radiance
    >>> # 8-14 um carries about 37 % of a 20 C black body's sigma T^4 / pi
    >>> sigma_t4_pi = 5.670374419e-8 * 293.15**4 / np.pi
    >>> round(float(band_radiance(20.0) / sigma_t4_pi), 2)
    0.37
    """
    t = np.asarray(temp_c, dtype=np.float64)
    if t.size and (not np.all(np.isfinite(t)) or t.min() < _TABLE_MIN_C or t.max() > _TABLE_MAX_C):
        raise InputError(f"temperatures must be finite, in [{_TABLE_MIN_C}, {_TABLE_MAX_C}] C")
    temps, rad = _radiance_table(band_um)
    return np.asarray(np.interp(t, temps, rad), dtype=np.float64)


def radiance_to_celsius(
    radiance: ArrayLike, *, band_um: tuple[float, float] = (8.0, 14.0)
) -> FloatArray:
    """Inverse of :func:`band_radiance` (brightness temperature [C]), clipped to its table.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal import band_radiance, radiance_to_celsius
    >>> radiance_to_celsius(band_radiance([-20.0, 36.6, 600.0])).round(3).tolist()
    [-20.0, 36.6, 600.0]
    """
    temps, rad = _radiance_table(band_um)
    return np.asarray(np.interp(np.asarray(radiance, dtype=np.float64), rad, temps))
