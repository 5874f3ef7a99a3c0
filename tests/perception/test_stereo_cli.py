"""``firefleet stereo``: outputs, their agreement with each other, and bad input (exit 2)."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from firefleet.cli import main
from firefleet.perception import stereo as st
from tests.perception.synthetic import PATTERN, SQUARE_M, board_poses, stereo_chessboards
from tests.perception.test_stereo import layered_pair

F_PX, B_M = 400.0, 0.12


@pytest.fixture
def pair(tmp_path: Path) -> tuple[Path, Path]:
    left, right, _ = layered_pair()
    paths = (tmp_path / "l.png", tmp_path / "r.png")
    for p, img in zip(paths, (left, right), strict=True):
        cv2.imwrite(str(p), img)
    return paths


def test_stereo_rectified_pair_writes_consistent_outputs(
    pair: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o"
    args = ["stereo", str(pair[0]), str(pair[1]), "--rectified", "--out", str(out)]
    args += ["--focal-px", str(F_PX), "--baseline-m", str(B_M), "--num-disparities", "32"]
    assert main(args) == 0
    assert sorted(p.name for p in out.glob("[!.]*")) == sorted(
        [
            "rectified_left.png",
            "rectified_right.png",
            "disparity.npy",
            "confidence.npy",
            "disparity.png",
            "rectified_pair.png",
            "depth.npy",
            "cloud.ply",
            "scan.json",
            "summary.json",
        ]
    )
    disp = np.load(out / "disparity.npy")
    depth = np.load(out / "depth.npy")
    assert disp.dtype == np.float32
    assert disp.shape == (160, 240)
    # The layers are at disparities 8 and 20 px: depth f B / d = 6 m and 2.4 m.
    _, _, gt = layered_pair()
    inner = (slice(4, -4), slice(40, -4))
    err = np.abs(disp - gt)[inner]
    assert np.mean(err <= 0.25) > 0.97  # as in the library test of the same pair
    np.testing.assert_allclose(depth, F_PX * B_M / disp, rtol=1e-6)  # float32
    summary = json.loads((out / "summary.json").read_text())
    assert summary["mode"] == "rectified"
    assert summary["focal_px"] == F_PX
    header = (out / "cloud.ply").read_bytes().split(b"end_header\n")[0].decode()
    assert f"element vertex {summary['points']}" in header
    scan = json.loads((out / "scan.json").read_text())
    assert scan["sectors"] == 32
    # The nearest obstacle is the square at 2.4 m (its measured points), within the
    # 1/16 px disparity step: 2.4 m * (1/16) / 20 = 8 mm.
    assert min(r for r in scan["range_m"] if r is not None) == pytest.approx(2.4, abs=0.05)
    assert "disparity_median_px" in capsys.readouterr().out
    png = cv2.imread(str(out / "disparity.png"))
    assert png is not None
    assert png.shape == (160, 240, 3)


def test_stereo_calibrated_pair(tmp_path: Path) -> None:
    _, lefts, rights = stereo_chessboards(10)
    calib = st.calibrate_stereo(lefts, rights, pattern_size=PATTERN, square_size_m=SQUARE_M)
    (tmp_path / "rig.yaml").write_text(st.calibration_yaml(calib), encoding="utf-8")
    cv2.imwrite(str(tmp_path / "l.png"), lefts[0])
    cv2.imwrite(str(tmp_path / "r.png"), rights[0])
    out = tmp_path / "o"
    args = ["stereo", str(tmp_path / "l.png"), str(tmp_path / "r.png")]
    # The board at 0.5-0.8 m is 100-160 px of disparity (f 600 px, B 0.12 m): range 176.
    args += ["--calib", str(tmp_path / "rig.yaml"), "--num-disparities", "176"]
    code = main([*args, "--out", str(out)])
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["mode"] == "calibrated"
    assert summary["baseline_m"] == pytest.approx(0.12, rel=0.01)  # the rig's baseline
    # Measured pixels are on the board (the grey surround has no texture to match): their
    # median depth lies within the board's true depth span (its four outer corners in
    # the left camera's frame; the rectified frame differs by a 1-degree rotation).
    rot, trans = board_poses(10, np.random.default_rng(7))[0]
    corners = [
        rot @ np.array([x, y, 0.0]) + trans
        for x in (-2 * SQUARE_M, (PATTERN[0] + 1) * SQUARE_M)
        for y in (-2 * SQUARE_M, (PATTERN[1] + 1) * SQUARE_M)
    ]
    depths = [float(c[2]) for c in corners]
    assert min(depths) < summary["depth_median_m"] < max(depths)
    left_rect = cv2.imread(str(out / "rectified_left.png"), cv2.IMREAD_UNCHANGED)
    assert left_rect is not None
    assert left_rect.shape == (480, 640)


def _one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("firefleet: error: ")
    return lines[0]


def test_stereo_bad_input_exits_2_and_writes_nothing(
    pair: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o"
    small = tmp_path / "small.png"
    cv2.imwrite(str(small), np.zeros((100, 100), np.uint8))
    assert main(["stereo", str(pair[0]), str(small), "--rectified", "--out", str(out)]) == 2
    assert "differ in size" in _one_error_line(capsys)
    junk = tmp_path / "junk.png"
    junk.write_bytes(b"garbage")
    assert main(["stereo", str(junk), str(pair[1]), "--rectified", "--out", str(out)]) == 2
    assert "junk.png: not a readable image" in _one_error_line(capsys)
    # A calibration made for 640 x 480 images, used on 240 x 160 ones.
    _, lefts, rights = stereo_chessboards(4)
    calib = st.calibrate_stereo(lefts, rights, pattern_size=PATTERN, square_size_m=SQUARE_M)
    (tmp_path / "rig.yaml").write_text(st.calibration_yaml(calib), encoding="utf-8")
    args = ["stereo", str(pair[0]), str(pair[1]), "--calib", str(tmp_path / "rig.yaml")]
    assert main([*args, "--out", str(out)]) == 2
    assert "calibration is for 640 x 480 px images, these are 240 x 160" in _one_error_line(capsys)
    assert main(["stereo", str(pair[0]), str(pair[1]), "--out", str(out)]) == 2
    assert "--calib FILE, --uncalibrated or --rectified" in _one_error_line(capsys)
    both = ["--rectified", "--uncalibrated", "--out", str(out)]
    assert main(["stereo", str(pair[0]), str(pair[1]), *both]) == 2
    assert "exclude each other" in _one_error_line(capsys)
    assert main(["stereo", str(pair[0]), str(tmp_path / "none.png"), "--rectified"]) == 2
    assert "none.png: no such image file" in _one_error_line(capsys)
    assert not out.exists()
    assert not list(tmp_path.glob(".o.staging-*"))


def test_corrupt_png_gives_our_message_not_opencvs(
    pair: tuple[Path, Path], tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    # A PNG signature followed by garbage: OpenCV's decoder logs "[ WARN:0@...]" and
    # "[ERROR:0@...]" lines to file descriptor 2 unless silenced.
    broken = tmp_path / "broken.png"
    broken.write_bytes(b"\x89PNG\r\n\x1a\n" + b"\x00" * 40)
    out = tmp_path / "o"
    assert main(["stereo", str(broken), str(pair[1]), "--rectified", "--out", str(out)]) == 2
    err = capfd.readouterr().err.strip().splitlines()
    assert err == [f"firefleet: error: {broken}: not a readable image (empty or corrupt)"]


@pytest.mark.parametrize(
    ("flags", "named"),
    [
        (["--num-disparities", "40"], "--num-disparities must be a positive multiple of 16"),
        (["--num-disparities", "256"], "below the image width 240 px, got 256"),
        (["--min-depth-m", "0"], "--min-depth-m must be a number > 0 [m], got 0.0"),
        (["--focal-px", "-5", "--baseline-m", "0.1"], "--focal-px must be a number > 0"),
        (["--sectors", "0"], "--sectors must be >= 1, got 0"),
    ],
)
def test_stereo_errors_name_the_flag(
    pair: tuple[Path, Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    flags: list[str],
    named: str,
) -> None:
    out = tmp_path / "o"
    args = ["stereo", str(pair[0]), str(pair[1]), "--rectified", *flags, "--out", str(out)]
    assert main(args) == 2
    assert named in _one_error_line(capsys)
    assert not out.exists()
