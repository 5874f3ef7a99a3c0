"""Section 2.7 of the reproduction report: thermal imaging and stereo vision, with claims.

The deliverable's section 2.7 shows pictures (Figures 39-45) and no numbers. Each run
here shows the same kind of picture made by firefleet, on data whose answer is known,
and checks that answer as a claim:

- thermal imaging (2.7.1): real radiometric frames from FLIR cameras with known
  contents (when the caller has them), and a simulated Lepton (80 x 60, 51 degrees)
  looking at a fire and a person at known bearings;
- stereo vision (2.7.2): the Middlebury Motorcycle pair with its ground-truth
  disparity (shipped by scikit-image): depth against the truth; and the deliverable's
  own procedure, rectification without calibration from matched interest points
  (Figures 42-45), on the same pair warped by known homographies, so that the
  rectified rows can be checked point by point.

Nothing here reads or writes files: the caller passes arrays and writes what comes back.

References
----------
D. Scharstein et al., "High-resolution stereo datasets with subpixel-accurate ground
truth", GCPR 2014 (the Middlebury 2014 data set).
"""

from __future__ import annotations

import io
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.report.html import ReportRun
from firefleet.scenarios.schema import Claim
from firefleet.sim.metrics import metrics_document

__all__ = ["KNOWN_FRAMES", "stereo_runs", "thermal_run"]


KNOWN_FRAMES = {
    "flir_t420_frame0_celsius": "one small warm object near row 128, column 172, not a fire",
    "flir_duo_pro_r_frame0_celsius": "a fire-free outdoor scene",
}
"""The real frames the thermal run knows the answer of (shared data's README)."""

_T420_OBJECT_RC = (128.0, 172.0)
"""Where the T420 frame's warm object is [px] (row, column)."""


def _claim(metric: str, op: str, value: float, source: str, rel_tol: float = 0.0) -> Claim:
    return Claim(metric=metric, op=op, value=value, rel_tol=rel_tol, source=source)  # type: ignore[arg-type]


# ---------------------------------------------------------------- thermal imaging


def _simulated_scene() -> tuple[Any, FloatArray, dict[str, float]]:
    """A room seen by a robot's Lepton: a fire and a person at known bearings."""
    from firefleet.sim.sensors import ThermalScene

    walls = np.array([[8.0, -6.0, 8.0, 6.0], [0.0, 6.0, 8.0, 6.0], [0.0, -6.0, 8.0, -6.0]])
    scene = ThermalScene(
        walls_m=walls,
        wall_temp_c=np.full(3, 21.0),
        object_xy_m=np.array([[5.0, 1.2], [3.5, -1.0]]),
        object_size_m=np.array([[0.6, 0.8], [0.5, 1.7]]),
        object_temp_c=np.array([400.0, 34.0]),  # a pool fire; a clothed person's surface
    )
    pose = np.array([[0.0, 0.0, 0.0]])
    truth = {
        "fire": math.atan2(1.2, 5.0),
        "person": math.atan2(-1.0, 3.5),
    }
    return scene, pose, truth


