"""Thermal imaging: frames, radiometry, filtering, detection of fires and people, bearing, range.

Deliverable section 2.7.1: a FLIR Lepton (80 x 60 pixels, 51 degree horizontal field
of view, NETD under 50 mK) lets a robot find the seat of a fire and the heat
signature of a victim through smoke and darkness; "ranging" (measuring how far away
they are) is the deliverable's next step, done here from a size prior through the
pinhole model, or from a stereo depth.

Pipeline of :func:`detect` on one frame in degrees Celsius ``(H, W)``:

1. :func:`denoise`: column fixed-pattern offsets removed (:func:`destripe`), then a
   3 x 3 median (dead pixels, temporal noise).
   Pixels at fire temperatures are kept unfiltered (a median would erase a fire that
   fills one or two pixels).
2. Local background: a grey opening along each row with a segment a third of the
   frame wide (an object narrower than that is removed from it; a band of warm wall
   across the view and a step edge between a hot wall and a cool floor are kept).
   Candidate regions are the 8-connected components of pixels at least
   ``warm_contrast_k / 2`` above it that hold a pixel at least ``warm_contrast_k``
   above it (hysteresis), and of pixels at fire temperatures.
3. Each region: area, peak and mean temperature, centroid, bounding box, and the
   temperature of its surround (median of a ring around it).
4. Kind: ``"fire"`` if its peak reaches ``fire_min_c``, or ``fire_contrast_min_c``
   with at least ``fire_contrast_k`` above its surround (a small or distant fire
   that fills only part of a pixel); ``"person"`` if its mean is at skin or clothing
   temperature and its size is plausible for a person at the implied range;
   ``"warm"`` otherwise.
5. Sub-pixel extent from the fraction of each pixel the object fills, computed in
   8-14 um band radiance (what the microbolometer integrates), so partly covered edge
   pixels count for what they hold. Bearing is the mid-azimuth of the object's two
   edges through the camera model (:class:`CameraModel`, pinhole with Brown-Conrady
   distortion); range is ``size / angular size`` for the prior, or the median stereo
   depth in the region, with a 1-sigma uncertainty.

Temperatures are apparent (brightness) temperatures, emissivity 1.
"""

from __future__ import annotations

import functools
import logging
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
import scipy.ndimage as ndi
from numpy.typing import ArrayLike, NDArray

from firefleet.errors import InputError, check_fields

__all__ = [
    "FRAME_SUFFIXES",
    "CameraModel",
    "Detection",
    "DetectionParams",
    "FrameDetections",
    "LinearCalibration",
    "band_radiance",
    "celsius_to_counts",
    "check_frame",
    "counts_to_celsius",
    "denoise",
    "destripe",
    "detect",
    "detections_document",
    "frame_paths",
    "radiance_to_celsius",
    "range_from_size",
    "read_frame",
]

logger = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]
Kind = Literal["fire", "person", "warm"]

KELVIN = 273.15
LEPTON_HFOV_RAD = math.radians(51.0)
"""Lepton 2.5 / 3.5 horizontal field of view (deliverable 2.7.1.2)."""
FRAME_SUFFIXES = (".npy", ".png", ".pgm", ".pnm", ".tif", ".tiff")
"""File types :func:`read_frame` reads."""
_H_PLANCK = 6.62607015e-34  # J s (SI 2019, exact)
_C_LIGHT = 2.99792458e8  # m/s (exact)
_K_BOLTZMANN = 1.380649e-23  # J/K (exact)
_TABLE_MIN_C, _TABLE_MAX_C, _TABLE_STEP_K = -100.0, 2000.0, 0.25


# ----------------------------------------------------------------------------- camera


