"""Stereo: calibration, rectification, disparity, depth, clouds and range scans.

Ground truth comes from synthetic data (chessboards rendered through a known camera
pair, textured layers with known disparity) and from the Middlebury Motorcycle pair
that ships with scikit-image (ground-truth disparity and calibration in its docstring).
"""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest
import skimage.data
from numpy.typing import NDArray

from firefleet.errors import InputError
from firefleet.perception import stereo as st
from tests.perception.synthetic import PATTERN, SIZE, SQUARE_M, Rig, stereo_chessboards

Image = NDArray[np.uint8]

# Motorcycle calibration, from skimage.data.stereo_motorcycle's docstring (valid for the
# 4x down-sampled images it ships: the full-size Middlebury values divided by 4).
MOTO_F_PX = 994.978
MOTO_B_M = 0.193001
MOTO_DOFFS_PX = 31.086
MOTO_CX, MOTO_CY = 311.193, 254.877


@pytest.fixture(scope="module")
def chessboards() -> tuple[Rig, list[Image], list[Image], st.StereoCalibration]:
    rig, lefts, rights = stereo_chessboards(10)
    calib = st.calibrate_stereo(lefts, rights, pattern_size=PATTERN, square_size_m=SQUARE_M)
    return rig, lefts, rights, calib


@pytest.fixture(scope="module")
def motorcycle() -> tuple[Image, Image, NDArray[np.float32]]:
    left, right, gt = skimage.data.stereo_motorcycle()  # type: ignore[no-untyped-call]
    return (
        np.ascontiguousarray(left[..., ::-1]),  # RGB -> BGR, as cv2.imread gives
        np.ascontiguousarray(right[..., ::-1]),
        gt.astype(np.float32),
    )


def bad_fraction(disp: NDArray[np.float32], gt: NDArray[np.float32], thr: float = 2.0) -> float:
    """Middlebury bad-thr over valid ground truth and columns >= 64; no value = bad."""
    valid = np.isfinite(gt)
    valid[:, :64] = False
    err = np.abs(disp - gt)[valid]
    return float(np.mean(~(err <= thr)))


# ------------------------------------------------------------------ calibration


def test_calibration_recovers_focal_length_and_baseline(
    chessboards: tuple[Rig, list[Image], list[Image], st.StereoCalibration],
) -> None:
    rig, _, _, calib = chessboards
    assert calib.image_size == SIZE
    # Acceptance: focal length and baseline within 1 %, reprojection error <= 0.5 px.
    for k_est, k_true in ((calib.k_left, rig.k_left), (calib.k_right, rig.k_right)):
        assert k_est[0, 0] == pytest.approx(k_true[0, 0], rel=0.01)
        assert k_est[1, 1] == pytest.approx(k_true[1, 1], rel=0.01)
    assert calib.baseline_m == pytest.approx(float(np.linalg.norm(rig.translation_m)), rel=0.01)
    assert calib.rms_px <= 0.5
    # The rotation between the cameras: within 0.2 degrees (a 1 % baseline-class error
    # on a 12 cm rig over the board's 0.5-0.8 m depths).
    r_err = cv2.Rodrigues(calib.rotation @ rig.rotation.T)[0]
    assert math.degrees(float(np.linalg.norm(r_err))) < 0.2


def test_calibration_file_round_trip_and_errors(
    chessboards: tuple[Rig, list[Image], list[Image], st.StereoCalibration], tmp_path: Path
) -> None:
    calib = chessboards[3]
    path = tmp_path / "rig.yaml"
    path.write_text(st.calibration_yaml(calib), encoding="utf-8")
    back = st.load_calibration(path)
    assert back.image_size == calib.image_size
    for name in ("k_left", "dist_left", "k_right", "dist_right", "rotation", "translation_m"):
        np.testing.assert_array_equal(getattr(back, name), getattr(calib, name))  # exact: repr
    assert back.rms_px == calib.rms_px
    text = path.read_text()
    (tmp_path / "nofield.yaml").write_text(text.replace("translation_m:", "translation:"))
    with pytest.raises(InputError, match="missing field translation_m"):
        st.load_calibration(tmp_path / "nofield.yaml")
    (tmp_path / "bad.yaml").write_text("format: [unclosed\n")
    with pytest.raises(InputError, match="not a YAML calibration"):
        st.load_calibration(tmp_path / "bad.yaml")
    with pytest.raises(InputError, match="no such calibration file"):
        st.load_calibration(tmp_path / "missing.yaml")


