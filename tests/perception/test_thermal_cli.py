"""``firefleet thermal``: detections.json, PNGs, exit 2 on bad input with nothing written."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from firefleet.cli import main

DATA = Path(__file__).resolve().parents[1] / "data" / "thermal"


def _npy(tmp_path: Path, name: str) -> Path:
    with np.load(DATA / f"{name}.npz") as npz:
        path = tmp_path / f"{name}.npy"
        np.save(path, npz["celsius"])
    return path


def test_real_frames_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    frames = tmp_path / "frames"
    frames.mkdir()
    _npy(frames, "flir_t420_frame0_celsius")
    _npy(frames, "flir_duo_pro_r_frame0_celsius")
    out = tmp_path / "out"
    assert main(["thermal", str(frames), "--out", str(out)]) == 0
    doc = json.loads((out / "detections.json").read_text())
    by_name = {d["frame"]: d for d in doc}
    t420 = by_name["flir_t420_frame0_celsius.npy"]
    assert not t420["fire_alarm"]
    assert not by_name["flir_duo_pro_r_frame0_celsius.npy"]["fire_alarm"]
    assert len(t420["detections"]) == 1
    det = t420["detections"][0]
    assert det["kind"] == "warm"
    assert set(det) >= {"centroid_rc", "bbox_rc", "peak_c", "mean_c", "area_px", "bearing_rad"}
    assert det["range_m"] is None
    # README: near row 128, column 172 (3 px: the object's radius)
    assert abs(det["centroid_rc"][0] - 128) < 3
    assert abs(det["centroid_rc"][1] - 172) < 3
    for stem in ("flir_t420_frame0_celsius", "flir_duo_pro_r_frame0_celsius"):
        assert (out / f"{stem}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "flir_t420_frame0_celsius.npy" in capsys.readouterr().out


def test_counts_png_with_tlinear(tmp_path: Path) -> None:
    counts = np.full((60, 80), 29315, dtype=np.uint16)  # 20.00 C in centikelvin
    counts[20:24, 30:33] = 52315  # 250.00 C: a fire
    cv2.imwrite(str(tmp_path / "fire.png"), counts)
    out = tmp_path / "o"
    assert (
        main(["thermal", str(tmp_path / "fire.png"), "--counts", "tlinear", "--out", str(out)]) == 0
    )
    doc = json.loads((out / "detections.json").read_text())
    assert doc[0]["fire_alarm"] is True
    assert doc[0]["detections"][0]["peak_c"] == pytest.approx(250.0, abs=1e-6)


@pytest.mark.parametrize(
    ("setup", "message"),
    [
        ("nan", "non-finite"),
        ("empty", "empty file"),
        ("shape", "shape (H, W)"),
        ("dtype", "dtype"),
        ("missing", "no such file"),
        ("png-no-counts", "--counts"),
    ],
)
def test_bad_input_exits_2_one_line_nothing_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], setup: str, message: str
) -> None:
    good = np.full((60, 80), 20.0)
    np.save(tmp_path / "good.npy", good)
    bad = tmp_path / "bad.npy"
    if setup == "nan":
        good[3, 3] = np.nan
        np.save(bad, good)
    elif setup == "empty":
        bad.write_bytes(b"")
    elif setup == "shape":
        np.save(bad, np.zeros((2, 60, 80)))
    elif setup == "dtype":
        np.save(bad, np.zeros((60, 80), dtype=bool))
    elif setup == "png-no-counts":
        bad = tmp_path / "bad.png"
        cv2.imwrite(str(bad), np.zeros((60, 80), dtype=np.uint16))
    else:
        bad = tmp_path / "nothing.npy"
    out = tmp_path / "out"
    assert main(["thermal", str(tmp_path / "good.npy"), str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err
    assert len(err.strip().splitlines()) == 1
    assert "Traceback" not in err
    assert not out.exists()  # the good frame's outputs were staged, then dropped
    assert not list(tmp_path.glob(".out.staging-*"))


def test_same_stem_frames_get_distinct_pictures(tmp_path: Path) -> None:
    # x.npy (temperatures) and x.png (counts) in one call: two pictures, not one
    # overwritten by the other.
    hot = np.full((60, 80), 20.0)
    hot[20:24, 30:33] = 250.0
    np.save(tmp_path / "x.npy", hot)
    cv2.imwrite(str(tmp_path / "x.png"), np.full((60, 80), 29315, dtype=np.uint16))  # 20 C
    out = tmp_path / "o"
    args = ["thermal", str(tmp_path / "x.npy"), str(tmp_path / "x.png"), "--counts", "tlinear"]
    assert main([*args, "--out", str(out)]) == 0
    written = sorted(p.name for p in out.glob("[!.]*"))
    assert written == ["detections.json", "x_npy.png", "x_png.png"]
    doc = json.loads((out / "detections.json").read_text())
    assert [(d["frame"], d["figure"], d["fire_alarm"]) for d in doc] == [
        ("x.npy", "x_npy.png", True),
        ("x.png", "x_png.png", False),
    ]
    assert (out / "x_npy.png").read_bytes() != (out / "x_png.png").read_bytes()


def test_same_file_name_in_two_folders_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
        np.save(tmp_path / folder / "x.npy", np.full((60, 80), 20.0))
    out = tmp_path / "o"
    args = ["thermal", str(tmp_path / "a" / "x.npy"), str(tmp_path / "b" / "x.npy")]
    assert main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "share the file name x.npy" in err[0]
    assert not out.exists()


@pytest.mark.parametrize(
    ("flags", "named"),
    [
        (["--hfov-deg", "0"], "--hfov-deg must be in (0, 180) degrees, got 0.0"),
        (["--hfov-deg", "200"], "--hfov-deg must be in (0, 180) degrees, got 200.0"),
        (["--hfov-deg", "nan"], "--hfov-deg must be in (0, 180) degrees, got nan"),
        (["--fire-width-m", "-1"], "--fire-width-m must be > 0 [m], got -1.0"),
        (["--counts", "0,-273.15"], "--counts GAIN,OFFSET needs a finite GAIN > 0"),
        (["--counts", "0.01,nan"], "--counts GAIN,OFFSET needs a finite GAIN > 0"),
    ],
)
def test_errors_name_the_flag_typed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], named: str
) -> None:
    np.save(tmp_path / "f.npy", np.full((60, 80), 20.0))
    assert main(["thermal", str(tmp_path / "f.npy"), *flags, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith(f"firefleet: error: {named}")
    assert "camera." not in err[0]
    assert "calibration." not in err[0]
    assert "hfov_rad" not in err[0]
