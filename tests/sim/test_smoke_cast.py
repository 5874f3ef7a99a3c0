"""Smoke in the range sensors: Beer-Lambert along the rays (firefleet.sim._smoke_cast,
firefleet.sim.ranging's ``smoke=``), against analytic cases and a NumPy reference."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.sim._smoke_cast import (
    LIDAR_OPTICS,
    STEREO_OPTICS,
    SmokeField,
    SmokeOptics,
    optical_depth_segments,
    smoke_reach,
)
from firefleet.sim.ranging import (
    LidarParams,
    RangeSensors,
    StereoScanParams,
    UltrasonicParams,
    lidar_scan,
    stereo_scan,
    ultrasonic_scan,
)
from firefleet.world import OccupancyGrid


def _open(h: int, w: int, res: float) -> OccupancyGrid:
    occ = np.zeros((h, w), dtype=bool)
    return OccupancyGrid(occ, ~occ, resolution_m=res)


def _reference_depth(
    sigma: np.ndarray, res: float, x: float, y: float, ang: float, length: float
) -> float:
    """Exact optical depth by NumPy: every crossing of a grid line, sorted; sigma at each
    piece's midpoint times its length."""
    h, w = sigma.shape
    dx, dy = math.cos(ang), math.sin(ang)
    ts = [0.0, length]
    for k in range(w + 1):
        if dx != 0.0:
            ts.append((k * res - x) / dx)
    for k in range(h + 1):
        if dy != 0.0:
            ts.append((k * res - y) / dy)
    t = np.unique(np.clip(np.asarray(ts), 0.0, length))
    mid = 0.5 * (t[1:] + t[:-1])
    col = np.floor((x + mid * dx) / res).astype(int)
    row_up = np.floor((y + mid * dy) / res).astype(int)
    inside = (col >= 0) & (col < w) & (row_up >= 0) & (row_up < h)
    s = np.zeros(mid.size)
    s[inside] = sigma[h - 1 - row_up[inside], col[inside]]
    return float(np.sum(s * np.diff(t)))


def test_optics_limits_and_checks() -> None:
    assert LIDAR_OPTICS.max_depth == pytest.approx(-math.log(0.01) / 2.0)
    assert STEREO_OPTICS.max_depth == pytest.approx(3.0)
    with pytest.raises(InputError, match="passes"):
        SmokeOptics(passes=3, threshold=0.1)
    with pytest.raises(InputError, match="threshold"):
        SmokeOptics(passes=2, threshold=1.5)
    with pytest.raises(InputError, match="shape"):
        SmokeField(_open(4, 4, 0.5), np.zeros((3, 4)))
    with pytest.raises(InputError, match=">= 0"):
        SmokeField(_open(4, 4, 0.5), -np.ones((4, 4)))


@pytest.mark.parametrize("sigma", [0.2, 0.5, 1.3])
def test_uniform_smoke_blinds_the_lidar_at_the_analytic_range(sigma: float) -> None:
    """Uniform smoke: the ray goes blind at ln(threshold) / (-2 sigma)."""
    grid = _open(120, 120, 0.25)  # 30 m square: every ray goes blind on it
    smoke = SmokeField(grid, np.full(grid.shape, sigma))
    bearings = np.linspace(-math.pi, math.pi, 13)
    reach = smoke_reach(smoke, [[15.0, 15.0, 0.3]], bearings, LIDAR_OPTICS)
    assert reach == pytest.approx(math.log(0.01) / (-2.0 * sigma), rel=1e-9)


def test_a_slab_of_smoke_between_walls() -> None:
    """A slab of smoke from x = 2 to 4 m: a lidar at x = 1 m facing a wall at x = 6 m
    sees it through thin smoke (optical depth 2 sigma below the limit) and loses it
    through dense smoke, the beam going blind ln(0.01) / (-2 sigma) into the slab."""
    occ = np.zeros((40, 80), dtype=bool)
    occ[:, 60] = True  # a wall at x = 6.0 m (0.1 m cells)
    grid = OccupancyGrid(occ, ~occ, resolution_m=0.1)
    field = _open(40, 80, 0.1)
    params = LidarParams(beams=1, fov_deg=1.0, noise_m=0.0, max_range_m=10.0)
    pose = [[1.0, 2.0, 0.0]]
    rng = np.random.default_rng(0)
    clear = lidar_scan(grid, pose, params, robot_radius_m=0.0, rng=rng)
    assert clear[0, 0] == pytest.approx(5.0)
    for sigma, seen in ((0.5, True), (1.0, True), (1.2, False), (3.0, False)):
        ext = np.zeros(field.shape)
        ext[:, 20:40] = sigma
        smoke = SmokeField(field, ext)
        r = lidar_scan(grid, pose, params, robot_radius_m=0.0, rng=rng, smoke=smoke)
        assert (r[0, 0] == pytest.approx(5.0)) if seen else np.isinf(r[0, 0]), sigma
        blind = smoke_reach(smoke, pose, [0.0], LIDAR_OPTICS)[0, 0]
        # the slab (2 m deep) starts 1 m ahead: blind 1 m + ln(0.01) / (-2 sigma) into it
        slab_depth = 2.0 * sigma
        expect = 1.0 + math.log(0.01) / (-2.0 * sigma) if slab_depth > 2.3026 else math.inf
        assert blind == pytest.approx(expect, rel=1e-9)


