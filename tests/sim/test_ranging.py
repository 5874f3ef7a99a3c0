"""Range sensors against analytic cases, a brute-force ray marcher and an exact reference."""

from __future__ import annotations

import itertools
import math
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.perception.stereo import range_scan
from firefleet.sim._ranging_cast import (
    _cast_team,
    _hash_discs,
    cast_ray,
    cast_team,
    clearance_cells,
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

RES = 0.05


def box_room(h: int = 80, w: int = 120) -> OccupancyGrid:
    """A room whose walls are one cell thick: inner faces x = RES, (w-1) RES; y likewise."""
    occ = np.zeros((h, w), dtype=bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    return OccupancyGrid(occ, ~occ, resolution_m=RES, origin_m=(-1.0, 2.0))


def slab_reference(grid: OccupancyGrid, x: float, y: float, angle: float) -> float:
    """Exact distance to the first occupied cell (every cell a box, NumPy slab test)."""
    rows, cols = np.nonzero(grid.occupied)
    ox, oy = grid.origin_m
    h = grid.shape[0]
    x0 = ox + cols * grid.resolution_m
    y0 = oy + (h - 1 - rows) * grid.resolution_m
    x1, y1 = x0 + grid.resolution_m, y0 + grid.resolution_m
    dx, dy = math.cos(angle), math.sin(angle)
    with np.errstate(divide="ignore", invalid="ignore"):
        tx0, tx1 = (x0 - x) / dx, (x1 - x) / dx
        ty0, ty1 = (y0 - y) / dy, (y1 - y) / dy
    t_in = np.maximum(np.minimum(tx0, tx1), np.minimum(ty0, ty1))
    t_out = np.minimum(np.maximum(tx0, tx1), np.maximum(ty0, ty1))
    hit = (t_out >= np.maximum(t_in, 0.0)) & (t_out >= 0)
    return float(np.maximum(t_in[hit], 0.0).min()) if hit.any() else math.inf


def march_reference(
    grid: OccupancyGrid, x: float, y: float, angle: float, step: float, max_r: float
) -> float:
    """Brute force: sample the ray every ``step`` metres; the first sample in an occupied
    cell (off the map counts as free) gives the range."""
    t = np.arange(0.0, max_r + step, step)
    pts = np.stack([x + t * math.cos(angle), y + t * math.sin(angle)], axis=-1)
    inside = grid.contains(pts)
    rc = grid.cell_of(pts)
    h, w = grid.shape
    occ = inside & grid.occupied[np.clip(rc[:, 0], 0, h - 1), np.clip(rc[:, 1], 0, w - 1)]
    return float(t[np.argmax(occ)]) if occ.any() else math.inf


def random_grid(seed: int, h: int = 60, w: int = 70) -> OccupancyGrid:
    rng = np.random.default_rng(seed)
    occ = rng.random((h, w)) < 0.04
    occ[rng.integers(0, h), :] = True  # a wall across
    occ[:, rng.integers(0, w, 2)] = True  # two walls down
    return OccupancyGrid(occ, ~occ, resolution_m=0.1, origin_m=(-2.0, 1.0))


def free_pose(grid: OccupancyGrid, rng: np.random.Generator) -> tuple[float, float, float]:
    x0, x1, y0, y1 = grid.extent_m
    while True:
        x, y = rng.uniform(x0, x1), rng.uniform(y0, y1)
        if not grid.occupied_at([x, y]):
            return x, y, rng.uniform(-np.pi, np.pi)


NO_DROPOUT: dict[str, Any] = {
    "dropout": 0.0,
    "dropout_incidence_deg": 90.0,
    "dropout_width_deg": 1e-3,
}
"""Echoes lost only past 90 degrees of incidence: never."""
NOISELESS = LidarParams(beams=360, fov_deg=360.0, max_range_m=30.0, noise_m=0.0)


def test_walls_and_corners_of_a_room_are_d_over_cos() -> None:
    """Every beam in a closed room: range = d / cos(beam - wall normal) to the nearest wall
    along it, corners included (the least of two walls' d / cos)."""
    grid = box_room()
    x_lo, x_hi = -1.0 + RES, -1.0 + 119 * RES
    y_lo, y_hi = 2.0 + RES, 2.0 + 79 * RES
    poses = np.array([[0.3, 3.1, 0.4], [4.2, 5.5, -2.0], [-0.8, 2.1, 3.0]])
    ranges = lidar_scan(grid, poses, NOISELESS, robot_radius_m=0.0, rng=np.random.default_rng(0))
    for (x, y, th), row in zip(poses, ranges, strict=True):
        a = th + NOISELESS.bearings_rad
        c, s = np.cos(a), np.sin(a)
        with np.errstate(divide="ignore"):
            tx = np.where(c > 0, (x_hi - x) / c, (x_lo - x) / c)
            ty = np.where(s > 0, (y_hi - y) / s, (y_lo - y) / s)
        np.testing.assert_allclose(row, np.minimum(tx, ty), rtol=0, atol=1e-9)


def test_a_robot_disc_ranges_at_centre_distance_minus_radius() -> None:
    """Another robot D ahead: r = D - R; off-axis, the ray-circle root; never itself."""
    occ = np.zeros((200, 200), dtype=bool)
    grid = OccupancyGrid(occ, ~occ, resolution_m=RES)
    params = LidarParams(beams=8, fov_deg=360.0, max_range_m=8.0, noise_m=0.0)
    r_disc, d = 0.17, 3.0
    poses = np.array([[2.0, 5.0, 0.0], [2.0 + d, 5.0, 1.0]])
    out = lidar_scan(grid, poses, params, robot_radius_m=r_disc, rng=np.random.default_rng(0))
    ahead = int(np.argmin(np.abs(params.bearings_rad)))
    assert out[0, ahead] == pytest.approx(d - r_disc, abs=1e-12)
    # and the other way round, robot 1 turned to face robot 0
    p1 = LidarParams(beams=1, fov_deg=10.0, max_range_m=8.0, noise_m=0.0)
    back = lidar_scan(
        grid,
        poses[::-1] * [1, 1, 0] + [0, 0, np.pi],
        p1,
        robot_radius_m=r_disc,
        rng=np.random.default_rng(0),
    )
    assert back[0, 0] == pytest.approx(d - r_disc, abs=1e-12)
    # off-axis: a beam at angle phi from the centre line meets the circle at
    # D cos(phi) - sqrt(R^2 - D^2 sin^2 phi)
    phi = 0.03
    one = LidarParams(beams=1, fov_deg=10.0, max_range_m=8.0, noise_m=0.0)
    out = lidar_scan(
        grid,
        [[2.0, 5.0, phi], [2.0 + d, 5.0, 0.0]],
        one,
        robot_radius_m=r_disc,
        rng=np.random.default_rng(0),
    )
    expect = d * math.cos(phi) - math.sqrt(r_disc**2 - (d * math.sin(phi)) ** 2)
    assert out[0, 0] == pytest.approx(expect, abs=1e-12)
    alone = lidar_scan(grid, poses[:1], params, robot_radius_m=r_disc, rng=np.random.default_rng(0))
    assert np.all(np.isinf(alone))  # a robot never sees itself


@pytest.mark.parametrize("seed", range(6))
def test_lidar_matches_exact_and_brute_force_references_on_random_maps(seed: int) -> None:
    grid = random_grid(seed)
    rng = np.random.default_rng(100 + seed)
    params = LidarParams(beams=24, fov_deg=360.0, max_range_m=6.0, noise_m=0.0)
    poses = np.array([free_pose(grid, rng) for _ in range(4)])
    out = lidar_scan(grid, poses, params, robot_radius_m=0.0, rng=rng)
    step = 1e-3
    for (x, y, th), row in zip(poses, out, strict=True):
        for b, r in zip(params.bearings_rad, row, strict=True):
            exact = slab_reference(grid, x, y, th + b)
            exact = exact if exact <= params.max_range_m else math.inf
            if math.isinf(exact):
                assert math.isinf(r)
            else:
                assert r == pytest.approx(exact, abs=1e-9)
            marched = march_reference(grid, x, y, th + b, step, params.max_range_m)
            if math.isfinite(marched) and math.isfinite(r):
                assert r - 1e-9 <= marched <= r + step + 1e-9  # within one step length
            else:  # both miss, or the hit lies within one step of max range
                assert min(r, marched) >= params.max_range_m - step


def test_compiled_equals_python_and_batch_equals_one_at_a_time() -> None:
    grid = random_grid(7)
    rng = np.random.default_rng(3)
    poses = np.array([free_pose(grid, rng) for _ in range(5)])
    bearings = np.linspace(-3.0, 3.0, 17)
    occ = np.ascontiguousarray(grid.occupied)
    xy = np.ascontiguousarray(poses[:, :2])
    hashed = _hash_discs(xy, 0.2, 0.5)
    for part_c, part_p in zip(hashed, _hash_discs.py_func(xy, 0.2, 0.5), strict=True):
        np.testing.assert_array_equal(part_c, part_p)
    clear = clearance_cells(occ)
    x, y, th = poses[0]
    for b in bearings:
        for jumps in (clear, np.zeros_like(clear)):
            args = (occ, 0.1, -2.0, 1.0, x, y, th + b, 5.0, 0, xy, 0.2, *hashed, jumps)
            assert cast_ray(*args) == cast_ray.py_func(*args)
    r_c, c_c = cast_team(occ, 0.1, (-2.0, 1.0), poses, bearings, 5.0, 0.2, clear)
    r_p, c_p = np.empty_like(r_c), np.empty_like(c_c)
    _cast_team.py_func(occ, 0.1, -2.0, 1.0, poses, bearings, 5.0, 0.2, clear, r_p, c_p)
    np.testing.assert_array_equal(r_c, r_p)
    np.testing.assert_array_equal(c_c, c_p)
    # jumping through empty space changes no range (only the last bits of the arithmetic)
    r_walk, c_walk = cast_team(occ, 0.1, (-2.0, 1.0), poses, bearings, 5.0, 0.2)
    np.testing.assert_allclose(r_c, r_walk, rtol=0, atol=1e-9)
    np.testing.assert_allclose(c_c, c_walk, rtol=0, atol=1e-12)
    assert np.isfinite(r_c).any()
    assert np.isinf(r_c).any()
    # without discs, the batch is each robot alone, for every sensor
    for scan, params in (
        (lidar_scan, LidarParams(beams=30, noise_m=0.0, max_range_m=5.0)),
        (ultrasonic_scan, UltrasonicParams(noise_m=0.0, **NO_DROPOUT)),
        (stereo_scan, StereoScanParams(disparity_noise_px=0.0)),
    ):
        batch = scan(grid, poses, params, robot_radius_m=0.0, rng=np.random.default_rng(0))  # type: ignore[arg-type]
        singles = np.vstack(
            [
                scan(grid, p[None], params, robot_radius_m=0.0, rng=np.random.default_rng(0))  # type: ignore[arg-type]
                for p in poses
            ]
        )
        np.testing.assert_array_equal(batch, singles)


def wall_ahead(
    distance_m: float, normal_offset_rad: float = 0.0
) -> tuple[OccupancyGrid, np.ndarray]:
    """A wall whose face is x = 10 m; a robot distance_m before it, turned by the offset."""
    occ = np.zeros((400, 400), dtype=bool)
    occ[:, 200:] = True
    grid = OccupancyGrid(occ, ~occ, resolution_m=RES)
    return grid, np.array([[10.0 - distance_m, 10.0, normal_offset_rad]])


def test_ultrasonic_cone_nearest_return_min_and_max_range() -> None:
    p = UltrasonicParams(count=1, noise_m=0.0, **NO_DROPOUT)
    rng = np.random.default_rng(0)
    # the wall's normal inside the cone: the axis ray is the nearest, r = d
    grid, pose = wall_ahead(1.3, math.radians(3.75))
    assert ultrasonic_scan(grid, pose, p, robot_radius_m=0.0, rng=rng)[0, 0] == pytest.approx(
        1.3, abs=1e-9
    )
    # outside it: the cone's edge, r = d / cos(alpha - fov / 2)
    grid, pose = wall_ahead(1.3, math.radians(30.0))
    got = ultrasonic_scan(grid, pose, p, robot_radius_m=0.0, rng=rng)[0, 0]
    assert got == pytest.approx(1.3 / math.cos(math.radians(30.0 - 7.5)), abs=1e-9)
    grid, pose = wall_ahead(0.01)
    assert ultrasonic_scan(grid, pose, p, robot_radius_m=0.0, rng=rng)[0, 0] == p.min_range_m
    grid, pose = wall_ahead(3.99)
    assert ultrasonic_scan(grid, pose, p, robot_radius_m=0.0, rng=rng)[0, 0] == pytest.approx(
        3.99, abs=1e-9
    )
    grid, pose = wall_ahead(4.01)
    assert np.isinf(ultrasonic_scan(grid, pose, p, robot_radius_m=0.0, rng=rng)[0, 0])


def test_lidar_max_range() -> None:
    p = LidarParams(beams=1, fov_deg=1.0, max_range_m=10.0, noise_m=0.0)
    rng = np.random.default_rng(0)
    for d, expect in ((9.99, 9.99), (10.01, math.inf)):
        grid, pose = wall_ahead(d)
        assert lidar_scan(grid, pose, p, robot_radius_m=0.0, rng=rng)[0, 0] == pytest.approx(
            expect, abs=1e-9
        )


def test_noise_statistics() -> None:
    """Mean and standard deviation over many draws within 5 standard errors."""
    n = 20_000
    rng = np.random.default_rng(11)
    grid, pose = wall_ahead(2.0)
    poses = np.repeat(pose, n, axis=0)
    lid = lidar_scan(
        grid, poses, LidarParams(beams=1, fov_deg=1.0, noise_m=0.03), robot_radius_m=0.0, rng=rng
    )[:, 0]
    us = ultrasonic_scan(
        grid,
        poses,
        UltrasonicParams(count=1, noise_m=0.01, **NO_DROPOUT),
        robot_radius_m=0.0,
        rng=rng,
    )[:, 0]
    st_p = StereoScanParams(sectors=2, rays_per_sector=2, disparity_noise_px=0.3)
    st = stereo_scan(grid, poses, st_p, robot_radius_m=0.0, rng=rng)[:, 0]  # its ray at bearing 0
    for x, sigma in ((lid, 0.03), (us, 0.01), (st, float(st_p.depth_sigma_m(2.0)))):
        assert np.isfinite(x).all()
        assert abs(x.mean() - 2.0) < 5 * sigma / math.sqrt(n)
        assert abs(x.std(ddof=1) / sigma - 1.0) < 5 / math.sqrt(2 * n)
    assert st_p.depth_sigma_m(2.0) == pytest.approx(4.0 * 0.3 / (600.0 * 0.1))  # Z^2 s_d / (f B)


def test_dropout_rate_rises_with_incidence() -> None:
    """The share of lost echoes at each incidence matches the model (binomial, 5 sigma)."""
    p = UltrasonicParams(count=1, rays_per_cone=1, noise_m=0.0, dropout=0.02)
    n = 4_000
    rng = np.random.default_rng(5)
    rates = []
    for deg in (0.0, 30.0, 45.0, 50.0, 55.0, 70.0):
        grid, pose = wall_ahead(1.0, math.radians(deg))
        out = ultrasonic_scan(grid, np.repeat(pose, n, axis=0), p, robot_radius_m=0.0, rng=rng)[
            :, 0
        ]
        rate = float(np.isinf(out).mean())
        expect = float(p.dropout_probability(math.radians(deg)))
        assert abs(rate - expect) <= 5 * math.sqrt(expect * (1 - expect) / n) + 1e-3
        rates.append(rate)
    assert rates[0] < 0.05
    assert rates[-1] > 0.95
    assert all(b >= a - 0.02 for a, b in itertools.pairwise(rates))


def test_stereo_sectors_match_the_stereo_commands_range_scan() -> None:
    """A wall 2.5 m ahead seen by the simulated scan and by ``range_scan`` on points of the
    same wall in the camera frame (X right, Z ahead): the same sectors, the same ranges."""
    params = StereoScanParams(sectors=12, disparity_noise_px=0.0, rays_per_sector=2)
    grid, pose = wall_ahead(2.5, 0.0)
    sim = stereo_scan(grid, pose, params, robot_radius_m=0.0, rng=np.random.default_rng(0))[0]
    lateral = np.linspace(-2.0, 2.0, 400_001)  # points along the wall, X = -y
    points = np.column_stack([lateral, np.zeros_like(lateral), np.full_like(lateral, 2.5)])
    ref = range_scan(points, n_sectors=12, fov_rad=params.fov_rad)
    np.testing.assert_allclose(ref.bearing_rad, params.bearings_rad, atol=1e-12)
    np.testing.assert_allclose(sim, ref.range_m, atol=1e-4)


def test_stage_reads_at_sensor_rates_and_holds_between() -> None:
    grid, pose = wall_ahead(3.0)
    stage = RangeSensors(
        grid,
        0.2,
        lidar=LidarParams(beams=1, fov_deg=1.0, noise_m=0.0, rate_hz=10.0),
        ultrasonic=UltrasonicParams(count=1, noise_m=0.0, rate_hz=25.0, **NO_DROPOUT),
        dt_s=0.01,
        rng=np.random.default_rng(0),
    )
    lidar, sonar = [], []
    for k in range(30):
        drive = SimpleNamespace(pose=np.add(pose, [[0.01 * k, 0.0, 0.0]]))
        out = stage.read(None, drive)
        assert set(out) == {"lidar_range_m", "ultrasonic_range_m"}
        lidar.append(out["lidar_range_m"][0, 0])
        sonar.append(out["ultrasonic_range_m"][0, 0])
    expect_l = [3.0 - 0.01 * (10 * (k // 10)) for k in range(30)]
    np.testing.assert_allclose(lidar, expect_l, atol=1e-9)
    scans = [
        k
        for k in range(30)
        if k == 0 or math.floor(k * 0.25 + 1e-9) != math.floor((k - 1) * 0.25 + 1e-9)
    ]
    assert scans == [0, 4, 8, 12, 16, 20, 24, 28]
    expect_u = [3.0 - 0.01 * max(s for s in scans if s <= k) for k in range(30)]
    np.testing.assert_allclose(sonar, expect_u, atol=1e-9)


@pytest.mark.parametrize(
    ("make", "field"),
    [
        (lambda: UltrasonicParams(count=0), "ultrasonic.count"),
        (lambda: UltrasonicParams(fov_deg=-1.0), "ultrasonic.fov_deg"),
        (lambda: UltrasonicParams(min_range_m=5.0), "ultrasonic.min_range_m"),
        (lambda: UltrasonicParams(dropout=1.5), "ultrasonic.dropout"),
        (lambda: LidarParams(beams=2.5), "lidar.beams"),  # type: ignore[arg-type]
        (lambda: LidarParams(max_range_m=float("nan")), "lidar.max_range_m"),
        (lambda: LidarParams(fov_deg=400.0), "lidar.fov_deg"),
        (lambda: StereoScanParams(baseline_m=0.0), "stereo.baseline_m"),
        (lambda: StereoScanParams(sectors=0), "stereo.sectors"),
    ],
)
def test_bad_parameters_name_the_field(make: object, field: str) -> None:
    with pytest.raises(InputError, match=field.replace(".", r"\.")):
        make()  # type: ignore[operator]


def test_bad_poses_and_radius() -> None:
    grid, _ = wall_ahead(1.0)
    rng = np.random.default_rng(0)
    with pytest.raises(InputError, match="poses"):
        lidar_scan(grid, [[1.0, 2.0]], LidarParams(), robot_radius_m=0.2, rng=rng)
    with pytest.raises(InputError, match="robot_radius_m"):
        lidar_scan(grid, [[1.0, 2.0, 0.0]], LidarParams(), robot_radius_m=-0.2, rng=rng)


def disc_reference(xy: np.ndarray, me: int, angle: float, radius: float) -> float:
    """Nearest hit of a ray from robot ``me`` on every other robot's disc (NumPy roots)."""
    d = np.array([math.cos(angle), math.sin(angle)])
    f = xy[me] - np.delete(xy, me, axis=0)
    b = f @ d
    c = np.sum(f * f, axis=1) - radius**2
    disc = b * b - c
    ok = (disc >= 0) & (b <= 0)
    s = -b[ok] - np.sqrt(disc[ok])
    inside = c <= 0
    return 0.0 if inside.any() else (float(s.min()) if s.size else math.inf)


@pytest.mark.parametrize("seed", range(3))
def test_a_crowd_blocks_beams_as_discs(seed: int) -> None:
    """40 robots on a random map: every beam is the nearer of the exact wall hit and the
    nearest other robot's disc (discs sorted into bearing bins must lose none)."""
    grid = random_grid(seed)
    rng = np.random.default_rng(seed)
    poses = np.array([free_pose(grid, rng) for _ in range(40)])
    params = LidarParams(beams=45, max_range_m=4.0, noise_m=0.0)
    out = lidar_scan(grid, poses, params, robot_radius_m=0.25, rng=rng)
    blocked_by_robot = 0
    for a, (x, y, th) in enumerate(poses):
        for b, r in zip(params.bearings_rad, out[a], strict=True):
            wall = slab_reference(grid, x, y, th + b)
            robot = disc_reference(poses[:, :2], a, th + b, 0.25)
            blocked_by_robot += robot < wall
            expect = min(wall, robot)
            assert r == pytest.approx(expect if expect <= 4.0 else math.inf, abs=1e-9)
    assert blocked_by_robot > 20  # the crowd matters in this test


def test_skipped_ticks_scan_as_the_reads_would() -> None:
    """A quiet stretch's ticks with the scans in it (``skip`` with the poses): the same
    readings and the same noise draws as reading every tick."""
    grid, _ = wall_ahead(3.0)
    start = np.array([[0.5, 1.0, 0.3], [1.0, 1.5, 2.0]])
    poses = start[None] + np.linspace(0.0, 0.5, 40)[:, None, None] * np.array([1.0, 0.5, 0.1])

    def stage() -> RangeSensors:
        return RangeSensors(
            grid,
            0.2,
            lidar=LidarParams(beams=16, noise_m=0.02, rate_hz=10.0),
            ultrasonic=UltrasonicParams(count=8, rate_hz=15.0),
            dt_s=0.01,
            rng=np.random.default_rng(7),
        )

    every, batched = stage(), stage()
    for k in range(39):
        every.read(None, SimpleNamespace(pose=poses[k]))
    batched.read(None, SimpleNamespace(pose=poses[0]))
    assert batched.quiet_ticks(38) < 38  # scans due: not quiet for held readings
    assert batched.quiet_ticks(38, scans=True) == 38
    batched.skip(38, None, poses[1:39])  # ticks 1 .. 38
    got = batched.read(None, SimpleNamespace(pose=poses[39]))
    want = every.read(None, SimpleNamespace(pose=poses[39]))
    for name in want:
        np.testing.assert_array_equal(got[name], want[name])
    assert batched.rng.random() == every.rng.random()
