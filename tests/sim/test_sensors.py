"""Simulated thermal camera: analytic renders, and detection against known ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.perception.thermal import (
    CameraModel,
    Detection,
    DetectionParams,
    FrameDetections,
    band_radiance,
    detect,
    radiance_to_celsius,
)
from firefleet.sim.sensors import ThermalCameraParams, ThermalScene, render_thermal

NOISELESS = ThermalCameraParams(netd_k=0.0, column_fpn_k=0.0, resolution_k=0.0)
PIXEL_ANGLE_RAD = CameraModel().pixel_angle_rad  # 51 / 80 deg: the bearing bound


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def test_floor_and_ceiling_split_at_the_horizon() -> None:
    scene = ThermalScene(floor_c=18.0, ceiling_c=26.0)
    frame = render_thermal(scene, np.zeros((1, 3)), NOISELESS, rng=np.random.default_rng(0))[0]
    # camera axis horizontal, principal point at row 29.5: rows 0-29 see the ceiling, 30-59
    # the floor (an infinite room: every ray hits one or the other); float rounding only
    assert np.abs(frame[:30] - 26.0).max() < 1e-6
    assert np.abs(frame[30:] - 18.0).max() < 1e-6


def test_wall_top_edge_blends_in_radiance() -> None:
    # a wall 4 m ahead whose top edge, seen from the camera 0.5 m above the floor, lies
    # exactly on the boundary at row 20.0 (its height from the pinhole model)
    cam = CameraModel()
    h = 0.5
    _, cy = cam.principal_point
    top_row_edge = 20.0  # row 20's centre: its upper half sees sky, its lower half the wall
    height = h + 4.0 * (cy - top_row_edge) / cam.fx_px
    scene = ThermalScene(
        walls_m=np.array([[4.0, -50.0, 4.0, 50.0]]),
        wall_temp_c=np.array([40.0]),
        wall_height_m=height,
        ceiling_c=None,
        sky_c=0.0,
    )
    frame = render_thermal(scene, np.zeros((1, 3)), NOISELESS, rng=np.random.default_rng(0))[0]
    # wall down to where the floor in front of it takes over: 0.5 m / 4 m = y_n 0.125, row
    # 29.5 + 0.125 fx = 40.0; rows 21-39 see only the wall, rows 41 and on only the floor
    assert np.abs(frame[21:40] - 40.0).max() < 1e-6
    assert np.abs(frame[41:] - 20.0).max() < 1e-6
    assert np.abs(frame[:20] - 0.0).max() < 1e-6  # sky
    # row 20: half the rays see the wall: the mean of the two radiances, not of temperatures
    expected = radiance_to_celsius(0.5 * (band_radiance(40.0) + band_radiance(0.0)))
    assert np.abs(frame[20] - expected).max() < 1e-3  # the 0.25 K radiance table: < 1 mK


def test_same_seed_same_frames_and_noise_level() -> None:
    scene = ThermalScene()
    poses = np.array([[0.0, 0.0, 0.0], [1.0, 2.0, 1.0]])
    prm = ThermalCameraParams(column_fpn_k=0.0, resolution_k=0.0)
    a = render_thermal(scene, poses, prm, rng=np.random.default_rng(5))
    b = render_thermal(scene, poses, prm, rng=np.random.default_rng(5))
    assert a.shape == (2, 60, 80)
    assert np.array_equal(a, b)
    noise = a[0, 30:] - 20.0  # the floor half
    # 2,400 samples: the sample std is within 5 % of 0.05 K at ~3.5 sigma
    assert np.std(noise) == pytest.approx(0.05, rel=0.05)


def test_bad_scene_and_pose_input() -> None:
    with pytest.raises(InputError, match="walls_m"):
        ThermalScene(walls_m=np.zeros((2, 3)), wall_temp_c=np.zeros(2))
    with pytest.raises(InputError, match="object_temp_c"):
        ThermalScene(object_xy_m=np.zeros((1, 2)), object_size_m=np.ones((1, 2)))
    with pytest.raises(InputError, match="poses"):
        render_thermal(ThermalScene(), np.zeros(3), rng=np.random.default_rng(0))
    with pytest.raises(InputError, match="temperatures"):
        ThermalScene(floor_c=float("nan"))


def _room(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Four walls of a 30 m x 30 m hall around the origin, 15-30 C."""
    walls = np.array(
        [[-15, -15, 15, -15], [15, -15, 15, 15], [15, 15, -15, 15], [-15, 15, -15, -15]],
        dtype=float,
    )
    return walls, rng.uniform(15.0, 30.0, 4)


