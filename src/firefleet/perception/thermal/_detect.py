"""Detection of fires, people and warm objects in one frame, with bearing and range."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError, check_fields
from firefleet.perception.thermal._camera import (
    CameraModel,
)
from firefleet.perception.thermal._detect_kernel import describe_region, filter_frame, find_regions
from firefleet.perception.thermal._frames import check_frame, denoise
from firefleet.perception.thermal._radiometry import _radiance_table

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
    flame_core_c : float or None
        ``None`` (default): a fire region is one detection. Else a fire region holding
        pixels at or above this [C] is reported as its *flame cores* instead, one
        detection per connected group of them, each with its own bearing and range:
        the hot gas a fire pushes out of a room reads above ``fire_min_c`` over much
        of a frame that looks at the room's door, and one region over all of it has
        its centroid and median depth on the gas and the walls near the camera, not on
        the flames (the Lepton's low-gain range saturates at about 450 C; flames read
        there, the gas less).

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
    flame_core_c: float | None = None

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
        if self.flame_core_c is not None:
            check_fields(self, "detection", positive=("flame_core_c",))
            if self.flame_core_c < self.fire_min_c:
                raise InputError(
                    f"detection.flame_core_c {self.flame_core_c} must be at least "
                    f"fire_min_c {self.fire_min_c}"
                )
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


def _measure(
    stats: FloatArray, camera: CameraModel, shape: tuple[int, int], box: tuple[int, int, int, int]
) -> tuple[float, float, float, bool, bool]:
    """Bearing and angular width/height of a region from its sub-pixel centre and extent
    (:func:`~firefleet.perception.thermal._detect_kernel.describe_region`: the fraction of
    each pixel the object fills in band radiance; an upright box fills ``a_i b_j``, so
    the width is the sum of the column profile, the height that of the row profile in
    the column nearest the centre over that column's fill).

    Returns (bearing [rad], angular width [rad], ``tan(top) - tan(bottom)`` of the
    elevations of its top and bottom edges, cut horizontally, cut vertically).
    """
    h, w = shape
    r0, c0, r1, c1 = box
    cut_h = c0 == 0 or c1 == w
    cut_v = r0 == 0 or r1 == h
    if stats[7] < 0.5:  # cannot happen for a region above its surround; keep the centroid
        return float(camera.bearing(stats[3], stats[4])), math.nan, math.nan, True, True
    rc, cc, hpx, wpx = float(stats[8]), float(stats[9]), float(stats[10]), float(stats[11])
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


@functools.lru_cache(maxsize=1)
def _default_params() -> DetectionParams:
    """The default thresholds (made once: a robot calls :func:`detect` nine times a second)."""
    return DetectionParams()


@functools.lru_cache(maxsize=8)
def _default_camera(shape: tuple[int, ...]) -> CameraModel:
    """The default camera of a frame size (made once per size)."""
    return CameraModel.for_frame(shape)


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
    p = _default_params() if params is None else params
    raw = check_frame(frame_c)
    cam = _default_camera(raw.shape) if camera is None else camera
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
    flat, f = filter_frame(raw, p.destripe, 1.0, p.median_size == 3, p.fire_contrast_min_c)
    if p.median_size != 3:  # another median (or none): SciPy's, fire-hot pixels kept
        f = denoise(flat, median_size=p.median_size, stripes=False)
        f = np.where(flat >= p.fire_contrast_min_c, flat, f)
    size = p.background_px if p.background_px is not None else max(15, raw.shape[1] // 3)
    background, _, low, labels, top, areas, boxes = find_regions(
        f, p.fire_contrast_min_c, p.warm_contrast_k, int(size)
    )
    keep = np.flatnonzero((top >= p.warm_contrast_k) & (areas >= p.min_area_px))
    found: list[Detection] = []
    if keep.size:
        table_c, table_rad = _radiance_table((8.0, 14.0))
        has_depth = depth is not None
        depth_arr = depth if depth is not None else f
        for i in keep:
            box = (int(boxes[i, 0]), int(boxes[i, 1]), int(boxes[i, 2]), int(boxes[i, 3]))
            stats = describe_region(
                f,
                labels,
                low,
                int(i) + 1,
                boxes[i],
                background,
                p.fire_min_c,
                p.fire_contrast_min_c,
                p.fire_contrast_k,
                table_c,
                table_rad,
                depth_arr,
                has_depth,
            )
            if stats[15] > 0.5:  # band_radiance's table does not reach
                raise InputError(f"temperatures must be finite, in [{table_c[0]}, {table_c[-1]}] C")
            if stats[6] > 0.5 and p.flame_core_c is not None and stats[0] >= p.flame_core_c:
                core_labels, core_boxes = _flame_cores(f, labels == int(i) + 1, p)
                for j, cb in enumerate(core_boxes):
                    core = describe_region(
                        f, core_labels, low, j + 1, cb, background, p.fire_min_c,
                        p.fire_contrast_min_c, p.fire_contrast_k, table_c, table_rad,
                        depth_arr, has_depth,
                    )  # fmt: skip
                    cbox = (int(cb[0]), int(cb[1]), int(cb[2]), int(cb[3]))
                    found.append(_describe(core, cbox, f.shape, cam, p))
                if len(core_boxes):
                    continue
            found.append(_describe(stats, box, f.shape, cam, p))
    order = {"fire": 0, "person": 1, "warm": 2}
    found.sort(key=lambda d: (order[d.kind], -d.peak_c))
    return FrameDetections(detections=tuple(found), background_c=background, filtered_c=f)


def _flame_cores(
    f: FloatArray, region: np.ndarray, p: DetectionParams
) -> tuple[np.ndarray, np.ndarray]:
    """The flame cores of a fire region (``DetectionParams.flame_core_c``): labels (H, W)
    of the 8-connected groups of its pixels at or above ``flame_core_c`` with at least
    ``min_area_px`` pixels (1..K, 0 elsewhere), and their boxes (K, 4) [r0, c0, r1, c1)."""
    import scipy.ndimage as ndi

    assert p.flame_core_c is not None
    lab, k = ndi.label(region & (f >= p.flame_core_c), structure=np.ones((3, 3), dtype=bool))
    sizes = np.bincount(lab.ravel(), minlength=k + 1)
    big = np.flatnonzero(sizes[1:] >= p.min_area_px) + 1
    out = np.zeros(f.shape, dtype=np.int32)  # as ``find_regions``' labels
    boxes = np.zeros((len(big), 4), dtype=np.int64)
    slices = ndi.find_objects(lab)
    for j, old in enumerate(big):
        out[lab == old] = j + 1
        rs, cs = slices[old - 1]
        boxes[j] = (rs.start, cs.start, rs.stop, cs.stop)
    return out, boxes


def _describe(
    stats: FloatArray,
    box: tuple[int, int, int, int],
    shape: tuple[int, int],
    cam: CameraModel,
    p: DetectionParams,
) -> Detection:
    """A region's detection from its numbers (``describe_region``): kind, bearing, range."""
    peak, mean, surround = float(stats[0]), float(stats[1]), float(stats[5])
    centroid = (float(stats[3]), float(stats[4]))
    is_fire = stats[6] > 0.5
    bearing, ang_w, dtan_v, cut_h, cut_v = _measure(stats, cam, shape, box)
    stereo = None
    if stats[12] > 0.5:
        z, spread = float(stats[13]), float(stats[14])
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
        bbox_rc=box,
        peak_c=peak,
        mean_c=mean,
        area_px=int(stats[2]),
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