def test_calibration_needs_three_boards() -> None:
    blank = np.full((480, 640), 128, np.uint8)
    with pytest.raises(InputError, match="at least 3 pairs"):
        st.calibrate_stereo([blank] * 3, [blank] * 3)


def test_calibrated_rectification_aligns_rows_and_gives_metric_depth(
    chessboards: tuple[Rig, list[Image], list[Image], st.StereoCalibration],
) -> None:
    _, lefts, rights, calib = chessboards
    rect = st.rectify_calibrated(calib)
    assert rect.calibrated
    dy_all, squares = [], []
    for lft, rgt in zip(lefts, rights, strict=True):
        rl, rr = st.rectify_pair(lft, rgt, rect)
        cl = st.find_chessboard(rl, pattern_size=PATTERN)
        cr = st.find_chessboard(rr, pattern_size=PATTERN)
        if cl is None or cr is None:  # alpha = 0 crops: a board near the edge can leave
            continue
        dy_all.append(np.abs(cl[:, 1] - cr[:, 1]))
        d = cl[:, 0] - cr[:, 0]
        z = rect.focal_px * rect.baseline_m / (d + rect.doffs_px)
        pts = np.column_stack(
            [
                (cl[:, 0] - rect.cx_px) * z / rect.focal_px,
                (cl[:, 1] - rect.cy_px) * z / rect.focal_px,
                z,
            ]
        ).reshape(PATTERN[1], PATTERN[0], 3)
        squares.append(np.linalg.norm(np.diff(pts, axis=1), axis=2).ravel())
    assert len(dy_all) >= 5
    # Rows aligned to well under the 0.5 px floor (sub-pixel corners are ~0.05 px).
    assert float(np.median(np.concatenate(dy_all))) < 0.2
    # Triangulated corners are one square apart: 3 cm within 1 % (the calibration's
    # focal/baseline error budget).
    assert float(np.mean(np.concatenate(squares))) == pytest.approx(SQUARE_M, rel=0.01)


def test_rectify_pair_rejects_a_calibration_for_another_size(
    chessboards: tuple[Rig, list[Image], list[Image], st.StereoCalibration],
) -> None:
    rect = st.rectify_calibrated(chessboards[3])
    small = np.zeros((240, 320), np.uint8)
    with pytest.raises(InputError, match="calibration is for 640 x 480"):
        st.rectify_pair(small, small, rect)


# ---------------------------------------------------------- uncalibrated rectification


def _rotation_h(rvec: tuple[float, float, float]) -> NDArray[np.float64]:
    """Homography of a camera rotation about its centre, K R K^-1 (Motorcycle's K)."""
    k = np.array([[MOTO_F_PX, 0, MOTO_CX], [0, MOTO_F_PX, MOTO_CY], [0, 0, 1.0]])
    rot = cv2.Rodrigues(np.array(rvec))[0]
    return np.asarray(k @ rot @ np.linalg.inv(k))


UNRECTIFY = {
    "rotations": (_rotation_h((0.01, -0.015, 0.02)), _rotation_h((-0.012, 0.01, -0.025))),
    "projective": (
        np.array([[1.0, 0.02, 5.0], [0.01, 1.0, -4.0], [2e-5, -1e-5, 1.0]]),
        np.array([[0.99, -0.01, -3.0], [-0.015, 1.01, 6.0], [-1e-5, 2e-5, 1.0]])
        @ _rotation_h((0.0, 0.0, 0.03)),
    ),
}


