"""The webcams adapter on video files (the cameras' fakes, as for ``stereo capture``):
which frame, its timestamp, reads that fail counted, a wrong size refused, the capture
thread, and ``firefleet robot --fake`` with a video pair."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
from pathlib import Path

import cv2
import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.perception.stereo import StereoCalibration, calibration_yaml
from firefleet.robot import Webcams, load_role, open_adapters, parse_robot_config, run_onboard

ROOT = Path(__file__).resolve().parents[2]
FPS = 10.0
W, H = 32, 24


def video(path: Path, levels: list[int]) -> str:
    """A video of uniform frames, frame k at grey level ``levels[k]``."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), FPS, (W, H))
    for level in levels:
        writer.write(np.full((H, W, 3), level, np.uint8))
    writer.release()
    return str(path)


@pytest.fixture
def pair(tmp_path: Path) -> tuple[str, str]:
    left = video(tmp_path / "left.avi", [10 * k for k in range(12)])
    right = video(tmp_path / "right.avi", [200 - 10 * k for k in range(8)])  # ends first
    return left, right


def test_frames_come_in_order_with_their_timestamps(pair: tuple[str, str]) -> None:
    with Webcams(pair, width=W, height=H) as cams:
        frames = [cams.read() for _ in range(10)]
        dropped = cams.dropped
    got = [f for f in frames if f is not None]
    assert len(got) == 8  # the right file has 8 frames
    for k, f in enumerate(got):
        assert f.index == k
        assert f.t_s == pytest.approx((k / FPS, k / FPS), abs=1e-9)
        assert f.pair.skew_s == pytest.approx(0.0)
        assert abs(float(f.images[0].mean()) - 10 * k) < 3  # MJPG is lossy, not that lossy
        assert abs(float(f.images[1].mean()) - (200 - 10 * k)) < 3
    assert dropped == 2  # two reads after the right file ended: counted, not raised


def test_one_camera(pair: tuple[str, str]) -> None:
    with Webcams(pair[:1], width=W, height=H) as cams:
        frames = [cams.read() for _ in range(13)]
        assert cams.dropped == 1
    assert [f.index for f in frames if f is not None] == list(range(12))
    assert frames[3] is not None
    assert frames[3].t_s == pytest.approx((0.3,))
    with pytest.raises(InputError, match="a stereo pair needs two cameras"):
        _ = frames[0].pair  # type: ignore[union-attr]


def test_a_wrong_frame_size_is_a_clear_error(pair: tuple[str, str], tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"left\.avi: frames of 32x24x3 .*expected 64x48x3 "
                       r"\(hardware\.webcams\.width/height\)"):  # fmt: skip
        Webcams(pair, width=64, height=48)
    small = cv2.VideoWriter(str(tmp_path / "s.avi"), cv2.VideoWriter.fourcc(*"MJPG"), FPS, (16, 24))
    small.write(np.zeros((24, 16, 3), np.uint8))
    small.release()
    with pytest.raises(InputError, match="frames of different sizes: 32 x 24 vs 16 x 24 px"):
        Webcams([pair[0], str(tmp_path / "s.avi")], width=W, height=H)
    with pytest.raises(InputError, match=r"video nowhere\.avi: no such file"):
        Webcams(["nowhere.avi"], width=W, height=H)


def test_the_capture_thread_hands_over_the_newest_frame(pair: tuple[str, str]) -> None:
    before = threading.active_count()
    with Webcams(pair, width=W, height=H, rate_hz=50.0) as cams:
        cams.start()
        seen = []
        while cams.dropped == 0:  # until the right file ends (8 frames at 50 Hz)
            frame = cams.poll()
            if frame is not None:
                seen.append(frame.index)
            threading.Event().wait(0.005)
    assert threading.active_count() == before
    assert seen == sorted(seen)
    assert len(set(seen)) == len(seen)
    assert seen
    assert set(seen) <= set(range(8))


