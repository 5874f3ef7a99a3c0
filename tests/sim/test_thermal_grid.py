"""The grid thermal renderer against the segment renderer and the real detector."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.perception.thermal import detect
from firefleet.sim.sensors import (
    GridThermalScene,
    ThermalCameraParams,
    ThermalScene,
    render_thermal,
    render_thermal_grid,
)
from firefleet.world import OccupancyGrid

QUIET = ThermalCameraParams(netd_k=0.0, column_fpn_k=0.0, resolution_k=0.0)
RES = 0.25


def _room(width_m: float = 10.0, height_m: float = 5.0) -> OccupancyGrid:
    """A rectangular room: one ring of wall cells around open cells."""
    h, w = round(height_m / RES), round(width_m / RES)
    walls = np.zeros((h, w), dtype=bool)
    walls[[0, -1], :] = True
    walls[:, [0, -1]] = True
    return OccupancyGrid(walls, ~walls, resolution_m=RES)


def _inner_box(width_m: float = 10.0, height_m: float = 5.0) -> list[list[float]]:
    """The room's inner wall faces as segments."""
    a, bx, by = RES, width_m - RES, height_m - RES
    return [[a, a, bx, a], [bx, a, bx, by], [bx, by, a, by], [a, by, a, a]]


def test_room_and_person_equal_the_segment_renderer() -> None:
    """Same walls, floor, ceiling and person billboard, the same 4 x 4 rays per pixel: the
    two ray casters (cell walk vs segment intersection) agree to round-off."""
    grid = _room()
    temp = np.full(grid.shape, 24.0)
    person = np.array([[6.0, 3.0]])
    scene = ThermalScene(
        walls_m=np.array(_inner_box()),
        wall_temp_c=np.full(4, 24.0),
        object_xy_m=person,
        object_size_m=np.array([[0.5, 1.7]]),
        object_temp_c=np.array([37.0]),
        wall_height_m=2.5,
        floor_c=24.0,
        ceiling_c=24.0,
    )
    poses = np.array([[1.0, 2.0, 0.2], [8.0, 4.0, math.pi + 0.4], [5.0, 1.0, 1.0]])
    ref = render_thermal(scene, poses, QUIET, rng=np.random.default_rng(0))
    got = render_thermal_grid(
        poses, grid, temp, np.zeros(grid.shape, bool), person, QUIET, rng=np.random.default_rng(0)
    )
    assert got.shape == ref.shape == (3, 60, 80)
    diff = np.abs(got - ref)
    assert diff.max() < 1e-6  # tolerance: float round-off (measured: 0)
    assert got[0].max() > 30.0  # the person is in view


def test_person_found_by_the_detector_at_its_bearing_and_range() -> None:
    grid = _room()
    pose = np.array([[1.0, 2.0, 0.0]])
    person = np.array([[5.0, 3.0]])
    frame = render_thermal_grid(
        pose,
        grid,
        np.full(grid.shape, 20.0),
        np.zeros(grid.shape, bool),
        person,
        rng=np.random.default_rng(1),
    )[0]
    found = [d for d in detect(frame).detections if d.kind == "person"]
    assert len(found) == 1
    bearing = math.atan2(1.0, 4.0)
    pixel_rad = math.radians(51.0) / 80
    assert abs(found[0].bearing_rad - bearing) < pixel_rad
    assert found[0].range_m is not None
    # tolerance: the detector's range from the 1.7 m stature prior (sigma 0.1 m, ~6 %)
    # on a ~12-pixel-tall region: 15 %
    assert abs(found[0].range_m - math.hypot(4.0, 1.0)) < 0.15 * math.hypot(4.0, 1.0)


def test_person_behind_a_wall_is_not_seen() -> None:
    grid = _room()
    occupied = np.array(grid.occupied)
    col = round(3.0 / RES)
    occupied[:, col] = True  # a full-height wall at x = 3 m
    walled = OccupancyGrid(occupied, ~occupied, resolution_m=RES)
    frame = render_thermal_grid(
        [[1.0, 2.0, 0.0]],
        walled,
        np.full(grid.shape, 20.0),
        np.zeros(grid.shape, bool),
        [[5.0, 2.5]],
        QUIET,
        rng=np.random.default_rng(2),
    )[0]
    assert frame.max() == pytest.approx(20.0)
    assert not detect(frame).detections


