"""Detection of fires, people and warm objects in one frame, with bearing and range."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import scipy.ndimage as ndi
from numpy.typing import ArrayLike, NDArray

from firefleet._typing import FloatArray
from firefleet.errors import InputError, check_fields
from firefleet.perception.thermal._camera import (
    CameraModel,
)
from firefleet.perception.thermal._frames import check_frame, denoise, destripe
from firefleet.perception.thermal._radiometry import band_radiance

Kind = Literal["fire", "person", "warm"]


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

    Examples
    --------
    >>> from firefleet.perception.thermal import DetectionParams
    >>> params = DetectionParams()
    >>> params == DetectionParams()
    True
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

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal import detect
    >>> frame = np.full((60, 80), 20.0)
    >>> frame[25:31, 37:43] = 400.0
    >>> fire = detect(frame).detections[0]
    >>> fire.kind, fire.area_px, fire.bbox_rc, round(fire.peak_c, 1)
    ('fire', 36, (25, 37, 31, 43), 400.0)
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

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal import detect
    >>> result = detect(np.full((60, 80), 20.0))
    >>> result.detections, result.fire_alarm, round(result.background_c, 3)
    ((), False, 20.0)
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

    Examples
    --------
    >>> import math
    >>> from firefleet.perception.thermal import range_from_size
    >>> r, sigma = range_from_size(2 * math.atan(0.25), 0.5)  # 0.5 m wide, seen at 1 m
    >>> round(float(r), 12), float(sigma)
    (1.0, 0.0)
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

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal import detect
    >>> frame = np.full((60, 80), 20.0)
    >>> frame[25:31, 37:43] = 400.0  # a 6 x 6 px fire on the optical axis
    >>> result = detect(frame)
    >>> fire = result.detections[0]
    >>> len(result.detections), fire.kind, result.fire_alarm, round(fire.bearing_rad, 4)
    (1, 'fire', True, 0.0)
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


def detections_document(name: str, result: FrameDetections) -> dict[str, Any]:
    """The ``detections.json`` entry of one frame.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.thermal import detect, detections_document
    >>> document = detections_document("frame.npy", detect(np.full((60, 80), 20.0)))
    >>> document
    {'frame': 'frame.npy', 'fire_alarm': False, 'background_c': 20.0, 'detections': []}
    """
    return {
        "frame": name,
        "fire_alarm": result.fire_alarm,
        "background_c": round(result.background_c, 3),
        "detections": [d.to_json() for d in result.detections],
    }