@dataclass(frozen=True)
class CameraModel:
    """Pinhole camera with Brown-Conrady lens distortion (OpenCV's convention).

    Pixel ``(row, col)`` has its centre at ``(row, col)``; the image spans
    ``[-0.5, width - 0.5]`` horizontally. The optical axis is horizontal and points
    along the robot's heading; bearings are positive to the left (counter-clockwise,
    the robot frame's convention).

    Attributes
    ----------
    width_px, height_px : int
        Image size [px] (Lepton 2.x: 80 x 60).
    hfov_rad : float
        Horizontal field of view of the undistorted pinhole [rad]; sets
        ``fx = (width / 2) / tan(hfov / 2)``, square pixels (``fy = fx``).
    cx_px, cy_px : float or None
        Principal point [px]; ``None`` is the image centre ``((W-1)/2, (H-1)/2)``.
    k1, k2, p1, p2 : float
        Radial and tangential distortion coefficients (OpenCV ``distCoeffs`` order
        k1, k2, p1, p2), on normalised coordinates.
    """

    width_px: int = 80
    height_px: int = 60
    hfov_rad: float = LEPTON_HFOV_RAD
    cx_px: float | None = None
    cy_px: float | None = None
    k1: float = 0.0
    k2: float = 0.0
    p1: float = 0.0
    p2: float = 0.0

    def __post_init__(self) -> None:
        check_fields(self, "camera", positive=("width_px", "height_px", "hfov_rad"))
        if not self.hfov_rad < math.pi:
            raise InputError(f"camera.hfov_rad must be < pi, got {self.hfov_rad}")
        for name in ("k1", "k2", "p1", "p2"):
            if not math.isfinite(getattr(self, name)):
                raise InputError(f"camera.{name} must be finite, got {getattr(self, name)}")

    @classmethod
    def for_frame(cls, shape: tuple[int, ...], *, hfov_deg: float = 51.0) -> CameraModel:
        """An undistorted camera of the frame's size (rows, cols) and a field of view [deg]."""
        if len(shape) != 2:
            raise InputError(f"frame shape must be (H, W), got {shape}")
        return cls(width_px=int(shape[1]), height_px=int(shape[0]), hfov_rad=math.radians(hfov_deg))

    @property
    def fx_px(self) -> float:
        """Focal length [px]."""
        return 0.5 * self.width_px / math.tan(0.5 * self.hfov_rad)

    @property
    def principal_point(self) -> tuple[float, float]:
        """(cx, cy) [px]."""
        cx = 0.5 * (self.width_px - 1) if self.cx_px is None else self.cx_px
        cy = 0.5 * (self.height_px - 1) if self.cy_px is None else self.cy_px
        return cx, cy

    @property
    def pixel_angle_rad(self) -> float:
        """Mean angle of one pixel across the image, ``hfov / width`` [rad] (Lepton: 0.6375 deg)."""
        return self.hfov_rad / self.width_px

    @property
    def distorted(self) -> bool:
        """True if any distortion coefficient is non-zero."""
        return any((self.k1, self.k2, self.p1, self.p2))

    def _distort(self, x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
        r2 = x * x + y * y
        radial = 1.0 + r2 * (self.k1 + self.k2 * r2)
        xd = x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x)
        yd = y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y
        return xd, yd

    def normalized(self, rows: ArrayLike, cols: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Undistorted normalised coordinates ``(x, y)`` (x right, y down) of pixel positions.

        Parameters
        ----------
        rows, cols : array_like, broadcastable
            Pixel positions [px], sub-pixel allowed.

        Returns
        -------
        x, y : ndarray
            Ray direction ``(x, y, 1)`` in the camera frame. With distortion, the
            fixed-point iteration of OpenCV's ``undistortPoints`` (20 iterations).
        """
        cx, cy = self.principal_point
        f = self.fx_px
        xd = (np.asarray(cols, dtype=np.float64) - cx) / f
        yd = (np.asarray(rows, dtype=np.float64) - cy) / f
        xd, yd = np.broadcast_arrays(xd, yd)
        if not self.distorted:
            return xd.copy(), yd.copy()
        x, y = xd.copy(), yd.copy()
        for _ in range(20):
            r2 = x * x + y * y
            radial = 1.0 + r2 * (self.k1 + self.k2 * r2)
            dx = 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x)
            dy = self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y
            x = (xd - dx) / radial
            y = (yd - dy) / radial
        return x, y

    def project(self, x: ArrayLike, y: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Pixel ``(rows, cols)`` of normalised coordinates (distortion applied)."""
        cx, cy = self.principal_point
        xd, yd = self._distort(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))
        return cy + self.fx_px * yd, cx + self.fx_px * xd

    def bearing(self, rows: ArrayLike, cols: ArrayLike) -> FloatArray:
        """Azimuth of pixel positions [rad], positive to the left of the optical axis."""
        x, _ = self.normalized(rows, cols)
        return np.asarray(-np.arctan(x), dtype=np.float64)


# ------------------------------------------------------------------------- radiometry


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
        return cls(gain_c_per_count=gain, offset_c=offset, max_count=65535)


def counts_to_celsius(counts: ArrayLike, calibration: LinearCalibration) -> FloatArray:
    """Temperature [C] of integer camera counts.

    Raises
    ------
    InputError
        If ``counts`` is not an integer array or holds values outside
        ``[0, calibration.max_count]``.
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
    """Nearest counts of temperatures [C], clipped to ``[0, max_count]`` (the inverse)."""
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
    """
    t = np.asarray(temp_c, dtype=np.float64)
    if t.size and (not np.all(np.isfinite(t)) or t.min() < _TABLE_MIN_C or t.max() > _TABLE_MAX_C):
        raise InputError(f"temperatures must be finite, in [{_TABLE_MIN_C}, {_TABLE_MAX_C}] C")
    temps, rad = _radiance_table(band_um)
    return np.asarray(np.interp(t, temps, rad), dtype=np.float64)