def thermal_run(frames: Mapping[str, FloatArray], *, seed: int = 0) -> ReportRun:
    """Fires and people in real FLIR frames of known content and in a simulated Lepton.

    Parameters
    ----------
    frames : mapping of str to ndarray, shape (H, W)
        Real frames [C] by name; those named in :data:`KNOWN_FRAMES` are checked
        against their known answer, others are only shown. May be empty.
    seed : int
        Seed of the simulated camera's noise.

    Returns
    -------
    ReportRun
        Figures ``<frame>.png`` and ``simulated_lepton.png``; claims on the known frames
        (the T420's one warm object where it is, no fire alarm anywhere) and on the
        simulated frame (the fire and the person found, their bearings within one
        pixel's angle).
    """
    from firefleet.perception import thermal as th
    from firefleet.report.thermal import detection_png
    from firefleet.sim.sensors import ThermalCameraParams, render_thermal

    files: dict[str, bytes] = {}
    metrics: dict[str, float | list[float]] = {}
    claims: list[Claim] = []
    alarms = 0
    for name, frame in frames.items():
        camera = th.CameraModel.for_frame(frame.shape)
        found = th.detect(frame, camera=camera)
        files[f"{name}.png"] = detection_png(found.filtered_c, found, title=name)
        alarms += int(found.fire_alarm)
        if name == "flir_t420_frame0_celsius":
            warm = [d for d in found.detections if d.kind in ("warm", "person")]
            metrics["t420_warm_objects"] = float(len(warm))
            offsets = [math.dist(d.centroid_rc, _T420_OBJECT_RC) for d in warm]
            metrics["t420_warm_object_offset_px"] = min(offsets) if offsets else math.nan
    known = [n for n in frames if n in KNOWN_FRAMES]
    if "flir_t420_frame0_celsius" in frames:
        claims += [
            _claim(
                "t420_warm_objects",
                "~",
                1.0,
                "shared data README: one small warm object in the FLIR T420 frame",
                rel_tol=0.01,
            ),
            _claim(
                "t420_warm_object_offset_px",
                "<=",
                10.0,
                "shared data README: near row 128, column 172 (10 px: the object's size)",
            ),
        ]
    if known:
        metrics["fire_alarm_frames"] = float(alarms)
        claims.append(
            _claim(
                "fire_alarm_frames",
                "<=",
                0.0,
                "shared data README: neither real frame holds a fire (29.5 C at most)",
            )
        )

    scene, pose, truth = _simulated_scene()
    params = ThermalCameraParams()
    frame = render_thermal(scene, pose, params, rng=np.random.default_rng(seed))[0]
    found = th.detect(frame, camera=params.camera)
    files["simulated_lepton.png"] = detection_png(
        found.filtered_c, found, title="simulated Lepton 80 x 60: a fire and a person"
    )
    pixel_deg = math.degrees(params.camera.pixel_angle_rad)
    for kind in ("fire", "person"):
        hits = [d for d in found.detections if d.kind == kind]
        metrics[f"simulated_{kind}_found"] = float(len(hits))
        errors = [abs(math.degrees(d.bearing_rad - truth[kind])) for d in hits]
        metrics[f"simulated_{kind}_bearing_error_deg"] = min(errors) if errors else math.nan
        claims += [
            _claim(
                f"simulated_{kind}_found",
                "~",
                1.0,
                f"2.7.1: a thermal camera finds the {kind} (one in the scene)",
                rel_tol=0.01,
            ),
            _claim(
                f"simulated_{kind}_bearing_error_deg",
                "<=",
                round(pixel_deg, 3),
                "firefleet's bound: within one pixel's angle (51 deg / 80 px)",
            ),
        ]
    figures = (*(f"{n}.png" for n in frames), "simulated_lepton.png")
    return ReportRun(
        name="thermal",
        title="Thermal imaging: real FLIR frames and a simulated Lepton",
        reproduces="Section 2.7.1, Figure 39",
        deliverable_says=(
            'Thermal cameras "allow viewing through darkness or smoke, they make it easy '
            "for the firefighters to quickly find the seat of a structure fire, or see the "
            'heat signature of visually obscured victims"; the Lepton "offers a resolution '
            'of 80x60 pixels and a 51-deg Horizontal Field of View".'
        ),
        command="firefleet thermal FRAME...",
        files=files,
        figures=figures,
        document=metrics_document("thermal", tuple(claims), metrics),
    )


# ---------------------------------------------------------------- stereo vision

_MOTORCYCLE = {"focal_px": 994.978, "baseline_m": 0.193001, "doffs_px": 31.086}
"""skimage.data.stereo_motorcycle's calibration (its docstring; the down-sampled pair)."""

_WARPS = (
    np.array([[1.0, 0.02, 5.0], [0.01, 1.0, -4.0], [2e-5, -1e-5, 1.0]]),
    np.array([[0.99, -0.01, -3.0], [-0.015, 1.01, 6.0], [-1e-5, 2e-5, 1.0]]),
)
"""Known homographies that un-rectify the Motorcycle pair (a small tilt and keystone)."""


def _motorcycle() -> tuple[NDArray[np.uint8], NDArray[np.uint8], NDArray[np.float32]]:
    try:
        import skimage.data
    except ImportError as exc:  # pragma: no cover - scikit-image ships with the tests
        raise InputError("the stereo section needs scikit-image (its Motorcycle pair)") from exc
    left, right, gt = skimage.data.stereo_motorcycle()  # type: ignore[no-untyped-call]
    return (
        np.ascontiguousarray(left[..., ::-1]),  # RGB -> BGR, as OpenCV reads images
        np.ascontiguousarray(right[..., ::-1]),
        gt.astype(np.float32),
    )


def _png(fig: Any) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return buf.getvalue()


def _anaglyph_png(left: NDArray[Any], right: NDArray[Any], title: str) -> bytes:
    """Red-cyan composite of a pair (the deliverable's Figure 44): red left, cyan right."""
    from matplotlib.figure import Figure

    grey_l = left.mean(axis=2) if left.ndim == 3 else left.astype(float)
    grey_r = right.mean(axis=2) if right.ndim == 3 else right.astype(float)
    rgb = np.stack([grey_l, grey_r, grey_r], axis=2).astype(np.uint8)
    h, w = rgb.shape[:2]
    fig = Figure(figsize=(w / 100, h / 100 + 0.45), dpi=100)
    ax = fig.add_axes((0.0, 0.0, 1.0, h / (h + 45)))
    ax.imshow(rgb, interpolation="nearest")
    ax.set_axis_off()
    fig.suptitle(title, fontsize=11)
    return _png(fig)


