"""The NumPy / SciPy thermal detector the compiled one replaced: the reference that
tests/perception/test_detect_kernel.py compares it with (the same arithmetic, with
scipy.ndimage's grey opening, labelling and per-label reductions)."""

# mypy: ignore-errors
from __future__ import annotations

import math

import numpy as np
import scipy.ndimage as ndi
from numpy.typing import ArrayLike, NDArray

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.perception.thermal import CameraModel, band_radiance, denoise, destripe
from firefleet.perception.thermal._detect import (
    Detection,
    DetectionParams,
    FrameDetections,
    Kind,
    _size_range,
)
from firefleet.perception.thermal._frames import check_frame


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


def detect_reference(
    frame_c: ArrayLike,
    *,
    camera: CameraModel | None = None,
    params: DetectionParams | None = None,
    depth_m: ArrayLike | None = None,
) -> FrameDetections:
    """The NumPy / SciPy detector as it was before compilation (the reference)."""
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