@pytest.mark.parametrize("case", sorted(UNRECTIFY))
def test_uncalibrated_rectification_of_warped_motorcycle(
    motorcycle: tuple[Image, Image, NDArray[np.float32]], case: str
) -> None:
    left, right, gt = motorcycle
    h, w = gt.shape
    a, b = UNRECTIFY[case]
    wl = cv2.warpPerspective(left, a, (w, h))
    wr = cv2.warpPerspective(right, b, (w, h))
    rect = st.rectify_uncalibrated(wl, wr)
    assert not rect.calibrated
    assert rect.h_left is not None
    assert rect.h_right is not None
    # Ground-truth correspondences (left (x, y) <-> right (x - d, y)) through the known
    # warps and the estimated rectification: their rows must agree.
    ys, xs = np.nonzero(np.isfinite(gt))
    pl = np.column_stack([xs, ys]).astype(float)
    pr = np.column_stack([xs - gt[ys, xs], ys]).astype(float)

    def apply(hm: NDArray[np.float64], p: NDArray[np.float64]) -> NDArray[np.float64]:
        q = p @ hm[:, :2].T + hm[:, 2]
        return q[:, :2] / q[:, 2:3]

    ql, qr = apply(rect.h_left @ a, pl), apply(rect.h_right @ b, pr)
    inside = (ql[:, 0] >= 0) & (ql[:, 0] < w) & (ql[:, 1] >= 0) & (ql[:, 1] < h)
    assert inside.mean() > 0.9  # the rectified left image keeps the scene in frame
    # Acceptance: median vertical offset of corresponding points <= 0.5 px.
    assert float(np.median(np.abs(ql[inside, 1] - qr[inside, 1]))) <= 0.5
    # Disparities of the scene fall inside the search range the rectification proposes.
    d = ql[inside, 0] - qr[inside, 0]
    lo, hi = np.percentile(d, [1, 99])
    assert rect.min_disparity <= lo
    assert hi < rect.min_disparity + rect.num_disparities
    # Re-detected matches on the rectified pair agree too (the same floor).
    rl, rr = st.rectify_pair(wl, wr, rect)
    ml, mr = st.match_features(rl, rr)
    assert len(ml) > 100
    assert float(np.median(np.abs(ml[:, 1] - mr[:, 1]))) <= 0.5


def test_uncalibrated_rectification_needs_texture() -> None:
    flat = np.full((120, 160), 90, np.uint8)
    with pytest.raises(InputError, match="interest-point matches"):
        st.rectify_uncalibrated(flat, flat)


# -------------------------------------------------------------------- disparity


def layered_pair(
    d_back: float = 8.0, d_front: float = 20.0
) -> tuple[Image, Image, NDArray[np.float32]]:
    """Textured background at disparity ``d_back``, a textured square at ``d_front``.

    Returns the left and right images and the true disparity of the left image.
    """
    rng = np.random.default_rng(3)
    h, w = 160, 240
    back = cv2.GaussianBlur(rng.integers(0, 256, (h, w + 64)).astype(np.uint8), (0, 0), 1.0)
    front = cv2.GaussianBlur(rng.integers(0, 256, (60, 70)).astype(np.uint8), (0, 0), 1.0)
    y0, x0 = 50, 120
    left = back[:, 32 : 32 + w].copy()
    right = back[:, 32 + int(d_back) : 32 + int(d_back) + w].copy()
    left[y0 : y0 + 60, x0 : x0 + 70] = front
    xr = x0 - int(d_front)
    right[y0 : y0 + 60, xr : xr + 70] = front
    gt = np.full((h, w), d_back, np.float32)
    gt[y0 : y0 + 60, x0 : x0 + 70] = d_front
    return np.asarray(left, np.uint8), np.asarray(right, np.uint8), gt


def test_disparity_of_layers_with_occlusion_filled_from_the_background() -> None:
    left, right, gt = layered_pair()
    res = st.compute_disparity(left, right, num_disparities=32)
    inner = np.zeros_like(gt, dtype=bool)
    inner[4:-4, 40:-4] = True  # away from the borders SGBM cannot match
    # Exact integer shifts of one texture: SGBM's sub-pixel estimate is within 0.25 px
    # (its 1/16 px output, parabola bias on a blurred texture) nearly everywhere.
    err = np.abs(res.disparity - gt)
    assert np.mean(err[inner] <= 0.25) > 0.97
    # The strip just left of the square is seen by the left camera only (occluded
    # in the right); it must be rejected by the checks and filled from the background.
    strip = np.zeros_like(inner)
    strip[55:105, 109:119] = True  # 12 px wide occlusion (20 - 8), 1 px margin
    assert res.measured[strip].mean() < 0.5
    assert float(np.median(res.disparity[strip])) == pytest.approx(8.0, abs=0.5)
    assert np.all(res.confidence[~res.measured] == 0.0)
    assert res.confidence[inner & res.measured].mean() > 0.8  # smooth, supported surface
    # Plain SGBM leaves the occlusion without a value (the reason for filling).
    plain = st.sgbm_disparity(left, right, num_disparities=32)
    assert np.isnan(plain[strip]).mean() > 0.5