def _matches_png(
    left: NDArray[Any],
    right: NDArray[Any],
    pts_l: NDArray[Any],
    pts_r: NDArray[Any],
    title: str,
) -> bytes:
    """Matched interest points drawn across the pair (the deliverable's 'SURF features')."""
    from matplotlib.figure import Figure

    def rgb(img: NDArray[Any]) -> NDArray[Any]:
        return np.repeat(img[..., None], 3, axis=2) if img.ndim == 2 else img[..., ::-1]

    both = np.concatenate([rgb(left), rgb(right)], axis=1)
    h, w = left.shape[:2]
    fig = Figure(figsize=(2 * w / 100, h / 100 + 0.45), dpi=100)
    ax = fig.add_axes((0.0, 0.0, 1.0, h / (h + 45)))
    ax.imshow(both, interpolation="nearest")
    step = max(1, len(pts_l) // 150)
    for (xl, yl), (xr, yr) in zip(pts_l[::step], pts_r[::step], strict=True):
        ax.plot([xl, xr + w], [yl, yr], color="yellow", lw=0.5, alpha=0.8)
    ax.plot(pts_l[::step, 0], pts_l[::step, 1], "r+", ms=4)
    ax.plot(pts_r[::step, 0] + w, pts_r[::step, 1], "c+", ms=4)
    ax.set_xlim(0, 2 * w)
    ax.set_ylim(h, 0)
    ax.set_axis_off()
    fig.suptitle(title, fontsize=11)
    return _png(fig)


def _calibrated_run(
    left: NDArray[np.uint8], right: NDArray[np.uint8], gt: NDArray[np.float32]
) -> ReportRun:
    from firefleet.perception import stereo as st
    from firefleet.report.stereo import disparity_png, rectified_pair_png

    result = st.compute_disparity(left, right, num_disparities=64)
    valid = np.isfinite(gt)
    valid[:, :64] = False  # the left strip has no match inside the right image
    err = np.abs(result.disparity - gt)[valid]
    bad = float(np.mean(~(err <= 2.0)))
    z = st.depth_from_disparity(result.disparity, **_MOTORCYCLE)
    f, b, d0 = _MOTORCYCLE["focal_px"], _MOTORCYCLE["baseline_m"], _MOTORCYCLE["doffs_px"]
    z_gt = f * b / (gt + d0)
    rel = np.abs(z - z_gt)[valid] / z_gt[valid]
    metrics: dict[str, float | list[float]] = {
        "bad_2px_pct": 100.0 * bad,
        "depth_median_rel_error_pct": 100.0
        * float(np.median(np.where(np.isnan(rel), np.inf, rel))),
        "measured_pct": 100.0 * float(result.measured[valid].mean()),
        "depth_min_m": float(np.nanmin(z_gt[valid])),
        "depth_max_m": float(np.nanmax(z_gt[valid])),
    }
    claims = (
        _claim(
            "depth_median_rel_error_pct",
            "<=",
            3.0,
            "firefleet's bound: depth within 3 % of the truth for the robot's range finding "
            "(2.7.2: 'compute the 3-D world points in actual units')",
        ),
        _claim(
            "bad_2px_pct",
            "<=",
            15.0,
            "firefleet's bound: under 15 % of pixels off the truth by more than 2 px "
            "(Middlebury's bad-2.0)",
        ),
    )
    lo, hi = (float(v) for v in np.percentile(gt[np.isfinite(gt)], [1, 99]))
    files = {
        "rectified_pair.png": rectified_pair_png(left, right),
        "disparity.png": disparity_png(result.disparity, vmin=lo, vmax=hi),
        "disparity_truth.png": disparity_png(
            np.where(np.isfinite(gt), gt, np.nan), vmin=lo, vmax=hi
        ),
    }
    return ReportRun(
        name="stereo-motorcycle",
        title="Stereo vision: depth of the Middlebury Motorcycle against its ground truth",
        reproduces="Section 2.7.2, Figures 42-43",
        deliverable_says=(
            "Stereo vision is the process of recovering depth from camera images by "
            'comparing two or more views of the same scene ... "Calibrating the stereo '
            'camera system allows us to compute the 3-D world points in actual units".'
        ),
        command="firefleet stereo LEFT RIGHT --rectified --focal-px F --baseline-m B",
        files=files,
        figures=tuple(files),
        document=metrics_document("stereo-motorcycle", claims, metrics),
        captions={
            "disparity.png": "firefleet's disparity (near is red; black: no value)",
            "disparity_truth.png": "the ground-truth disparity, same colours "
            "(black: no ground truth)",
        },
    )


def _uncalibrated_run(
    left: NDArray[np.uint8], right: NDArray[np.uint8], gt: NDArray[np.float32]
) -> ReportRun:
    import cv2

    from firefleet.perception import stereo as st
    from firefleet.report.stereo import rectified_pair_png

    h, w = gt.shape
    a, b = _WARPS
    wl = cv2.warpPerspective(left, a, (w, h))
    wr = cv2.warpPerspective(right, b, (w, h))
    ml, mr = st.match_features(wl, wr)
    rect = st.rectify_uncalibrated(wl, wr)
    if rect.h_left is None or rect.h_right is None:  # pragma: no cover - always set here
        raise InputError("uncalibrated rectification returned no homographies")
    # Ground-truth correspondences through the known warps and the estimated rectification.
    ys, xs = np.nonzero(np.isfinite(gt))
    pl = np.column_stack([xs, ys]).astype(float)
    pr = np.column_stack([xs - gt[ys, xs], ys]).astype(float)

    def apply(hm: FloatArray, p: FloatArray) -> FloatArray:
        q = p @ hm[:, :2].T + hm[:, 2]
        return np.asarray(q[:, :2] / q[:, 2:3])

    ql, qr = apply(rect.h_left @ a, pl), apply(rect.h_right @ b, pr)
    inside = (ql[:, 0] >= 0) & (ql[:, 0] < w) & (ql[:, 1] >= 0) & (ql[:, 1] < h)
    before = np.abs(apply(a, pl)[:, 1] - apply(b, pr)[:, 1])
    after = np.abs(ql[inside, 1] - qr[inside, 1])
    rl, rr = st.rectify_pair(wl, wr, rect)
    metrics: dict[str, float | list[float]] = {
        "matches": float(len(ml)),
        "row_offset_before_median_px": float(np.median(before)),
        "row_offset_after_median_px": float(np.median(after)),
        "scene_in_frame_pct": 100.0 * float(inside.mean()),
    }
    claims = (
        _claim(
            "row_offset_after_median_px",
            "<=",
            0.5,
            "2.7.2.6: after rectification 'corresponding points will appear on the same rows' "
            "(firefleet's bound: half a pixel)",
        ),
        _claim(
            "scene_in_frame_pct",
            ">=",
            90.0,
            "firefleet's bound: the rectified left image keeps the scene in frame",
        ),
    )
    files = {
        "composite_before.png": _anaglyph_png(
            wl, wr, "Fig. 44: composite of the pair as captured (red left, cyan right)"
        ),
        "matched_features.png": _matches_png(
            wl, wr, ml, mr, f"interest points matched in both images ({len(ml)} SIFT matches)"
        ),
        "rectified.png": rectified_pair_png(rl, rr),
        "composite_after.png": _anaglyph_png(
            rl, rr, "Fig. 45: the rectified pair: corresponding points on the same rows"
        ),
    }
    return ReportRun(
        name="stereo-uncalibrated",
        title="Stereo vision: rectification without calibration, as the deliverable did it",
        reproduces="Section 2.7.2.6, Figures 44-45",
        deliverable_says=(
            "Read Stereo Image Pair; Collect Interest Points from Each Image; Rectify "
            'Images: the transformations are computed "in such a way that ... the '
            'corresponding epipolar lines will be in the same rows".'
        ),
        command="firefleet stereo LEFT RIGHT --uncalibrated",
        files=files,
        figures=tuple(files),
        document=metrics_document("stereo-uncalibrated", claims, metrics),
    )


def stereo_runs() -> tuple[ReportRun, ReportRun]:
    """The two stereo entries: depth against the truth, and uncalibrated rectification.

    Returns
    -------
    (ReportRun, ReportRun)
        ``stereo-motorcycle`` (the rectified pair, our disparity and the true one; depth
        error and bad-pixel share claimed) and ``stereo-uncalibrated`` (the pair warped by
        two known homographies, rectified from SIFT matches: composite before and after,
        the matches, the rectified pair; the median row offset of ground-truth
        correspondences claimed).

    Raises
    ------
    InputError
        If scikit-image (which ships the Motorcycle pair) is not installed.
    """
    left, right, gt = _motorcycle()
    return _calibrated_run(left, right, gt), _uncalibrated_run(left, right, gt)