def test_zero_smoke_is_clear_air_bit_for_bit() -> None:
    occ = np.zeros((60, 60), dtype=bool)
    occ[10:50, 45] = True
    occ[30, 5:40] = True
    grid = OccupancyGrid(occ, ~occ, resolution_m=0.1)
    smoke = SmokeField(_open(30, 30, 0.2), np.zeros((30, 30)))
    poses = [[1.0, 1.0, 0.2], [3.0, 4.5, -1.0], [2.2, 2.0, 2.0]]
    lidar = LidarParams(beams=64)
    a = lidar_scan(grid, poses, lidar, robot_radius_m=0.2, rng=np.random.default_rng(3))
    b = lidar_scan(
        grid, poses, lidar, robot_radius_m=0.2, rng=np.random.default_rng(3), smoke=smoke
    )
    np.testing.assert_array_equal(a, b)
    stereo = StereoScanParams()
    a = stereo_scan(grid, poses, stereo, robot_radius_m=0.2, rng=np.random.default_rng(3))
    b = stereo_scan(
        grid, poses, stereo, robot_radius_m=0.2, rng=np.random.default_rng(3), smoke=smoke
    )
    np.testing.assert_array_equal(a, b)


def test_stereo_scan_goes_blind_one_way_at_jin_visibility() -> None:
    """The stereo pair sees a lit wall while sigma d <= 3 (one pass)."""
    occ = np.zeros((60, 100), dtype=bool)
    occ[:, 70] = True  # a wall at x = 7 m
    grid = OccupancyGrid(occ, ~occ, resolution_m=0.1)
    params = StereoScanParams(sectors=1, rays_per_sector=1, disparity_noise_px=0.0)
    pose = [[1.0, 3.0, 0.0]]  # the wall 6 m ahead
    for sigma, seen in ((0.45, True), (0.55, False)):  # 3 / 6 = 0.5
        smoke = SmokeField(_open(60, 100, 0.1), np.full((60, 100), sigma))
        r = stereo_scan(
            grid, pose, params, robot_radius_m=0.0, rng=np.random.default_rng(0), smoke=smoke
        )
        assert (r[0, 0] == pytest.approx(6.0)) if seen else np.isinf(r[0, 0]), sigma


def test_range_sensors_dim_the_lidar_not_the_ultrasonic_ring() -> None:
    occ = np.zeros((40, 40), dtype=bool)
    occ[:, 30] = True  # a wall 2 m ahead of the robot
    grid = OccupancyGrid(occ, ~occ, resolution_m=0.1)
    dense = SmokeField(_open(40, 40, 0.1), np.full((40, 40), 5.0))
    stage = RangeSensors(
        grid,
        0.2,
        ultrasonic=UltrasonicParams(count=4, noise_m=0.0, dropout=0.0),
        lidar=LidarParams(beams=4, noise_m=0.0),
        rng=np.random.default_rng(0),
        smoke=lambda world: dense,
    )
    out = stage.read(None, SimpleNamespace(pose=np.array([[1.0, 2.0, 0.0]])))
    assert out["ultrasonic_range_m"][0, 0] == pytest.approx(2.0)  # sound: unaffected
    assert np.isinf(out["lidar_range_m"]).all()  # the wall ahead lost in the smoke
    plain = ultrasonic_scan(
        grid,
        [[1.0, 2.0, 0.0]],
        UltrasonicParams(count=4, noise_m=0.0, dropout=0.0),
        robot_radius_m=0.2,
        rng=np.random.default_rng(0),
    )
    np.testing.assert_array_equal(out["ultrasonic_range_m"], plain)


def test_compiled_walk_matches_numpy_reference() -> None:
    rng = np.random.default_rng(7)
    res = 0.25
    sigma = rng.exponential(0.4, size=(24, 32)) * (rng.random((24, 32)) < 0.6)
    smoke = SmokeField(_open(24, 32, res), sigma)
    starts = rng.uniform([-1.0, -1.0], [9.0, 7.0], size=(200, 2))
    ends = rng.uniform([-1.0, -1.0], [9.0, 7.0], size=(200, 2))
    ends[:5, 0] = starts[:5, 0]  # vertical rays
    ends[5:10, 1] = starts[5:10, 1]  # horizontal rays
    got = optical_depth_segments(smoke, starts, ends)
    ref = [
        _reference_depth(
            sigma, res, a[0], a[1], math.atan2(*(b - a)[::-1]), float(np.hypot(*(b - a)))
        )
        for a, b in zip(starts, ends, strict=True)
    ]
    np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-9)
    # the blind range: where the reference's optical depth reaches the lidar's limit
    poses = np.c_[starts[:40], rng.uniform(-math.pi, math.pi, 40)]
    reach = smoke_reach(smoke, poses, [0.0], LIDAR_OPTICS)[:, 0]
    for p, r in zip(poses, reach, strict=True):
        if np.isfinite(r):
            assert _reference_depth(sigma, res, p[0], p[1], p[2], r) == pytest.approx(
                LIDAR_OPTICS.max_depth, rel=1e-9
            )
        else:
            assert _reference_depth(sigma, res, p[0], p[1], p[2], 30.0) < LIDAR_OPTICS.max_depth