def test_the_onboard_loop_logs_the_webcam_pairs(pair: tuple[str, str]) -> None:
    config = parse_robot_config({
        "scenario": "coop-different-paths", "robot": 0, "duration_s": 1.0,
        "hardware": {"webcams": {"adapter": "v4l2", "width": W, "height": H, "rate_hz": 5.0,
                                 "fake_left": pair[0], "fake_right": pair[1]}},
    })  # fmt: skip
    with open_adapters(config, fake=True) as adapters:
        result = run_onboard(config, load_role(config, Path(".")), adapters, stop=threading.Event())
    indices = [int(f["index"]) for f in result.webcam]
    assert 3 <= len(indices) <= 6  # 5 Hz for 1 s
    assert indices == sorted(indices)
    assert all(f["skew_s"] == 0.0 for f in result.webcam)
    assert result.summary()["webcam_captures"] == len(indices)


def test_firefleet_robot_fake_with_a_video_pair(pair: tuple[str, str], tmp_path: Path) -> None:
    config = tmp_path / "robot.yaml"
    config.write_text(
        "scenario: coop-different-paths\nduration_s: 1.0\nhardware:\n"
        "  ultrasonic: {adapter: hcsr04, fake_distance_m: 0.7, air_temperature_c: 23.5}\n"
        f"  webcams: {{adapter: v4l2, width: {W}, height: {H}, rate_hz: 4.0,\n"
        f"            fake_left: {pair[0]}, fake_right: {pair[1]}}}\n"
    )
    run = subprocess.run(
        [sys.executable, "-m", "firefleet.cli", "robot", str(config), "--fake",
         "--out", str(tmp_path / "out")],
        env={**os.environ, "PYTHONPATH": str(ROOT / "src")}, capture_output=True, text=True,
        timeout=120, check=False,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["webcam_captures"] >= 2
    assert summary["range_readings"] == 10
    assert summary["range_median_m"] == pytest.approx(0.7, rel=1e-9)  # the fake's air: 23.5 C


def test_the_stereo_scan_measures_a_wall_at_its_depth(tmp_path: Path) -> None:
    # an ideal rig (f 200 px, baseline 0.1 m) looking at a textured wall with 8 px of
    # disparity: depth f B / d = 2.5 m
    w, h, f, b, d = 320, 240, 200.0, 0.1, 8
    k = np.array([[f, 0.0, (w - 1) / 2], [0.0, f, (h - 1) / 2], [0.0, 0.0, 1.0]])
    calib = StereoCalibration(image_size=(w, h), k_left=k, dist_left=np.zeros(5), k_right=k,
                              dist_right=np.zeros(5), rotation=np.eye(3),
                              translation_m=np.array([-b, 0.0, 0.0]))  # fmt: skip
    (tmp_path / "calib.yaml").write_text(calibration_yaml(calib))
    rng = np.random.default_rng(0)
    noise = rng.uniform(0, 255, (h, w + d, 3)).astype(np.float32)
    wall = np.clip((cv2.GaussianBlur(noise, (0, 0), 1.0) - 128) * 3 + 128, 0, 255).astype(np.uint8)
    paths = []
    for name, x0 in (("l.avi", 0), ("r.avi", d)):
        writer = cv2.VideoWriter(str(tmp_path / name), cv2.VideoWriter.fourcc(*"MJPG"), FPS, (w, h))
        for _ in range(10):
            writer.write(np.ascontiguousarray(wall[:, x0 : x0 + w]))
        writer.release()
        paths.append(str(tmp_path / name))
    webcams = {"adapter": "v4l2", "width": w, "height": h, "rate_hz": 5.0,
               "fake_left": paths[0], "fake_right": paths[1],
               "calibration": str(tmp_path / "calib.yaml")}  # fmt: skip
    config = parse_robot_config({
        "scenario": "coop-different-paths", "robot": 0, "duration_s": 1.0,
        "hardware": {"webcams": webcams},
    })  # fmt: skip
    with open_adapters(config, fake=True) as adapters:
        result = run_onboard(config, load_role(config, Path(".")), adapters, stop=threading.Event())
    nearest = [c["nearest_obstacle_m"] for c in result.webcam]
    assert len(nearest) >= 2
    np.testing.assert_allclose(nearest, f * b / d, rtol=0.02)
    small = parse_robot_config({
        "scenario": "coop-different-paths",
        "hardware": {"webcams": {**webcams, "width": 640, "height": 480}},
    })  # fmt: skip
    with (
        pytest.raises(InputError, match=r"calib\.yaml is for 320x240 px, the webcams give 640x480"),
        open_adapters(small, fake=True),
    ):
        pass