def test_fractional_shifts_are_ordered_and_within_sgbm_pixel_locking() -> None:
    rng = np.random.default_rng(5)
    tex = cv2.GaussianBlur(rng.integers(0, 256, (120, 260)).astype(np.uint8), (0, 0), 1.5)
    shifts = np.arange(11.0, 12.001, 0.125)
    medians = []
    for shift in shifts:
        warp = np.array([[1.0, 0.0, -shift], [0.0, 1.0, 0.0]])
        right = cv2.warpAffine(tex, warp, (260, 120))
        core = st.compute_disparity(tex, right, num_disparities=32).disparity[10:-10, 50:-20]
        medians.append(float(np.median(core)))
    # Sub-pixel output follows the true shift in order, and stays within 0.35 px of it:
    # SGBM's parabola over Birchfield-Tomasi costs is pixel-locked (estimates pulled to
    # integers; 0.31 px measured worst case at shift 11.625 on this texture).
    assert np.all(np.diff(medians) >= 0)
    assert medians[4] not in (11.0, 12.0)  # shift 11.5: a sub-pixel value, not an integer
    np.testing.assert_allclose(medians, shifts, atol=0.35)


def test_motorcycle_ours_has_30pct_fewer_bad_pixels_than_plain_sgbm(
    motorcycle: tuple[Image, Image, NDArray[np.float32]],
) -> None:
    left, right, gt = motorcycle
    ours = st.compute_disparity(left, right, num_disparities=64).disparity
    bad_ours = bad_fraction(ours, gt)
    for block in (3, 5):  # the two block sizes a user would pick; the floor holds for both
        bad_plain = bad_fraction(st.sgbm_disparity(left, right, block_size=block), gt)
        # Acceptance: at least 30 % fewer bad-2.0 pixels than plain SGBM.
        assert bad_ours <= 0.70 * bad_plain, (block, bad_ours, bad_plain)
    # Depth from the docstring's calibration: median relative error <= 3 % (acceptance),
    # over pixels with valid ground truth and columns >= 64.
    z = st.depth_from_disparity(
        ours, focal_px=MOTO_F_PX, baseline_m=MOTO_B_M, doffs_px=MOTO_DOFFS_PX
    )
    z_gt = MOTO_F_PX * MOTO_B_M / (gt + MOTO_DOFFS_PX)
    valid = np.isfinite(gt)
    valid[:, :64] = False
    rel = np.abs(z - z_gt)[valid] / z_gt[valid]
    assert float(np.median(np.where(np.isnan(rel), np.inf, rel))) <= 0.03


def test_disparity_bad_input() -> None:
    a = np.zeros((100, 120), np.uint8)
    with pytest.raises(InputError, match="differ in size"):
        st.compute_disparity(a, np.zeros((100, 121), np.uint8))
    with pytest.raises(InputError, match="uint8"):
        st.compute_disparity(a.astype(np.float32), a)
    with pytest.raises(InputError, match="multiple of 16"):
        st.compute_disparity(a, a, num_disparities=40)
    with pytest.raises(InputError, match="channel"):
        st.check_pair(a, np.zeros((100, 120, 3), np.uint8))


