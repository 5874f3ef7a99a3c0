"""Thermal frames: reading, checking, destriping and denoising."""

from __future__ import annotations

from pathlib import Path

import numba
import numpy as np
import scipy.ndimage as ndi
from numpy.typing import ArrayLike, NDArray

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.perception.thermal._radiometry import LinearCalibration, counts_to_celsius
from firefleet.perception.thermal._select import order_pair

FRAME_SUFFIXES = (".npy", ".png", ".pgm", ".pnm", ".tif", ".tiff")
"""File types :func:`read_frame` reads."""


def check_frame(frame: ArrayLike, name: str = "frame") -> FloatArray:
    """A 2-D finite float64 temperature frame [C], at least 3 x 3.

    Raises
    ------
    InputError
        If ``frame`` is not numeric, not 2-D, smaller than 3 x 3, or holds NaN or inf.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.errors import InputError
    >>> from firefleet.perception.thermal import check_frame
    >>> check_frame(np.full((3, 4), 20, dtype=np.uint16)).dtype
    dtype('float64')
    >>> try:
    ...     check_frame(np.zeros(5))
    ... except InputError as error:
    ...     print(error)
    frame: must have shape (H, W), got (5,)
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

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> from firefleet.perception.thermal import read_frame
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = pathlib.Path(folder.name) / "frame.npy"
    >>> np.save(path, np.full((60, 80), 21.5))
    >>> frame = read_frame(path)
    >>> frame.shape, float(frame[0, 0])
    ((60, 80), 21.5)
    >>> folder.cleanup()
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

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal import destripe
    >>> stripes = np.array([0.3, -0.3, -0.3, 0.3])  # column offsets, no mean, no trend
    >>> frame, offsets = destripe(np.full((6, 4), 25.0) + stripes)
    >>> float(np.abs(frame - 25.0).max().round(12)), offsets.round(6).tolist()
    (0.0, [0.3, -0.3, -0.3, 0.3])
    """
    f = check_frame(frame_c)
    steps = _column_steps(f, float(max_step_k))
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

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal import denoise
    >>> frame = np.full((5, 5), 20.0)
    >>> frame[2, 2] = 400.0  # a hot pixel
    >>> float(denoise(frame, stripes=False)[2, 2])
    20.0
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
    if median_size == 3:
        f = _median3_nearest(f)  # == ndi.median_filter(f, size=3, mode="nearest"), faster
    elif median_size > 1:
        f = ndi.median_filter(f, size=median_size, mode="nearest")
    return f


@numba.njit(cache=True)
def _column_steps(f: FloatArray, max_step: float) -> FloatArray:  # pragma: no cover - compiled
    """Per pair of neighbouring columns, the median of their differences below
    ``max_step`` in magnitude (NumPy's nanmedian of the masked differences: the mean of
    the middle two of an even count), 0 where no row qualifies."""
    h, w = f.shape
    steps = np.zeros(w - 1)
    buf = np.empty(h)
    work = np.empty(h)
    counts = np.empty(16, dtype=np.int64)
    for c in range(w - 1):
        m = 0
        for r in range(h):
            d = f[r, c + 1] - f[r, c]
            if abs(d) < max_step:
                buf[m] = d
                m += 1
        if m == 0:
            continue
        lower, upper = order_pair(buf, m, m // 2, counts, work)  # the middle one or two
        steps[c] = upper if m % 2 == 1 else 0.5 * (lower + upper)
    return steps


@numba.njit(cache=True, inline="always")
def _sort3(a: float, b: float, c: float) -> tuple[float, float, float]:  # pragma: no cover
    if a > b:
        a, b = b, a
    if b > c:
        b, c = c, b
    if a > b:
        a, b = b, a
    return a, b, c


@numba.njit(cache=True, inline="always")
def _med3(a: float, b: float, c: float) -> float:  # pragma: no cover - compiled
    return max(min(a, b), min(max(a, b), c))


@numba.njit(cache=True)
def _median3_nearest(f: FloatArray) -> FloatArray:  # pragma: no cover - compiled
    """3 x 3 median with the edge pixels repeated (scipy.ndimage's ``mode="nearest"``).

    Each pixel's three columns of three are sorted; the median of the nine is the
    median of (the largest of the three minima, the median of the three medians, the
    smallest of the three maxima) (A. Paeth, Graphics Gems, 1990): one of the nine
    values, exactly.
    """
    h, w = f.shape
    out = np.empty_like(f)
    lo = np.empty(w)
    mid = np.empty(w)
    hi = np.empty(w)
    for r in range(h):
        ra, rb = max(r - 1, 0), min(r + 1, h - 1)
        for c in range(w):
            lo[c], mid[c], hi[c] = _sort3(f[ra, c], f[r, c], f[rb, c])
        for c in range(w):
            ca, cb = max(c - 1, 0), min(c + 1, w - 1)
            a = max(max(lo[ca], lo[c]), lo[cb])
            b = _med3(mid[ca], mid[c], mid[cb])
            d = min(min(hi[ca], hi[c]), hi[cb])
            out[r, c] = _med3(a, b, d)
    return out


def frame_paths(inputs: list[str] | tuple[str, ...]) -> list[Path]:
    """The frame files named by ``inputs`` (files, or folders searched for frame files).

    Raises
    ------
    InputError
        A path that does not exist, or a folder without frames.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import numpy as np
    >>> from firefleet.perception.thermal import frame_paths
    >>> folder = tempfile.TemporaryDirectory()
    >>> for name in ("b.npy", "a.npy", "notes.txt"):
    ...     _ = (pathlib.Path(folder.name) / name).write_bytes(b"")
    >>> [path.name for path in frame_paths([folder.name])]
    ['a.npy', 'b.npy']
    >>> folder.cleanup()
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