def test_fires_and_people_at_known_bearings_and_ranges() -> None:
    rng = np.random.default_rng(2026)
    cam = CameraModel()
    worst = {"bearing": 0.0, "person_range": 0.0, "fire_range": 0.0}
    for trial in range(40):
        walls, wall_t = _room(rng)
        fire_w = rng.uniform(0.3, 1.0)
        fire_r = rng.uniform(3.0, 15.0)
        # a standing person is whole in the 39 degree vertical view from 3.4 m on (camera
        # 0.5 m high: 1.2 m / 3.4 m = tan 19.5 deg); closer, only the width prior applies
        person_r = rng.uniform(3.5, 12.0)
        # bearings with the whole object 2 px inside the 51 degree view (0.445 rad each side)
        half_f, half_p = math.atan(fire_w / 2 / fire_r), math.atan(0.25 / person_r)
        fire_b = -rng.uniform(half_f + 0.02, 0.40 - half_f)
        person_b = rng.uniform(half_p + 0.02, 0.40 - half_p)
        theta = rng.uniform(-math.pi, math.pi)
        pose = np.array([rng.uniform(-3, 3), rng.uniform(-3, 3), theta])

        def at(r: float, b: float, pose: np.ndarray = pose) -> list[float]:
            return [pose[0] + r * math.cos(pose[2] + b), pose[1] + r * math.sin(pose[2] + b)]

        scene = ThermalScene(
            walls_m=walls,
            wall_temp_c=wall_t,
            object_xy_m=np.array([at(fire_r, fire_b), at(person_r, person_b)]),
            object_size_m=np.array([[fire_w, rng.uniform(0.5, 1.5)], [0.5, 1.7]]),
            object_temp_c=np.array([rng.uniform(150.0, 400.0), rng.uniform(31.0, 36.0)]),
            floor_c=rng.uniform(15.0, 25.0),
            ceiling_c=rng.uniform(15.0, 25.0),
        )
        frame = render_thermal(scene, pose[None], rng=rng)[0]
        params = DetectionParams(fire_width_m=fire_w)
        found = detect(frame, camera=cam, params=params)
        assert found.fire_alarm, f"trial {trial}: fire missed"

        def nearest(
            kind: str, b: float, found: FrameDetections = found, trial: int = trial
        ) -> Detection:
            hits = [d for d in found.detections if d.kind == kind]
            assert hits, f"trial {trial}: no {kind} in {found.detections}"
            return min(hits, key=lambda d: abs(_wrap(d.bearing_rad - b)))

        fire, person = nearest("fire", fire_b), nearest("person", person_b)
        for det, b in ((fire, fire_b), (person, person_b)):
            worst["bearing"] = max(worst["bearing"], abs(_wrap(det.bearing_rad - b)))
        assert fire.range_m is not None
        assert person.range_m is not None
        worst["fire_range"] = max(worst["fire_range"], abs(fire.range_m / fire_r - 1))
        worst["person_range"] = max(worst["person_range"], abs(person.range_m / person_r - 1))
    # the bounds: one pixel's angle (51/80 deg) and 15 % of the range
    assert worst["bearing"] < PIXEL_ANGLE_RAD, worst
    assert worst["person_range"] < 0.15, worst
    assert worst["fire_range"] < 0.15, worst


def test_no_false_fire_alarm_in_1000_fire_free_frames() -> None:
    rng = np.random.default_rng(7)
    prm = ThermalCameraParams(supersample=2)  # partial pixels still blend; 4x faster
    alarms = 0
    for _ in range(1000):
        walls, wall_t = _room(rng)
        k = int(rng.integers(0, 5))
        pose = np.array([rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-math.pi, math.pi)])
        r = rng.uniform(0.8, 12.0, k)
        b = rng.uniform(-0.5, 0.5, k) + pose[2]
        xy = np.stack([pose[0] + r * np.cos(b), pose[1] + r * np.sin(b)], axis=-1)
        # people (28-37 C) and warm things: radiators, lamps, a hot pipe (up to 55 C)
        temps = np.where(rng.random(k) < 0.5, rng.uniform(28, 37, k), rng.uniform(35, 55, k))
        size = np.stack([rng.uniform(0.1, 1.5, k), rng.uniform(0.2, 2.0, k)], axis=-1)
        scene = ThermalScene(
            walls_m=walls,
            wall_temp_c=wall_t,
            object_xy_m=xy,
            object_size_m=size,
            object_temp_c=temps,
            floor_c=rng.uniform(10.0, 30.0),
            ceiling_c=rng.uniform(10.0, 40.0),  # a hot gas layer under the ceiling too
        )
        frame = render_thermal(scene, pose[None], prm, rng=rng)[0]
        alarms += detect(frame).fire_alarm
    assert alarms == 0