def test_read_image_errors(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such image file"):
        st.read_image(tmp_path / "none.png")
    (tmp_path / "empty.png").write_bytes(b"")
    with pytest.raises(InputError, match="not a readable image"):
        st.read_image(tmp_path / "empty.png")
    (tmp_path / "junk.png").write_bytes(b"\x89PNG\r\n\x1a\nthis is not a png")
    with pytest.raises(InputError, match="not a readable image"):
        st.read_image(tmp_path / "junk.png")


# ----------------------------------------------------------- depth, cloud, scan


def test_depth_and_point_cloud_of_a_plane() -> None:
    f, b, cx, cy = 500.0, 0.1, 40.0, 30.0
    disp = np.full((60, 80), 25.0, np.float32)  # Z = 500 * 0.1 / 25 = 2 m
    disp[0, 0] = np.nan
    disp[0, 1] = -3.0  # d + doffs <= 0: at infinity, no depth
    z = st.depth_from_disparity(disp, focal_px=f, baseline_m=b, doffs_px=2.0)
    assert np.isnan(z[0, 0])
    assert np.isnan(z[0, 1])
    np.testing.assert_allclose(z[1:], f * b / 27.0, rtol=1e-6)  # float32 arithmetic
    pts, rgb = st.point_cloud(disp, focal_px=f, baseline_m=b, cx_px=cx, cy_px=cy)
    assert pts.shape == (60 * 80 - 2, 3)
    assert rgb.shape == (60 * 80 - 2, 3)
    np.testing.assert_allclose(pts[:, 2], 2.0, rtol=1e-6)
    # Pixel (x=79, y=59) is the last point: X = (79 - 40) * 2 / 500, Y = (59 - 30) * 2 / 500.
    np.testing.assert_allclose(pts[-1], [39 * 2 / 500, 29 * 2 / 500, 2.0], rtol=1e-6)
    with pytest.raises(InputError, match="baseline_m"):
        st.depth_from_disparity(disp, focal_px=f, baseline_m=0.0)


def test_ply_file_layout() -> None:
    pts = np.array([[0.0, 1.0, 2.0], [-1.5, 0.25, 3.0]])
    rgb = np.array([[255, 0, 10], [1, 2, 3]], np.uint8)
    data = st.ply_bytes(pts, rgb)
    header, body = data.split(b"end_header\n")
    lines = header.decode("ascii").splitlines()
    assert lines[:2] == ["ply", "format binary_little_endian 1.0"]
    assert "element vertex 2" in lines
    props = [ln.split()[1:] for ln in lines if ln.startswith("property")]
    assert props == [
        ["float", "x"],
        ["float", "y"],
        ["float", "z"],
        ["uchar", "red"],
        ["uchar", "green"],
        ["uchar", "blue"],
    ]
    assert len(body) == 2 * 15  # 3 float32 + 3 uint8 per vertex, no padding
    rec = np.frombuffer(
        body, dtype=[("xyz", "<f4", 3), ("rgb", "u1", 3)]
    )  # the layout the header declares
    np.testing.assert_array_equal(rec["xyz"], pts.astype(np.float32))
    np.testing.assert_array_equal(rec["rgb"], rgb)


def test_range_scan_of_a_wall_and_a_post() -> None:
    # A wall 2 m ahead (Z = 2) from X = -3 to 3, and a post at bearing +10 deg, 1 m away.
    xs = np.linspace(-3.0, 3.0, 6001)
    wall = np.column_stack([xs, np.zeros_like(xs), np.full_like(xs, 2.0)])
    post_b = math.radians(10.0)
    post = np.array([[-math.sin(post_b), 0.0, math.cos(post_b)]] * 3)  # X right: -sin
    fov = math.radians(90.0)
    scan = st.range_scan(np.vstack([wall, post]), n_sectors=9, fov_rad=fov)
    assert scan.range_m.shape == (9,)
    assert scan.edges_rad.shape == (10,)
    # Wall: nearest point of a sector is at its edge closest to the axis, 2 / cos(edge);
    # 1 mm spacing of the points along the wall gives < 1e-3 m error.
    near_edge = np.minimum(np.abs(scan.edges_rad[:-1]), np.abs(scan.edges_rad[1:]))
    near_edge[4] = 0.0  # the middle sector contains the axis
    expected = 2.0 / np.cos(near_edge)
    sector_post = int(np.searchsorted(scan.edges_rad, post_b) - 1)
    expected[sector_post] = 1.0
    np.testing.assert_allclose(scan.range_m, expected, atol=1e-3)
    # min_points = 5 ignores the 3-point post; a height band excludes the wall (Y = 0).
    scan5 = st.range_scan(np.vstack([wall, post]), n_sectors=9, fov_rad=fov, min_points=5)
    assert scan5.range_m[sector_post] > 1.5
    none = st.range_scan(wall, n_sectors=9, fov_rad=fov, height_band_m=(0.1, 0.5))
    assert np.all(np.isinf(none.range_m))
    assert none.count.sum() == 0


def test_uncalibrated_rectification_of_a_degenerate_pair_is_an_input_error() -> None:
    # noise and its own 8 px shift: every match lies on one horizontal displacement, a
    # degenerate set on which OpenCV's fundamental-matrix fit asserts (was a cv2.error)
    noise = np.random.default_rng(0).integers(0, 256, (120, 160), dtype=np.uint8)
    with pytest.raises(InputError, match="uncalibrated rectification"):
        st.rectify_uncalibrated(noise, np.roll(noise, 8, axis=1))
