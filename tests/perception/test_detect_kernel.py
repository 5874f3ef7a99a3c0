"""The compiled thermal detector equals its NumPy / SciPy reference (the detector as it
was before compilation, tests/perception/_detect_reference.py) on real FLIR frames,
synthetic scenes and frames the mission's renderer makes; and its kernels equal SciPy's."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.ndimage as ndi

from firefleet.perception.thermal import CameraModel, DetectionParams, FrameDetections, detect
from firefleet.perception.thermal._detect_kernel import (
    filter_frame,
    find_regions,
    pairwise_sum,
)
from firefleet.perception.thermal._frames import destripe
from firefleet.perception.thermal._radiometry import _radiance_table
from firefleet.perception.thermal._table import (
    interp_sorted,
    interp_sorted_from,
    interp_sorted_slopes,
    interp_table,
    table_slopes,
)

from ._detect_reference import detect_reference

DATA = Path(__file__).resolve().parents[1] / "data" / "thermal"
FLOATS = (
    "peak_c",
    "mean_c",
    "surround_c",
    "bearing_rad",
    "angular_width_rad",
    "elevation_span",
    "range_m",
    "range_sigma_m",
)


def _same(got: FrameDetections, want: FrameDetections) -> None:
    assert got.background_c == pytest.approx(want.background_c, rel=1e-12, abs=1e-12)
    np.testing.assert_allclose(got.filtered_c, want.filtered_c, rtol=1e-12, atol=1e-11)
    assert len(got.detections) == len(want.detections)
    for g, w in zip(got.detections, want.detections, strict=True):
        assert (g.kind, g.bbox_rc, g.area_px, g.range_source) == (
            w.kind,
            w.bbox_rc,
            w.area_px,
            w.range_source,
        )
        np.testing.assert_allclose(g.centroid_rc, w.centroid_rc, rtol=1e-12)
        for name in FLOATS:
            a, b = getattr(g, name), getattr(w, name)
            if b is None or (isinstance(b, float) and math.isnan(b)):
                assert a is None if b is None else math.isnan(a), name
            else:
                assert a == pytest.approx(b, rel=1e-9, abs=1e-12), name


@pytest.mark.parametrize("name", ["flir_t420_frame0_celsius", "flir_duo_pro_r_frame0_celsius"])
def test_real_frames_equal_the_reference(name: str) -> None:
    with np.load(DATA / f"{name}.npz") as npz:
        frame = np.asarray(npz["celsius"], dtype=np.float64)
    _same(detect(frame), detect_reference(frame))


def _scene(rng: np.random.Generator, h: int = 60, w: int = 80) -> np.ndarray:
    f = 20.0 + rng.normal(0.0, 0.08, (h, w)) + rng.normal(0.0, 0.2, w)
    f[int(rng.integers(h // 2, h)) :, :] += rng.uniform(-2.0, 4.0)  # floor vs wall
    for _ in range(int(rng.integers(0, 6))):
        r0, c0 = int(rng.integers(0, h - 2)), int(rng.integers(0, w - 2))
        r1, c1 = r0 + int(rng.integers(1, 30)), c0 + int(rng.integers(1, 12))
        f[r0:r1, c0:c1] = rng.choice([33.0, 45.0, 70.0, 250.0, 600.0]) + rng.normal(
            0.0, 0.5, f[r0:r1, c0:c1].shape
        )
    return f


@pytest.mark.parametrize("seed", range(12))
def test_synthetic_scenes_equal_the_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    frame = _scene(rng)
    params = [
        DetectionParams(),
        DetectionParams(destripe=False),
        DetectionParams(median_size=1, background_px=20),
        DetectionParams(median_size=5, fire_width_m=0.8),
    ][seed % 4]
    depth = None
    if seed % 3 == 0:
        depth = rng.uniform(1.0, 8.0, frame.shape)
        depth[rng.random(frame.shape) < 0.3] = np.nan
    cam = CameraModel(k1=-0.1, p2=0.01) if seed % 5 == 0 else None
    _same(
        detect(frame, params=params, depth_m=depth, camera=cam),
        detect_reference(frame, params=params, depth_m=depth, camera=cam),
    )


def test_mission_frames_equal_the_reference() -> None:
    from firefleet.sim.sensors import ThermalCameraParams, render_thermal_grid_depth
    from firefleet.world import OccupancyGrid

    walls = np.zeros((40, 60), dtype=bool)
    walls[[0, -1], :] = walls[:, [0, -1]] = True
    walls[20, 10:40] = True
    room = OccupancyGrid(walls, ~walls, resolution_m=0.25)
    temp = np.full(walls.shape, 20.0)
    burning = np.zeros(walls.shape, dtype=bool)
    burning[30:32, 40:42] = True
    temp[28:34, 38:44] = 300.0
    temp[burning] = 800.0
    poses = np.array([[2.0, 2.5, 0.0], [5.0, 7.0, -0.3], [14.0, 3.0, math.pi]])
    frames, depth = render_thermal_grid_depth(
        poses,
        room,
        temp,
        burning,
        np.array([[9.0, 6.5], [6.0, 1.5]]),
        ThermalCameraParams(),
        rng=np.random.default_rng(3),
    )
    found: list[str] = []
    for frame, d in zip(frames, depth, strict=True):
        got = detect(frame, depth_m=d)
        _same(got, detect_reference(frame, depth_m=d))
        found += [d.kind for d in got.detections]
    assert "fire" in found
    assert "person" in found


@pytest.mark.parametrize("size", [5, 6, 15, 26])
def test_opening_and_labels_equal_scipy(size: int) -> None:
    rng = np.random.default_rng(size)
    f = rng.normal(20.0, 3.0, (30, 50))
    f[rng.random(f.shape) < 0.05] = 100.0
    background, contrast, low, labels, top, area, box = find_regions(f, 60.0, 3.0, size)
    want = f - ndi.grey_opening(f, size=(1, size), mode="nearest")
    np.testing.assert_array_equal(contrast, want)
    np.testing.assert_array_equal(low, (want >= 1.5) | (f >= 60.0))
    lab, n = ndi.label(low, structure=np.ones((3, 3), dtype=bool))
    np.testing.assert_array_equal(labels, lab)
    index = np.arange(1, n + 1)
    np.testing.assert_array_equal(top, ndi.maximum(np.where(f >= 60.0, np.inf, want), lab, index))
    np.testing.assert_array_equal(area, ndi.sum_labels(np.ones_like(f), lab, index))
    slices = ndi.find_objects(lab)
    np.testing.assert_array_equal(
        box, [[s[0].start, s[1].start, s[0].stop, s[1].stop] for s in slices]
    )
    assert background == np.median(f)


def test_filter_equals_destripe_and_median() -> None:
    rng = np.random.default_rng(7)
    f = _scene(rng)
    flat, out = filter_frame(f, True, 1.0, True, 60.0)
    np.testing.assert_allclose(flat, destripe(f)[0], rtol=0, atol=1e-12)
    want = ndi.median_filter(flat, size=3, mode="nearest")
    np.testing.assert_array_equal(out, np.where(flat >= 60.0, flat, want))


@pytest.mark.parametrize("n", [1, 7, 8, 9, 127, 128, 129, 300, 4000])
def test_pairwise_sum_is_numpys(n: int) -> None:
    x = np.random.default_rng(n).normal(size=n) * 10.0 ** np.random.default_rng(n).uniform(-4, 4, n)
    assert pairwise_sum(x) == x.sum()


def test_table_interpolation_is_numpys() -> None:
    table_c, table_rad = _radiance_table((8.0, 14.0))
    x = np.concatenate(
        [
            np.random.default_rng(0).uniform(-100.0, 2000.0, 2000),
            table_c[::97],
            [-100.0, 2000.0, 1999.9999, 20.125, 36.6],
        ]
    )
    got = np.array([interp_table(v, table_c, table_rad) for v in x])
    np.testing.assert_array_equal(got, np.interp(x, table_c, table_rad))
    step = 1.0 / 0.25
    guessed = [interp_sorted_from(v, table_c, table_rad, int((v + 100.0) * step), 0) for v in x]
    np.testing.assert_array_equal(guessed, got)
    rad = np.concatenate([np.interp(x, table_c, table_rad), table_rad[::101], [0.0, 1e9]])
    back = np.array([interp_sorted(v, table_rad, table_c) for v in rad])
    np.testing.assert_array_equal(back, np.interp(rad, table_rad, table_c))
    for lo, hi in ((0, 1), (4000, 4001), (10, 5000), (table_c.size - 2, table_c.size - 1)):
        from_guess = np.array([interp_sorted_from(v, table_rad, table_c, lo, hi) for v in rad])
        np.testing.assert_array_equal(from_guess, back)
        # the slopes given instead of divided out: the same numbers both ways
        back_k = table_slopes(table_rad, table_c)
        sloped = [interp_sorted_slopes(v, table_rad, table_c, back_k, lo, hi) for v in rad]
        np.testing.assert_array_equal(sloped, back)
        fwd_k = table_slopes(table_c, table_rad)
        sloped = [interp_sorted_slopes(v, table_c, table_rad, fwd_k, lo, hi) for v in x]
        np.testing.assert_array_equal(sloped, got)