def radiance_to_celsius(
    radiance: ArrayLike, *, band_um: tuple[float, float] = (8.0, 14.0)
) -> FloatArray:
    """Inverse of :func:`band_radiance` (brightness temperature [C]), clipped to its table."""
    temps, rad = _radiance_table(band_um)
    return np.asarray(np.interp(np.asarray(radiance, dtype=np.float64), rad, temps))


# ----------------------------------------------------------------------------- frames


def check_frame(frame: ArrayLike, name: str = "frame") -> FloatArray:
    """A 2-D finite float64 temperature frame [C], at least 3 x 3.

    Raises
    ------
    InputError
        If ``frame`` is not numeric, not 2-D, smaller than 3 x 3, or holds NaN or inf.
    """
    arr = np.asarray(frame)
    if arr.dtype.kind not in "fiu":
        raise InputError(f"{name}: must be a numeric array, got dtype {arr.dtype}")
    if arr.ndim != 2:
        raise InputError(f"{name}: must have shape (H, W), got {arr.shape}")
    if arr.shape[0] < 3 or arr.shape[1] < 3:
        raise InputError(f"{name}: must be at least 3 x 3 pixels, got {arr.shape}")
    out = arr.astype(np.float64)
    bad = ~np.isfinite(out)
    if bad.any():
        raise InputError(f"{name}: {int(bad.sum())} non-finite (NaN or inf) temperature(s)")
    if out.min() < -273.15:
        raise InputError(f"{name}: temperatures below absolute zero ({out.min():.6g} C)")
    return out


