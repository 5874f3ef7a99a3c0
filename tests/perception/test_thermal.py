"""Thermal frames, radiometry, filtering, detection, bearing and range."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest
import scipy.integrate
from numpy.typing import NDArray

from firefleet.errors import InputError
from firefleet.perception.thermal import (
    CameraModel,
    DetectionParams,
    LinearCalibration,
    band_radiance,
    celsius_to_counts,
    counts_to_celsius,
    denoise,
    destripe,
    detect,
    radiance_to_celsius,
    range_from_size,
    read_frame,
)

DATA = Path(__file__).resolve().parents[1] / "data" / "thermal"


def _real(name: str) -> NDArray[np.float32]:
    with np.load(DATA / f"{name}.npz") as npz:
        return np.asarray(npz["celsius"])


# ------------------------------------------------------------------------- real frames


def test_t420_frame_one_warm_object_near_row_128_col_172_no_fire() -> None:
    frame = _real("flir_t420_frame0_celsius")
    # FLIR T420 standard lens: 25 degree HFOV (the bearing only; detection does not need it)
    result = detect(frame, camera=CameraModel.for_frame(frame.shape, hfov_deg=25.0))
    assert not result.fire_alarm
    assert len(result.detections) == 1
    det = result.detections[0]
    assert det.kind != "fire"
    # data README: "one small warm object near column 172, row 128"; 3 px is its radius
    assert abs(det.centroid_rc[0] - 128) < 3
    assert abs(det.centroid_rc[1] - 172) < 3
    # the README's peak 29.5 C, lowered a little by the 3 x 3 median filter (< 0.5 K)
    assert 29.0 < det.peak_c <= 29.5
    assert det.range_m is None  # too small for a person at any plausible range: no prior fits


def test_duo_pro_r_frame_fire_free() -> None:
    result = detect(_real("flir_duo_pro_r_frame0_celsius"))
    assert not result.fire_alarm
    assert result.detections == ()  # smooth 3 K variations, nothing 3 K above the median


# -------------------------------------------------------------------------- radiometry


def _planck_quad(temp_c: float) -> float:
    h, c, k = 6.62607015e-34, 2.99792458e8, 1.380649e-23
    t = temp_c + 273.15
    value, _ = scipy.integrate.quad(
        lambda lam: 2 * h * c**2 / lam**5 / math.expm1(h * c / (lam * k * t)), 8e-6, 14e-6
    )
    return float(value)


@pytest.mark.parametrize("temp_c", [-40.0, 0.0, 20.0, 36.6, 150.0, 400.0, 900.0])
def test_band_radiance_equals_planck_quadrature(temp_c: float) -> None:
    # table interpolation at 0.25 K steps: second-order error well below 1e-5 relative
    assert band_radiance(temp_c) == pytest.approx(_planck_quad(temp_c), rel=1e-5)


def test_radiance_inverse_round_trip() -> None:
    temps = np.linspace(-30, 1200, 500)
    # interpolating the inverse in the same table: error of order step^2 * curvature, < 1 mK
    assert np.abs(radiance_to_celsius(band_radiance(temps)) - temps).max() < 1e-3


def test_tlinear_and_raw14_calibrations() -> None:
    tl = LinearCalibration.tlinear()
    assert counts_to_celsius(np.array([29315], dtype=np.uint16), tl)[0] == pytest.approx(20.0)
    assert LinearCalibration.parse("tlinear10").gain_c_per_count == 0.1
    raw = LinearCalibration.parse("0.05,-380")
    assert counts_to_celsius(np.array([8000]), raw)[0] == pytest.approx(20.0)
    assert celsius_to_counts(np.array([20.0]), tl)[0] == 29315
    with pytest.raises(InputError, match="integers"):
        counts_to_celsius(np.array([1.5]), tl)
    with pytest.raises(InputError, match=r"\[0, 16383\]"):
        counts_to_celsius(np.array([16384]), LinearCalibration(0.05, -380.0))
    with pytest.raises(InputError, match="--counts"):
        LinearCalibration.parse("warm")


# ------------------------------------------------------------------------------ files


def _counts_frame() -> NDArray[np.uint16]:
    rng = np.random.default_rng(0)
    return rng.integers(29000, 31000, (60, 80)).astype(np.uint16)


def test_read_16bit_png_tiff_pgm_as_counts(tmp_path: Path) -> None:
    counts = _counts_frame()
    expected = counts * 0.01 - 273.15
    cal = LinearCalibration.tlinear()
    cv2.imwrite(str(tmp_path / "f.png"), counts)  # OpenCV: an independent 16-bit writer
    cv2.imwrite(str(tmp_path / "f.tiff"), counts)
    header = b"P5\n80 60\n65535\n"  # Netpbm by hand: 16-bit samples are big-endian
    (tmp_path / "f.pgm").write_bytes(header + counts.astype(">u2").tobytes())
    for name in ("f.png", "f.tiff", "f.pgm"):
        assert np.allclose(read_frame(tmp_path / name, calibration=cal), expected, atol=1e-9)


def test_read_npy_celsius_and_counts(tmp_path: Path) -> None:
    frame = np.full((4, 5), 21.5, dtype=np.float32)
    np.save(tmp_path / "c.npy", frame)
    assert np.array_equal(read_frame(tmp_path / "c.npy"), frame.astype(np.float64))
    np.save(tmp_path / "n.npy", _counts_frame())
    cal = LinearCalibration.tlinear()
    assert read_frame(tmp_path / "n.npy", calibration=cal).shape == (60, 80)
    with pytest.raises(InputError, match="calibration"):
        read_frame(tmp_path / "n.npy")


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("empty.npy", b"", "empty file"),
        ("junk.npy", b"not numpy at all", "not a readable .npy"),
        ("junk.png", b"\x89PNG\r\n\x1a\n broken", "not a readable image"),
        ("frame.jpg", b"x", "unknown frame type"),
    ],
)
def test_read_bad_files(tmp_path: Path, name: str, content: bytes, message: str) -> None:
    (tmp_path / name).write_bytes(content)
    with pytest.raises(InputError, match=message):
        read_frame(tmp_path / name, calibration=LinearCalibration.tlinear())


def test_read_bad_arrays(tmp_path: Path) -> None:
    cal = LinearCalibration.tlinear()
    with pytest.raises(InputError, match="no such file"):
        read_frame(tmp_path / "missing.npy")
    nan = np.full((5, 5), 20.0)
    nan[2, 2] = np.nan
    np.save(tmp_path / "nan.npy", nan)
    with pytest.raises(InputError, match="1 non-finite"):
        read_frame(tmp_path / "nan.npy")
    np.save(tmp_path / "cube.npy", np.zeros((2, 5, 5)))
    with pytest.raises(InputError, match=r"shape \(H, W\)"):
        read_frame(tmp_path / "cube.npy")
    np.save(tmp_path / "text.npy", np.array([["a", "b"]]))
    with pytest.raises(InputError, match="dtype"):
        read_frame(tmp_path / "text.npy")
    cv2.imwrite(str(tmp_path / "eight.png"), np.zeros((6, 6), dtype=np.uint8))
    with pytest.raises(InputError, match="16-bit"):
        read_frame(tmp_path / "eight.png", calibration=cal)
    cv2.imwrite(str(tmp_path / "ok.png"), _counts_frame())
    with pytest.raises(InputError, match="calibration"):
        read_frame(tmp_path / "ok.png")


# ----------------------------------------------------------------------------- camera


def test_lepton_camera_geometry() -> None:
    cam = CameraModel()
    assert cam.fx_px == pytest.approx(40 / math.tan(math.radians(25.5)))
    assert math.degrees(cam.pixel_angle_rad) == pytest.approx(0.6375)
    # the outer edges of the image are at +-HFOV/2, the centre on the axis
    assert cam.bearing(29.5, -0.5) == pytest.approx(math.radians(25.5))
    assert cam.bearing(29.5, 79.5) == pytest.approx(-math.radians(25.5))
    assert cam.bearing(29.5, 39.5) == 0.0


def test_undistortion_matches_opencv() -> None:
    cam = CameraModel(k1=-0.25, k2=0.08, p1=0.002, p2=-0.001)
    cx, cy = cam.principal_point
    k = np.array([[cam.fx_px, 0, cx], [0, cam.fx_px, cy], [0, 0, 1]])
    dist = np.array([cam.k1, cam.k2, cam.p1, cam.p2])
    rows, cols = np.meshgrid(np.linspace(0, 59, 7), np.linspace(0, 79, 9), indexing="ij")
    pts = np.stack([cols.ravel(), rows.ravel()], axis=-1)[:, None, :]
    ref = cv2.undistortPoints(pts, k, dist)[:, 0, :]  # cv2: same iteration, float32 I/O
    x, y = cam.normalized(rows.ravel(), cols.ravel())
    assert np.abs(x - ref[:, 0]).max() < 1e-5
    assert np.abs(y - ref[:, 1]).max() < 1e-5
    # and projecting back lands on the pixels (the iteration converged)
    r2, c2 = cam.project(x, y)
    assert np.abs(r2 - rows.ravel()).max() < 1e-6
    assert np.abs(c2 - cols.ravel()).max() < 1e-6


def test_range_from_size_analytic_and_sigma() -> None:
    angle = 2 * math.atan(0.5 / 4.0)  # 1 m object at 4 m
    r, s = range_from_size(angle, 1.0, size_sigma_m=0.1, angular_sigma_rad=0.001)
    assert float(r) == pytest.approx(4.0, rel=1e-12)
    # first-order propagation checked by central differences
    eps = 1e-7
    dr_da = (
        float(range_from_size(angle + eps, 1.0)[0]) - float(range_from_size(angle - eps, 1.0)[0])
    ) / (2 * eps)
    assert float(s) == pytest.approx(math.hypot(0.4, dr_da * 0.001), rel=1e-6)
    with pytest.raises(InputError, match=r"\(0, pi\)"):
        range_from_size(0.0, 1.0)


# -------------------------------------------------------------------------- filtering


def test_destripe_recovers_column_offsets_around_a_tall_object() -> None:
    rng = np.random.default_rng(3)
    rows, cols = np.mgrid[0:60, 0:80]
    scene = 20.0 + 0.03 * cols + 0.02 * rows  # smooth gradient
    scene[5:55, 30:42] = 34.0  # a tall warm object: its edges are not stripes
    offsets = rng.normal(0, 0.15, 80)
    offsets -= offsets.mean()
    frame = scene + offsets + rng.normal(0, 0.03, scene.shape)
    fixed, found = destripe(frame)
    stripes_before = np.std(np.diff(offsets))
    stripes_after = np.std(np.diff(found - offsets))
    # each step is a median over >= 10 rows of 0.03 K noise differences (~0.01 K) against
    # 0.21 K column-to-column stripes: expect a ~20x reduction; 10x is the bound
    assert stripes_after < 0.1 * stripes_before
    # the object's edges are kept, not taken for stripes: its contrast with the patch
    # beside it (34 C against the gradient's mean 20 + 0.03 * 23.5 + 0.02 * 29.5 C) stays,
    # within the low-frequency residual of the offsets (a random walk of the steps, < 0.2 K)
    contrast = np.mean(fixed[10:50, 32:40]) - np.mean(fixed[10:50, 20:28])
    assert contrast == pytest.approx(34.0 - (20 + 0.03 * 23.5 + 0.02 * 29.5), abs=0.2)


def test_denoise_removes_dead_pixel_and_flat_field() -> None:
    frame = np.full((20, 30), 22.0)
    frame[7, 9] = -20.0  # dead pixel
    pattern = np.random.default_rng(4).normal(0, 0.2, frame.shape)
    out = denoise(frame + pattern, flat_field_c=20.0 + pattern, stripes=False)
    # the flat field removes the pattern but keeps its mean (the absolute offset, which the
    # shutter cannot know); the median removes the dead pixel; float rounding only
    assert np.abs(out - (22.0 + pattern.mean())).max() < 1e-9
    with pytest.raises(InputError, match="odd"):
        denoise(frame, median_size=2)


# -------------------------------------------------------------------------- detection


def _box_scene(value: float, rows: slice, cols: slice) -> NDArray[np.float64]:
    f = np.full((60, 80), 20.0)
    f[rows, cols] = value
    return f


def test_classification_fire_person_warm() -> None:
    p = DetectionParams(destripe=False)
    fire = detect(_box_scene(250.0, slice(30, 34), slice(10, 13)), params=p)
    assert fire.fire_alarm
    assert fire.detections[0].kind == "fire"
    # a small hot spot at 70 C, 50 K above its surround: fire by contrast
    spot = detect(_box_scene(70.0, slice(30, 32), slice(10, 12)), params=p)
    assert spot.detections[0].kind == "fire"
    # 45 C radiator panel: warm, not a fire (below 60 C)
    rad = detect(_box_scene(45.0, slice(30, 40), slice(10, 30)), params=p)
    assert not rad.fire_alarm
    assert rad.detections[0].kind == "warm"
    # 33 C, 28 x 8 px upright: a person at ~5 m
    person = detect(_box_scene(33.0, slice(10, 38), slice(36, 44)), params=p)
    assert person.detections[0].kind == "person"
    assert person.detections[0].range_source == "size"


def test_stereo_depth_gives_the_range() -> None:
    frame = _box_scene(33.0, slice(10, 38), slice(56, 64))
    depth = np.full(frame.shape, np.nan)
    depth[10:38, 56:64] = 3.0  # metres along the optical axis
    det = detect(frame, depth_m=depth).detections[0]
    cam = CameraModel()
    x, _ = cam.normalized(det.centroid_rc[0], det.centroid_rc[1])
    assert det.range_source == "stereo"
    assert det.range_m == pytest.approx(3.0 * math.sqrt(1 + float(x) ** 2), rel=1e-12)
    assert det.range_m is not None
    assert det.range_sigma_m == pytest.approx(0.02 * det.range_m)  # the 2 % floor, no spread


def test_detect_bad_input() -> None:
    frame = np.full((60, 80), 20.0)
    bad = frame.copy()
    bad[1, 1] = np.nan
    with pytest.raises(InputError, match="non-finite"):
        detect(bad)
    with pytest.raises(InputError, match="shape"):
        detect(np.zeros(80))
    with pytest.raises(InputError, match="dtype"):
        detect(np.full((60, 80), "hot"))
    with pytest.raises(InputError, match="camera is 120 x 160"):
        detect(frame, camera=CameraModel(width_px=160, height_px=120))
    with pytest.raises(InputError, match="depth_m shape"):
        detect(frame, depth_m=np.ones((3, 3)))
    with pytest.raises(InputError, match="person_min_c"):
        DetectionParams(person_min_c=40.0, person_max_c=30.0)
    assert detect(frame).detections == ()


def _gas_and_flames(cores: list[tuple[slice, slice]]) -> tuple[np.ndarray, np.ndarray]:
    """A door full of hot gas (200 C, 1 m away) with flames (450 C, 3 m away) in it."""
    frame = np.full((60, 80), 20.0)
    depth = np.full(frame.shape, np.nan)
    frame[8:52, 10:70] = 200.0
    depth[8:52, 10:70] = 1.0
    for rows, cols in cores:
        frame[rows, cols] = 450.0
        depth[rows, cols] = 3.0
    return frame, depth


def test_flame_cores_are_placed_on_the_flames_not_on_the_gas() -> None:
    core = (slice(26, 32), slice(52, 56))
    frame, depth = _gas_and_flames([core])
    # one region over the gas and the flames: its median depth is the gas's
    whole = detect(frame, depth_m=depth).detections
    assert [d.kind for d in whole] == ["fire"]
    assert whole[0].range_m == pytest.approx(1.0, abs=0.1)
    # reported as its core: the same bearing and range as the flames seen alone
    split = detect(frame, depth_m=depth, params=DetectionParams(flame_core_c=430.0)).detections
    alone_frame = np.full((60, 80), 20.0)
    alone_depth = np.full(frame.shape, np.nan)
    alone_frame[core], alone_depth[core] = 450.0, 3.0
    alone = detect(alone_frame, depth_m=alone_depth).detections
    assert [d.kind for d in split] == [d.kind for d in alone] == ["fire"]
    assert split[0].range_m == pytest.approx(alone[0].range_m, rel=1e-12)
    assert split[0].bearing_rad == pytest.approx(alone[0].bearing_rad, abs=1e-12)
    assert split[0].range_m is not None
    assert split[0].range_m > 3.0  # 3 m along the axis, off it: farther along the ray
    assert split[0].area_px == 24


def test_each_flame_core_is_a_detection_and_gas_alone_stays_one() -> None:
    frame, depth = _gas_and_flames([(slice(20, 24), slice(20, 24)), (slice(30, 36), slice(55, 60))])
    p = DetectionParams(flame_core_c=430.0)
    cores = detect(frame, depth_m=depth, params=p).detections
    assert sorted(d.area_px for d in cores) == [16, 30]
    assert all(d.range_m == pytest.approx(3.0, rel=0.15) for d in cores)
    assert cores[0].bearing_rad * cores[1].bearing_rad < 0  # one left, one right of the axis
    gas, gas_depth = _gas_and_flames([])
    only = detect(gas, depth_m=gas_depth, params=p).detections
    assert [d.kind for d in only] == ["fire"]
    assert only[0].area_px == 44 * 60
    with pytest.raises(InputError, match=r"flame_core_c 50\.0 must be at least fire_min_c"):
        DetectionParams(flame_core_c=50.0)