def test_burning_cell_is_a_fire_at_its_bearing() -> None:
    grid = _room()
    temp = np.full(grid.shape, 22.0)
    burning = np.zeros(grid.shape, bool)
    fire_xy = np.array([6.125, 1.125])  # a cell's centre
    row, col = grid.cell_of(fire_xy)
    burning[row, col] = True
    temp[row, col] = 800.0
    frame = render_thermal_grid(
        [[1.0, 2.0, 0.0]], grid, temp, burning, np.zeros((0, 2)), rng=np.random.default_rng(3)
    )[0]
    result = detect(frame)
    fires = [d for d in result.detections if d.kind == "fire"]
    assert result.fire_alarm
    assert len(fires) == 1
    # the flame is a cell's width (0.25 m at 5.2 m: ~2.7 px); its centroid within a pixel
    bearing = math.atan2(fire_xy[1] - 2.0, fire_xy[0] - 1.0)
    assert abs(fires[0].bearing_rad - bearing) < 1.5 * math.radians(51.0) / 80


def test_flame_hides_what_is_behind_it_below_its_height() -> None:
    grid = _room()
    burning = np.zeros(grid.shape, bool)
    temp = np.full(grid.shape, 20.0)
    row, col = grid.cell_of([3.125, 2.125])
    burning[row, col] = True
    temp[row, col] = 300.0
    scene = GridThermalScene(flame_height_m=1.0)
    params = ThermalCameraParams(netd_k=0.0, column_fpn_k=0.0, resolution_k=0.0, supersample=1)
    frame = render_thermal_grid(
        [[1.125, 2.125, 0.0]],
        grid,
        temp,
        burning,
        [[6.125, 2.125]],
        params,
        rng=np.random.default_rng(0),
        scene=scene,
    )[0]
    centre_col = 40  # the axis passes between columns 39 and 40 through the flame
    # mount 0.5 m, flame 1.0 m at 2 m: rows above the horizon up to atan(0.5 / 2) are flame
    fy = 40.0 / math.tan(math.radians(25.5))
    horizon = 29.5
    top_of_flame_row = horizon - fy * 0.5 / 1.875  # the flame's near face at 1.875 m
    assert frame[int(top_of_flame_row) + 2, centre_col] == pytest.approx(300.0, abs=0.5)
    assert frame[int(top_of_flame_row) - 2, centre_col] < 40.0  # above it: the person or wall


def test_bad_shapes_are_refused() -> None:
    grid = _room()
    with pytest.raises(InputError, match="temperature_c"):
        render_thermal_grid(
            [[1.0, 1.0, 0.0]],
            grid,
            np.zeros((3, 3)),
            np.zeros(grid.shape, bool),
            np.zeros((0, 2)),
            rng=np.random.default_rng(0),
        )
    with pytest.raises(InputError, match="burning"):
        render_thermal_grid(
            [[1.0, 1.0, 0.0]],
            grid,
            np.zeros(grid.shape),
            np.zeros((3, 3), bool),
            np.zeros((0, 2)),
            rng=np.random.default_rng(0),
        )


@pytest.mark.parametrize("supersample", [1, 2, 3])
def test_compiled_camera_equals_the_numpy_camera(supersample: int) -> None:
    """The one-pass compiled frames (rays, per-pixel radiance mean, camera) equal the
    NumPy composition of the same steps: the rays of grid_thermal_celsius, band radiance,
    the mean over each pixel's rays, the camera's offsets, noise, clip, quantisation."""
    from firefleet.perception.thermal import band_radiance
    from firefleet.sim._thermal_grid import grid_thermal_celsius
    from firefleet.sim.sensors import _camera_output, _ray_grid, render_thermal_grid_depth

    grid = _room()
    rng = np.random.default_rng(supersample)
    temp = 20.0 + rng.uniform(0.0, 30.0, grid.shape)
    burning = np.zeros(grid.shape, dtype=bool)
    burning[8:10, 30:32] = True
    temp[burning] = 700.0
    people = np.array([[6.0, 3.0], [3.0, 1.5]])
    prm = ThermalCameraParams(supersample=supersample)
    scene = GridThermalScene(lower_fraction=0.4)
    poses = np.array([[1.0, 2.0, 0.2], [8.0, 4.0, math.pi + 0.4], [5.0, 1.0, -0.3]])
    got, depth = render_thermal_grid_depth(
        poses, grid, temp, burning, people, prm, rng=np.random.default_rng(5), scene=scene
    )
    xn, yn = _ray_grid(prm)
    temps, rays_depth = grid_thermal_celsius(
        poses, grid, temp, burning, people, xn, yn, prm.mount_height_m, scene
    )
    s, n = supersample, poses.shape[0]
    radiance = band_radiance(temps).reshape(n, 60, s, 80, s).mean(axis=(2, 4))
    want = _camera_output(radiance, prm, np.random.default_rng(5))
    np.testing.assert_array_equal(got, want)
    centre = rays_depth.reshape(n, 60, s, 80, s)[:, :, s // 2, :, s // 2]
    np.testing.assert_array_equal(depth, np.where(np.isfinite(centre), centre, np.nan))
    assert (got > 400.0).any()  # the flame
    assert (got < 25.0).any()  # the cool floor