def read_frame(path: str | Path, *, calibration: LinearCalibration | None = None) -> FloatArray:
    """Read one thermal frame as temperatures [C], shape (H, W).

    Parameters
    ----------
    path : str or Path
        ``.npy``: a 2-D float array of temperatures [C] (or integer counts when
        ``calibration`` is given). ``.png``, ``.pgm``/``.pnm``, ``.tif``/``.tiff``: a
        16-bit single-channel image of counts; needs ``calibration``.
    calibration : LinearCalibration, keyword-only
        Counts to temperature (Raw14 gain and offset, or TLinear).

    Raises
    ------
    InputError
        Missing, empty or corrupt file, wrong shape or dtype, 8-bit or colour image,
        NaN temperatures, counts without a calibration.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in FRAME_SUFFIXES:
        raise InputError(f"{p}: unknown frame type {suffix!r}; expected one of {FRAME_SUFFIXES}")
    if not p.is_file():
        raise InputError(f"{p}: no such file")
    if p.stat().st_size == 0:
        raise InputError(f"{p}: empty file")
    if suffix == ".npy":
        try:
            arr = np.load(p, allow_pickle=False)
        except (ValueError, OSError, EOFError) as exc:
            raise InputError(f"{p}: not a readable .npy array ({exc})") from None
        if np.issubdtype(arr.dtype, np.integer):
            if calibration is None:
                raise InputError(f"{p}: holds integer counts; give a calibration (--counts)")
            return check_frame(counts_to_celsius(arr, calibration), str(p))
        if not np.issubdtype(arr.dtype, np.floating):
            raise InputError(f"{p}: dtype {arr.dtype}; expected float temperatures in C")
        return check_frame(arr, str(p))
    if calibration is None:
        raise InputError(f"{p}: a {suffix} image holds counts; give a calibration (--counts)")
    return check_frame(counts_to_celsius(_read_image_counts(p), calibration), str(p))


def _read_image_counts(p: Path) -> NDArray[np.uint16]:
    from PIL import Image, UnidentifiedImageError  # only when an image is read

    try:
        with Image.open(p) as img:
            img.load()
            mode = img.mode
            arr = np.array(img)
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as exc:
        raise InputError(f"{p}: not a readable image ({exc})") from None
    if mode not in ("I;16", "I;16B", "I;16L", "I;16N", "I"):
        raise InputError(f"{p}: image mode {mode}; expected 16-bit single-channel counts")
    if arr.ndim != 2:
        raise InputError(f"{p}: expected a single-channel image, got shape {arr.shape}")
    if arr.size and (arr.min() < 0 or arr.max() > 0xFFFF):
        raise InputError(f"{p}: pixel values outside 16 bits")
    return arr.astype(np.uint16)


# -------------------------------------------------------------------------- filtering


def destripe(frame_c: ArrayLike, *, max_step_k: float = 1.0) -> tuple[FloatArray, FloatArray]:
    """Remove column fixed-pattern offsets (the stripes of an uncooled microbolometer).

    The step between neighbouring columns' offsets is the median over rows of the
    difference of the two columns, over the rows where that difference is below
    ``max_step_k`` (object edges excluded); the offsets are the running sum of the
    steps, less their mean and linear trend (a linear ramp of offsets cannot be told
    from a scene's temperature gradient, so it is left in the scene).

    Parameters
    ----------
    frame_c : array_like, shape (H, W)
        Temperatures [C].
    max_step_k : float, keyword-only
        Largest column-to-column difference believed to be a stripe, not a scene edge [K].

    Returns
    -------
    frame : ndarray, shape (H, W)
        Corrected frame [C].
    offsets : ndarray, shape (W,)
        Column offsets removed [K] (zero mean, zero linear trend).
    """
    f = check_frame(frame_c)
    diff = f[:, 1:] - f[:, :-1]
    masked = np.where(np.abs(diff) < max_step_k, diff, np.nan)
    steps = np.zeros(diff.shape[1])
    usable = np.isfinite(masked).any(axis=0)
    if usable.any():
        steps[usable] = np.nanmedian(masked[:, usable], axis=0)
    offsets = np.concatenate([[0.0], np.cumsum(steps)])
    x = np.arange(offsets.size, dtype=np.float64)
    slope, intercept = np.polyfit(x, offsets, 1)
    offsets = offsets - (slope * x + intercept)
    return f - offsets, offsets


def denoise(
    frame_c: ArrayLike,
    *,
    median_size: int = 3,
    stripes: bool = True,
    flat_field_c: ArrayLike | None = None,
) -> FloatArray:
    """Fixed-pattern and noise filtering of one frame.

    Parameters
    ----------
    frame_c : array_like, shape (H, W)
        Temperatures [C].
    median_size : int, keyword-only
        Median filter width [px] (odd; 1 disables it). 3 removes dead or hot pixels
        and lowers Gaussian noise about 1.5 times, and moves a straight edge by none.
    stripes : bool, keyword-only
        Remove column offsets (:func:`destripe`).
    flat_field_c : array_like, shape (H, W), keyword-only
        A frame of a uniform scene (the shutter): its deviation from its own mean is
        the fixed pattern, subtracted first (the Lepton's flat-field correction).

    Returns
    -------
    ndarray, shape (H, W)
        The filtered frame [C].
    """
    f = check_frame(frame_c)
    if flat_field_c is not None:
        ff = check_frame(flat_field_c, "flat_field_c")
        if ff.shape != f.shape:
            raise InputError(f"flat_field_c shape {ff.shape} differs from the frame's {f.shape}")
        f = f - (ff - ff.mean())
    if stripes:
        f, _ = destripe(f)
    if median_size < 1 or median_size % 2 == 0:
        raise InputError(f"median_size must be a positive odd integer, got {median_size}")
    if median_size > 1:
        f = ndi.median_filter(f, size=median_size, mode="nearest")
    return f


# -------------------------------------------------------------------------- detection


@dataclass(frozen=True)
class DetectionParams:
    """Thresholds and priors of :func:`detect`.

    Attributes
    ----------
    warm_contrast_k : float
        A region's peak must be this far above the local background [K]; its pixels
        half as far (hysteresis).
    background_px : int or None
        Length of the row segment of the local background's grey opening [px]; objects
        narrower than it are found. ``None``: a third of the frame's width
        (at least 15).
    min_area_px : int
        Smallest region reported [px].
    fire_min_c : float
        A peak at or above this is a fire [C] (pyrolysis and flames; no person or room
        surface reaches it).
    fire_contrast_min_c, fire_contrast_k : float
        Or: a peak at or above ``fire_contrast_min_c`` [C] and at least
        ``fire_contrast_k`` [K] above its surround is a fire too (a fire far away,
        filling part of a pixel, reads cooler than it is).
    person_min_c, person_max_c : float
        Mean temperature band of a person [C] (clothing 28-34, skin 32-37).
    person_height_m, person_height_sigma_m : float
        Size prior: standing adult stature [m] and its spread (ISO 7250 stature SD
        ~0.07 m; 0.1 m with posture).
    person_width_m, person_width_sigma_m : float
        Shoulder-width prior [m] and spread.
    person_max_width_m : float
        Largest plausible person width at the implied range [m] (arms out).
    person_min_range_m, person_max_range_m : float
        Ranges at which a region can be called a person [m]; beyond the far limit a
        person is under ~5 Lepton pixels tall.
    fire_width_m, fire_width_sigma_m : float or None
        Size prior of a fire (its width [m]); ``None`` (default): no range from size
        for fires. The spread defaults to 20 % of the width.
    extent_sigma_px : float
        1-sigma error of a measured extent [px] (sub-pixel edges: a quarter pixel each).
    depth_sigma_rel : float
        Smallest relative 1-sigma error of a stereo depth.
    median_size : int
        Median filter width [px] of :func:`denoise` (pixels at ``fire_contrast_min_c``
        or above are exempt).
    destripe : bool
        Remove column stripes first.
    """

    warm_contrast_k: float = 3.0
    background_px: int | None = None
    min_area_px: int = 2
    fire_min_c: float = 100.0
    fire_contrast_min_c: float = 60.0
    fire_contrast_k: float = 30.0
    person_min_c: float = 28.0
    person_max_c: float = 40.0
    person_height_m: float = 1.7
    person_height_sigma_m: float = 0.1
    person_width_m: float = 0.5
    person_width_sigma_m: float = 0.15
    person_max_width_m: float = 1.2
    person_min_range_m: float = 0.3
    person_max_range_m: float = 30.0
    fire_width_m: float | None = None
    fire_width_sigma_m: float | None = None
    extent_sigma_px: float = 0.35
    depth_sigma_rel: float = 0.02
    median_size: int = 3
    destripe: bool = True

    def __post_init__(self) -> None:
        check_fields(
            self,
            "detection",
            positive=(
                "warm_contrast_k",
                "min_area_px",
                "fire_contrast_k",
                "person_height_m",
                "person_width_m",
                "person_max_width_m",
                "person_max_range_m",
                "extent_sigma_px",
            ),
            non_negative=(
                "person_height_sigma_m",
                "person_width_sigma_m",
                "person_min_range_m",
                "depth_sigma_rel",
            ),
        )
        if self.fire_width_m is not None:
            check_fields(self, "detection", positive=("fire_width_m",))
        if self.background_px is not None:
            check_fields(self, "detection", positive=("background_px",))
        if self.fire_width_sigma_m is not None:
            check_fields(self, "detection", non_negative=("fire_width_sigma_m",))
        if not self.person_min_c < self.person_max_c:
            raise InputError("detection.person_min_c must be below person_max_c")


@dataclass(frozen=True)
class Detection:
    """One detected region.

    Attributes
    ----------
    kind : {"fire", "person", "warm"}
    centroid_rc : (float, float)
        Centroid (row, col) of the region's pixels [px].
    bbox_rc : (int, int, int, int)
        ``(r0, c0, r1, c1)``, end exclusive (``frame[r0:r1, c0:c1]``).
    peak_c, mean_c : float
        Largest and mean filtered temperature in the region [C].
    area_px : int
        Pixels in the region.
    surround_c : float
        Median temperature of a ring around it [C].
    bearing_rad : float
        Azimuth of the object's centre [rad], positive left.
    angular_width_rad : float
        Azimuth between its sub-pixel left and right edges [rad] (``nan`` if cut by
        the frame's border).
    elevation_span : float
        ``tan(elevation of top) - tan(elevation of bottom)`` of its sub-pixel edges
        (height over horizontal range for an upright object; ``nan`` if cut).
    range_m, range_sigma_m : float or None
        Horizontal distance [m] and its 1-sigma error, from a size prior or a stereo
        depth; ``None`` if neither applies.
    range_source : {"size", "stereo", None}
    """

    kind: Kind
    centroid_rc: tuple[float, float]
    bbox_rc: tuple[int, int, int, int]
    peak_c: float
    mean_c: float
    area_px: int
    surround_c: float
    bearing_rad: float
    angular_width_rad: float
    elevation_span: float
    range_m: float | None = None
    range_sigma_m: float | None = None
    range_source: Literal["size", "stereo"] | None = None

    def to_json(self) -> dict[str, Any]:
        """The ``detections.json`` object of this detection."""
        return {
            "kind": self.kind,
            "centroid_rc": [round(self.centroid_rc[0], 3), round(self.centroid_rc[1], 3)],
            "bbox_rc": list(self.bbox_rc),
            "peak_c": round(self.peak_c, 3),
            "mean_c": round(self.mean_c, 3),
            "area_px": self.area_px,
            "surround_c": round(self.surround_c, 3),
            "bearing_rad": round(self.bearing_rad, 6),
            "range_m": None if self.range_m is None else round(self.range_m, 4),
            "range_sigma_m": None if self.range_sigma_m is None else round(self.range_sigma_m, 4),
            "range_source": self.range_source,
        }


@dataclass(frozen=True)
class FrameDetections:
    """Everything found in one frame.

    Attributes
    ----------
    detections : tuple of Detection
        Fires first, then people, then warm objects; hottest first within a kind.
    background_c : float
        The frame's median after filtering [C].
    filtered_c : ndarray, shape (H, W)
        The filtered frame the detections were measured on [C].
    """

    detections: tuple[Detection, ...]
    background_c: float
    filtered_c: FloatArray = field(repr=False)

    @property
    def fire_alarm(self) -> bool:
        """True if any detection is a fire."""
        return any(d.kind == "fire" for d in self.detections)


def range_from_size(
    angular_size_rad: ArrayLike,
    size_m: float,
    *,
    size_sigma_m: float = 0.0,
    angular_sigma_rad: ArrayLike = 0.0,
) -> tuple[FloatArray, FloatArray]:
    """Range of an object of known size from the angle it subtends (pinhole model).

    ``r = size / (2 tan(alpha / 2))`` for an object of width ``size`` facing the
    camera; first-order error propagation
    ``(sigma_r / r)^2 = (sigma_size / size)^2 + (sigma_alpha / (sin(alpha) ... ))^2``
    in its exact form ``dr/dalpha = -r / sin(alpha)``.

    Parameters
    ----------
    angular_size_rad : array_like
        Angle subtended [rad], in (0, pi).
    size_m : float
        Size prior [m].
    size_sigma_m, angular_sigma_rad : keyword-only
        1-sigma errors of the prior [m] and of the measured angle [rad].

    Returns
    -------
    range_m, sigma_m : ndarray
    """
    a = np.asarray(angular_size_rad, dtype=np.float64)
    if np.any(~np.isfinite(a)) or np.any(a <= 0) or np.any(a >= math.pi):
        raise InputError("angular_size_rad must lie in (0, pi)")
    r = size_m / (2.0 * np.tan(0.5 * a))
    rel_size = size_sigma_m / size_m
    rel_angle = np.asarray(angular_sigma_rad, dtype=np.float64) / np.sin(a)
    return r, r * np.sqrt(rel_size**2 + rel_angle**2)


def _profiles(frac: FloatArray, r0: int, c0: int) -> tuple[float, float, float, float] | None:
    """Sub-pixel centre (row, col) and extent (height, width) [px] of a fill map.

    ``frac`` is the fraction of each pixel the object fills. An upright box fills
    ``a_i b_j``: the width is the sum of the column profile (max over rows), the
    height the sum of the row profile taken in the column nearest the centre divided
    by that column's fill (so a slanted top edge off axis does not inflate it).
    """
    col_prof = frac.max(axis=0)
    wsum = float(col_prof.sum())
    if wsum <= 0:
        return None
    cc = float((np.arange(frac.shape[1]) * col_prof).sum() / wsum)
    jc = int(np.clip(round(cc), 0, frac.shape[1] - 1))
    row_prof = frac[:, jc] / max(float(col_prof[jc]), 1e-6)
    row_prof = np.clip(row_prof, 0.0, 1.0)
    hsum = float(row_prof.sum())
    if hsum <= 0:
        return None
    rc = float((np.arange(frac.shape[0]) * row_prof).sum() / hsum)
    return r0 + rc, c0 + cc, hsum, wsum


def _measure(
    f: FloatArray,
    region: NDArray[np.bool_],
    sl: tuple[slice, slice],
    surround_c: float,
    core_c: float,
    camera: CameraModel,
) -> tuple[float, float, float, bool, bool]:
    """Bearing and angular width/height of a region (sub-pixel, radiance fill fraction).

    Returns (bearing [rad], angular width [rad], ``tan(top) - tan(bottom)`` of the
    elevations of its top and bottom edges, cut horizontally, cut vertically).
    """
    h, w = f.shape
    r0, r1 = max(sl[0].start - 1, 0), min(sl[0].stop + 1, h)
    c0, c1 = max(sl[1].start - 1, 0), min(sl[1].stop + 1, w)
    window = f[r0:r1, c0:c1]
    near = ndi.binary_dilation(region[r0:r1, c0:c1], structure=np.ones((3, 3), dtype=bool))
    l_bg = band_radiance(surround_c)
    l_core = band_radiance(max(core_c, surround_c + 1e-3))
    frac = np.clip((band_radiance(window) - l_bg) / (l_core - l_bg), 0.0, 1.0) * near
    cut_h = sl[1].start == 0 or sl[1].stop == w
    cut_v = sl[0].start == 0 or sl[0].stop == h
    prof = _profiles(frac, r0, c0)
    if prof is None:  # cannot happen for a region above its surround; keep the centroid
        rows, cols = np.nonzero(region[sl])
        rc, cc = sl[0].start + rows.mean(), sl[1].start + cols.mean()
        return float(camera.bearing(rc, cc)), math.nan, math.nan, True, True
    rc, cc, hpx, wpx = prof
    x, y = camera.normalized(
        np.array([rc, rc, rc - hpx / 2, rc + hpx / 2]),
        np.array([cc - wpx / 2, cc + wpx / 2, cc, cc]),
    )
    az = -np.arctan(x[:2])
    bearing = float(az.mean())
    ang_w = float(az[0] - az[1])
    tan_top = -y[2] / math.sqrt(1.0 + x[2] ** 2)
    tan_bot = -y[3] / math.sqrt(1.0 + x[3] ** 2)
    return bearing, ang_w, float(tan_top - tan_bot), cut_h, cut_v


def _size_range(
    ang_w: float,
    dtan_v: float,
    p_height: tuple[float, float] | None,
    p_width: tuple[float, float] | None,
    sigma_px: float,
    fx_px: float,
) -> tuple[float, float] | None:
    """Range [m] and 1-sigma from width and height priors (inverse-variance combined).

    Width: an object of width ``W`` facing the camera subtends ``2 atan(W / 2r)``.
    Height: an upright object of height ``H`` at horizontal range ``r`` spans
    elevations with ``tan(top) - tan(bottom) = H / r`` wherever the camera's height.
    ``p_height``, ``p_width`` are (size, sigma) priors [m]; ``sigma_px`` the extent error.
    """
    estimates: list[tuple[float, float]] = []
    if p_width is not None and math.isfinite(ang_w) and 0 < ang_w < math.pi:
        rw, sw = range_from_size(
            ang_w, p_width[0], size_sigma_m=p_width[1], angular_sigma_rad=sigma_px / fx_px
        )
        estimates.append((float(rw), float(sw)))
    if p_height is not None and math.isfinite(dtan_v) and dtan_v > 0:
        rh = p_height[0] / dtan_v
        rel = math.hypot(p_height[1] / p_height[0], sigma_px / fx_px / dtan_v)
        estimates.append((rh, rh * rel))
    if not estimates:
        return None
    if len(estimates) == 1:
        return estimates[0]
    wts = [1.0 / max(s, 1e-12) ** 2 for _, s in estimates]
    mean = sum(w * e[0] for w, e in zip(wts, estimates, strict=True)) / sum(wts)
    return mean, 1.0 / math.sqrt(sum(wts))


def detect(
    frame_c: ArrayLike,
    *,
    camera: CameraModel | None = None,
    params: DetectionParams | None = None,
    depth_m: ArrayLike | None = None,
) -> FrameDetections:
    """Find fires, people and other warm objects in one thermal frame.

    Parameters
    ----------
    frame_c : array_like, shape (H, W)
        Temperatures [C] (see :func:`read_frame`).
    camera : CameraModel, keyword-only
        The camera (its size must match the frame); default: a 51 degree HFOV pinhole
        of the frame's size (the Lepton's optics).
    params : DetectionParams, keyword-only
        Thresholds and priors.
    depth_m : array_like, shape (H, W), keyword-only
        Stereo depth along the optical axis [m] registered to the thermal frame, NaN
        where unknown. Where a region holds finite depths, its range is their median
        (converted to horizontal distance along the bearing), overriding size priors.

    Returns
    -------
    FrameDetections
        The detections and the filtered frame.

    Raises
    ------
    InputError
        Bad frame (shape, dtype, NaN), camera of another size, depth of another shape.
    """
    p = DetectionParams() if params is None else params
    raw = check_frame(frame_c)
    cam = CameraModel.for_frame(raw.shape) if camera is None else camera
    if (cam.height_px, cam.width_px) != raw.shape:
        raise InputError(
            f"camera is {cam.height_px} x {cam.width_px} px but the frame is "
            f"{raw.shape[0]} x {raw.shape[1]}"
        )
    depth = None
    if depth_m is not None:
        depth = np.asarray(depth_m, dtype=np.float64)
        if depth.shape != raw.shape:
            raise InputError(f"depth_m shape {depth.shape} differs from the frame's {raw.shape}")
    flat = destripe(raw)[0] if p.destripe else raw
    f = denoise(flat, median_size=p.median_size, stripes=False)
    # a fire far away may fill one or two pixels, which a median filter would erase: keep
    # every pixel hot enough to be a fire as it was (after destriping only)
    hot = flat >= p.fire_contrast_min_c
    if hot.any():
        f = np.where(hot, flat, f)
    background = float(np.median(f))
    size = p.background_px if p.background_px is not None else max(15, raw.shape[1] // 3)
    # local background: a grey opening (erosion then dilation) along each row removes
    # every warm structure narrower than ``size`` and keeps wider ones (a band of warm
    # wall across the view) and horizontal step edges (hot wall above a cool floor)
    contrast = f - ndi.grey_opening(f, size=(1, size), mode="nearest")
    fiery = f >= p.fire_contrast_min_c
    low = (contrast >= 0.5 * p.warm_contrast_k) | fiery
    labels, n = ndi.label(low, structure=np.ones((3, 3), dtype=bool))
    if n == 0:
        return FrameDetections(detections=(), background_c=background, filtered_c=f)
    index = np.arange(1, n + 1)
    top = np.asarray(ndi.maximum(np.where(fiery, np.inf, contrast), labels, index))
    areas = np.asarray(ndi.sum_labels(np.ones_like(f), labels, index))
    keep = (top >= p.warm_contrast_k) & (areas >= p.min_area_px)
    slices = ndi.find_objects(labels)
    found: list[Detection] = []
    for lab in index[keep]:
        sl = slices[lab - 1]
        assert sl is not None
        found.append(_describe(f, labels, int(lab), sl, low, background, cam, p, depth))
    order = {"fire": 0, "person": 1, "warm": 2}
    found.sort(key=lambda d: (order[d.kind], -d.peak_c))
    return FrameDetections(detections=tuple(found), background_c=background, filtered_c=f)


def _describe(
    f: FloatArray,
    labels: NDArray[np.int32],
    lab: int,
    sl: tuple[slice, slice],
    low: NDArray[np.bool_],
    background: float,
    cam: CameraModel,
    p: DetectionParams,
    depth: FloatArray | None,
) -> Detection:
    h, w = f.shape
    region = labels == lab
    values = f[sl][region[sl]]
    peak, mean = float(values.max()), float(values.mean())
    rows, cols = np.nonzero(region[sl])
    centroid = (float(sl[0].start + rows.mean()), float(sl[1].start + cols.mean()))
    bbox = (sl[0].start, sl[1].start, sl[0].stop, sl[1].stop)
    ring = 3
    outer = (
        slice(max(sl[0].start - ring, 0), min(sl[0].stop + ring, h)),
        slice(max(sl[1].start - ring, 0), min(sl[1].stop + ring, w)),
    )
    around = f[outer][~low[outer]]
    surround = float(np.median(around)) if around.size else background
    is_fire = peak >= p.fire_min_c or (
        peak >= p.fire_contrast_min_c and peak - surround >= p.fire_contrast_k
    )
    core = peak if is_fire else float(np.percentile(values, 75))
    bearing, ang_w, dtan_v, cut_h, cut_v = _measure(f, region, sl, surround, core, cam)
    stereo = None
    if depth is not None:
        d = depth[sl][region[sl]]
        d = d[np.isfinite(d) & (d > 0)]
        if d.size:
            z = float(np.median(d))
            spread = 1.4826 * float(np.median(np.abs(d - z)))
            x, _ = cam.normalized(centroid[0], centroid[1])
            scale = math.sqrt(1.0 + float(x) ** 2)
            stereo = (z * scale, max(spread, p.depth_sigma_rel * z) * scale)
    kind: Kind
    rng: tuple[float, float] | None
    if is_fire:
        kind = "fire"
        rng = stereo
        if rng is None and p.fire_width_m is not None and not cut_h:
            sig = 0.2 * p.fire_width_m if p.fire_width_sigma_m is None else p.fire_width_sigma_m
            rng = _size_range(
                ang_w, math.nan, None, (p.fire_width_m, sig), p.extent_sigma_px, cam.fx_px
            )
    else:
        prior = _size_range(
            math.nan if cut_h else ang_w,
            math.nan if cut_v else dtan_v,
            (p.person_height_m, p.person_height_sigma_m),
            (p.person_width_m, p.person_width_sigma_m),
            p.extent_sigma_px,
            cam.fx_px,
        )
        rng = stereo if stereo is not None else prior
        kind = "warm"
        # a region cut by the left or right border has no width to judge (often the end of
        # a warm wall): it stays "warm"
        if p.person_min_c <= mean <= p.person_max_c and rng is not None and not cut_h:
            r = rng[0]
            width_at_r = 2.0 * r * math.tan(0.5 * ang_w) if math.isfinite(ang_w) else 0.0
            height_at_r = r * dtan_v if math.isfinite(dtan_v) else math.nan
            plausible = (
                p.person_min_range_m <= r <= p.person_max_range_m
                and width_at_r <= p.person_max_width_m
                and (not math.isfinite(height_at_r) or 0.3 <= height_at_r <= 2.3)
            )
            if plausible:
                kind = "person"
        if kind == "warm" and stereo is None:
            rng = None  # a person-size prior says nothing about an unknown warm object
    return Detection(
        kind=kind,
        centroid_rc=centroid,
        bbox_rc=bbox,
        peak_c=peak,
        mean_c=mean,
        area_px=int(values.size),
        surround_c=surround,
        bearing_rad=bearing,
        angular_width_rad=ang_w if not cut_h else math.nan,
        elevation_span=dtan_v if not cut_v else math.nan,
        range_m=None if rng is None else rng[0],
        range_sigma_m=None if rng is None else rng[1],
        range_source=None if rng is None else ("stereo" if rng is stereo else "size"),
    )


def frame_paths(inputs: list[str] | tuple[str, ...]) -> list[Path]:
    """The frame files named by ``inputs`` (files, or folders searched for frame files).

    Raises
    ------
    InputError
        A path that does not exist, or a folder without frames.
    """
    paths: list[Path] = []
    for item in inputs:
        p = Path(item)
        if p.is_dir():
            found = sorted(q for q in p.iterdir() if q.suffix.lower() in FRAME_SUFFIXES)
            if not found:
                raise InputError(f"{p}: folder holds no frames ({', '.join(FRAME_SUFFIXES)})")
            paths.extend(found)
        elif p.exists():
            paths.append(p)
        else:
            raise InputError(f"{p}: no such file or folder")
    return paths


def detections_document(name: str, result: FrameDetections) -> dict[str, Any]:
    """The ``detections.json`` entry of one frame."""
    return {
        "frame": name,
        "fire_alarm": result.fire_alarm,
        "background_c": round(result.background_c, 3),
        "detections": [d.to_json() for d in result.detections],
    }
