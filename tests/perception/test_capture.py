"""Stereo capture from video files (frame synchronisation, offsets, timestamps, errors)."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

from firefleet.cli import main
from firefleet.errors import InputError
from firefleet.perception.capture import (
    open_source,
    pair_files,
    stereo_capture,
    timestamp_row,
    timestamps_csv,
)

FPS = 10.0


def write_video(path: Path, n: int, base: int = 0) -> None:
    """An MJPG video whose frame k is flat grey level ``base + 10 k`` (its index, readable
    back through JPEG to +-2 levels)."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), FPS, (64, 48))
    assert writer.isOpened()
    for k in range(n):
        writer.write(np.full((48, 64, 3), base + 10 * k, np.uint8))
    writer.release()


def level(path: Path) -> float:
    img = cv2.imread(str(path))
    assert img is not None
    return float(img.mean())


def capture_into(left: str, right: str, folder: Path, **kwargs: int) -> list[dict[str, Any]]:
    """Capture with the library and save the pairs as the ``capture`` command does."""
    folder.mkdir(parents=True, exist_ok=True)
    rows = []
    for frame in stereo_capture(left, right, **kwargs):
        for name, content in pair_files(frame).items():
            (folder / name).write_bytes(content)
        rows.append(timestamp_row(frame))
    (folder / "timestamps.csv").write_text(timestamps_csv(rows), encoding="utf-8")
    return rows


def test_one_file_opened_twice_with_an_offset(tmp_path: Path) -> None:
    video = tmp_path / "cam.avi"
    write_video(video, 20)
    out = tmp_path / "pairs"
    rows = capture_into(str(video), str(video), out, n_frames=5, offset_frames=3)
    assert [r["index"] for r in rows] == [0, 1, 2, 3, 4]
    for k, row in enumerate(rows):
        # Frame k on the left, frame k + 3 on the right (JPEG keeps flat levels to +-2).
        assert level(out / row["left"]) == pytest.approx(10 * k, abs=2)
        assert level(out / row["right"]) == pytest.approx(10 * (k + 3), abs=2)
        # Timestamps are the frames' positions in the file: k / fps and (k + 3) / fps.
        assert row["t_left_s"] == pytest.approx(k / FPS, abs=1e-6)
        assert row["skew_s"] == pytest.approx(3 / FPS, abs=1e-6)
    with (out / "timestamps.csv").open() as fh:
        table = list(csv.DictReader(fh))
    assert [int(r["index"]) for r in table] == [0, 1, 2, 3, 4]
    assert float(table[2]["t_right_s"]) == pytest.approx(0.5, abs=1e-6)


def test_two_files_every_second_pair_stops_at_the_shorter(tmp_path: Path) -> None:
    write_video(tmp_path / "l.avi", 9)
    write_video(tmp_path / "r.avi", 6, base=5)
    out = tmp_path / "pairs"
    rows = capture_into(str(tmp_path / "l.avi"), str(tmp_path / "r.avi"), out, n_frames=10, every=2)
    # Frames 0, 2, 4 of both (the right file ends after frame 5).
    assert len(rows) == 3
    for k, row in zip((0, 2, 4), rows, strict=True):
        assert level(out / row["left"]) == pytest.approx(10 * k, abs=2)
        assert level(out / row["right"]) == pytest.approx(5 + 10 * k, abs=2)
        assert row["skew_s"] == pytest.approx(0.0, abs=1e-6)


def test_sources_that_cannot_be_opened_are_named(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"camera /dev/video63: cannot be opened"):
        open_source("/dev/video63")
    with pytest.raises(InputError, match=r"video .*nothere\.avi: no such file"):
        open_source(str(tmp_path / "nothere.avi"))
    junk = tmp_path / "junk.avi"
    junk.write_bytes(b"not a video at all")
    with pytest.raises(InputError, match=r"junk\.avi"):
        list(stereo_capture(str(junk), str(junk), n_frames=1))


def test_capture_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    video = tmp_path / "cam.avi"
    write_video(video, 8)
    out = tmp_path / "cap"
    code = main(
        ["capture", str(video), str(video), "--frames", "2", "--offset", "1", "--out", str(out)]
    )
    assert code == 0
    names = sorted(p.name for p in out.glob("[!.]*"))
    assert names == [
        "left_000000.png",
        "left_000001.png",
        "right_000000.png",
        "right_000001.png",
        "timestamps.csv",
    ]
    assert level(out / "right_000001.png") == pytest.approx(20, abs=2)  # frame 1 + 1
    assert "wrote 2 pair(s)" in capsys.readouterr().out
    bad = tmp_path / "bad"
    assert main(["capture", "/dev/video63", str(video), "--out", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "firefleet: error: camera /dev/video63: cannot be opened (no such device, or busy)"
    ]
    assert not bad.exists()
    assert not list(tmp_path.glob(".bad.staging-*"))


def test_opencv_log_lines_do_not_reach_the_terminal(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    # OpenCV writes "[ WARN:0@...]" lines to file descriptor 2 when a camera or a video
    # cannot be opened; capfd sees them (capsys would not).
    junk = tmp_path / "junk.avi"
    junk.write_bytes(b"not a video at all")
    for source in ("/dev/video63", str(junk)):
        assert main(["capture", source, source, "--out", str(tmp_path / "o")]) == 2
        err = capfd.readouterr().err.strip().splitlines()
        assert len(err) == 1, err
        assert err[0].startswith("firefleet: error: ")
        assert "WARN" not in err[0]
    # The library leaves OpenCV's log level as it found it.
    before = cv2.utils.logging.getLogLevel()
    with pytest.raises(InputError):
        open_source("/dev/video63")
    assert cv2.utils.logging.getLogLevel() == before


@pytest.mark.parametrize(
    ("flags", "named"),
    [
        (["--frames", "0"], "--frames must be >= 1, got 0"),
        (["--offset", "-1"], "--offset must be >= 0, got -1"),
        (["--every", "0"], "--every must be >= 1, got 0"),
        (["--width", "0"], "--width must be > 0 [px], got 0"),
    ],
)
def test_capture_errors_name_the_flag(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], named: str
) -> None:
    video = tmp_path / "cam.avi"
    write_video(video, 4)
    out = tmp_path / "o"
    assert main(["capture", str(video), str(video), *flags, "--out", str(out)]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [f"firefleet: error: {named}"]
    assert not out.exists()
