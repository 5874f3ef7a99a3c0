"""Frame-synchronised stereo capture from two cameras or two video files.

This replaces the deliverable's ``motion`` and ``fswebcam`` set-up (Annexure A), where
each webcam was read by its own process (``fswebcam -d /dev/video0``, then
``/dev/video1``) and the two pictures were taken at different moments. Here both
sources are read by one loop: each step first *grabs* a frame from both (a cheap call
that latches the frame), then *retrieves* (decodes) them, so the two exposures are as
close in time as the drivers allow, and each frame keeps its timestamp.

Sources are camera devices (``/dev/video0`` or an index ``0``) or video files. Video
files are synchronised by frame number; ``offset_frames`` drops that many frames from
the right source first (two recordings started at different moments, or one file
opened twice to make a shifted pair).
"""

from __future__ import annotations

import csv
import io
import logging
import re
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from firefleet.errors import InputError
from firefleet.perception._opencv import quiet_opencv

__all__ = [
    "TIMESTAMP_COLUMNS",
    "StereoFrame",
    "open_source",
    "pair_files",
    "read_pairs",
    "stereo_capture",
    "timestamp_row",
    "timestamps_csv",
]

log = logging.getLogger(__name__)

_DEVICE = re.compile(r"^(?:/dev/video)?(\d+)$")


@dataclass(frozen=True, eq=False)
class StereoFrame:
    """One synchronised pair.

    Attributes
    ----------
    index : int
        Pair number, from 0.
    t_left_s, t_right_s : float
        Timestamps [s]: the position in the video for files, the monotonic clock at the
        grab for cameras.
    left, right : ndarray of uint8, shape (H, W, 3)
        BGR frames.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.capture import StereoFrame
    >>> image = np.zeros((4, 6, 3), np.uint8)
    >>> StereoFrame(index=0, t_left_s=1.0, t_right_s=1.25, left=image, right=image).skew_s
    0.25
    """

    index: int
    t_left_s: float
    t_right_s: float
    left: NDArray[np.uint8]
    right: NDArray[np.uint8]

    @property
    def skew_s(self) -> float:
        """``t_right_s - t_left_s`` [s] (for files, relative to the start of each file)."""
        return self.t_right_s - self.t_left_s


def _is_device(spec: str) -> bool:
    return _DEVICE.match(spec) is not None


def open_source(
    spec: str, *, width: int | None = None, height: int | None = None
) -> cv2.VideoCapture:
    """Open a camera (``/dev/videoN`` or ``N``) or a video file.

    Parameters
    ----------
    spec : str
        Device path, device index, or video file path.
    width, height : int, optional
        Requested camera resolution [px] (cameras only; the deliverable's webcams give
        640 x 480).

    Raises
    ------
    InputError
        Naming ``spec`` if it cannot be opened (no such device or file, busy device,
        undecodable file).

    Examples
    --------
    >>> from firefleet.errors import InputError
    >>> from firefleet.perception.capture import open_source
    >>> try:
    ...     open_source("no-such-video.avi")
    ... except InputError as error:
    ...     print(error)
    video no-such-video.avi: no such file
    """
    m = _DEVICE.match(spec)
    if m is not None:
        with quiet_opencv():
            cap = cv2.VideoCapture(int(m.group(1)))
        if not cap.isOpened():
            raise InputError(f"camera {spec}: cannot be opened (no such device, or busy)")
        if width is not None:
            cap.set(cv2.CAP_PROP_FRAME_WIDTH, width)
        if height is not None:
            cap.set(cv2.CAP_PROP_FRAME_HEIGHT, height)
        return cap
    path = Path(spec)
    if not path.is_file():
        raise InputError(f"video {spec}: no such file")
    with quiet_opencv():
        cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        raise InputError(f"video {spec}: cannot be opened (not a video OpenCV can decode)")
    return cap


def _frame_time_s(cap: cv2.VideoCapture, device: bool) -> float:
    return time.monotonic() if device else float(cap.get(cv2.CAP_PROP_POS_MSEC)) / 1000.0


def read_pairs(
    left: cv2.VideoCapture,
    right: cv2.VideoCapture,
    *,
    n_frames: int,
    offset_frames: int = 0,
    every: int = 1,
    devices: tuple[bool, bool] = (False, False),
) -> Iterator[StereoFrame]:
    """Yield synchronised pairs: grab both, then retrieve both.

    Parameters
    ----------
    left, right : cv2.VideoCapture
        Open sources (:func:`open_source`).
    n_frames : int
        Pairs to yield; fewer if a source ends first.
    offset_frames : int
        Frames dropped from the right source before the first pair (>= 0).
    every : int
        Keep every ``every``-th pair (>= 1).
    devices : tuple of bool
        Whether each source is a live camera (timestamps from the clock) or a file.

    Raises
    ------
    InputError
        If a frame cannot be decoded, or the two sources give frames of different
        sizes.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import cv2
    >>> import numpy as np
    >>> from firefleet.perception.capture import open_source, read_pairs
    >>> folder = tempfile.TemporaryDirectory()
    >>> video = str(pathlib.Path(folder.name) / "clip.avi")
    >>> writer = cv2.VideoWriter(video, cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (32, 24))
    >>> for k in range(5):
    ...     writer.write(np.full((24, 32, 3), 40 * k, np.uint8))
    >>> writer.release()
    >>> pairs = list(read_pairs(open_source(video), open_source(video), n_frames=2, every=2))
    >>> [pair.index for pair in pairs], pairs[0].left.shape, [round(p.t_left_s, 3) for p in pairs]
    ([0, 1], (24, 32, 3), [0.0, 0.2])
    >>> folder.cleanup()
    """
    if n_frames < 1 or offset_frames < 0 or every < 1:
        raise InputError(
            f"need n_frames >= 1, offset_frames >= 0, every >= 1; got {n_frames}, "
            f"{offset_frames}, {every}"
        )
    for _ in range(offset_frames):
        with quiet_opencv():
            grabbed = right.grab()
        if not grabbed:
            return
    k = 0
    produced = 0
    while produced < n_frames:
        with quiet_opencv():
            ok_l = left.grab()
            t_l = _frame_time_s(left, devices[0])
            ok_r = right.grab()
            t_r = _frame_time_s(right, devices[1])
        if not (ok_l and ok_r):
            return
        k += 1
        if (k - 1) % every:
            continue
        with quiet_opencv():
            got_l, img_l = left.retrieve()
            got_r, img_r = right.retrieve()
        if not (got_l and got_r) or img_l is None or img_r is None:
            raise InputError(f"pair {produced}: a frame could not be decoded")
        if img_l.shape != img_r.shape:
            raise InputError(
                f"the sources give frames of different sizes: {img_l.shape[1]} x "
                f"{img_l.shape[0]} vs {img_r.shape[1]} x {img_r.shape[0]} px"
            )
        yield StereoFrame(produced, t_l, t_r, np.asarray(img_l), np.asarray(img_r))
        produced += 1


@contextmanager
def _opened(spec: str, **kwargs: Any) -> Iterator[cv2.VideoCapture]:
    cap = open_source(spec, **kwargs)
    try:
        yield cap
    finally:
        cap.release()


TIMESTAMP_COLUMNS = ("index", "left", "right", "t_left_s", "t_right_s", "skew_s")
"""Columns of ``timestamps.csv`` (:func:`timestamps_csv`)."""


def pair_files(frame: StereoFrame) -> dict[str, bytes]:
    """The pair as PNG files, ``left_NNNNNN.png`` and ``right_NNNNNN.png``, name to bytes.

    Raises
    ------
    InputError
        If a frame cannot be encoded.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.capture import StereoFrame, pair_files
    >>> image = np.zeros((4, 6, 3), np.uint8)
    >>> files = pair_files(StereoFrame(7, t_left_s=0.0, t_right_s=0.0, left=image, right=image))
    >>> sorted(files), files["left_000007.png"][:4]
    (['left_000007.png', 'right_000007.png'], b'\x89PNG')
    """
    files: dict[str, bytes] = {}
    for side, img in (("left", frame.left), ("right", frame.right)):
        name = f"{side}_{frame.index:06d}.png"
        ok, buf = cv2.imencode(".png", img)
        if not ok:
            raise InputError(f"{name}: could not be encoded as PNG")
        files[name] = bytes(buf.tobytes())
    return files


def timestamp_row(frame: StereoFrame) -> dict[str, Any]:
    """The ``timestamps.csv`` row of a pair: file names, timestamps and skew [s].

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.capture import StereoFrame, timestamp_row
    >>> image = np.zeros((4, 6, 3), np.uint8)
    >>> row = timestamp_row(StereoFrame(3, t_left_s=0.5, t_right_s=0.75, left=image, right=image))
    >>> row["left"], row["right"], row["skew_s"]
    ('left_000003.png', 'right_000003.png', 0.25)
    """
    return {
        "index": frame.index,
        "left": f"left_{frame.index:06d}.png",
        "right": f"right_{frame.index:06d}.png",
        "t_left_s": frame.t_left_s,
        "t_right_s": frame.t_right_s,
        "skew_s": frame.skew_s,
    }


def timestamps_csv(rows: list[dict[str, Any]]) -> str:
    """``timestamps.csv`` text of :func:`timestamp_row` rows (columns
    :data:`TIMESTAMP_COLUMNS`).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.capture import StereoFrame, timestamp_row, timestamps_csv
    >>> image = np.zeros((4, 6, 3), np.uint8)
    >>> row = timestamp_row(StereoFrame(0, t_left_s=0.0, t_right_s=0.5, left=image, right=image))
    >>> print(timestamps_csv([row]), end="")
    index,left,right,t_left_s,t_right_s,skew_s
    0,left_000000.png,right_000000.png,0.0,0.5,0.5
    """
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=list(TIMESTAMP_COLUMNS), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return text.getvalue()


def stereo_capture(
    left: str,
    right: str,
    *,
    n_frames: int,
    offset_frames: int = 0,
    every: int = 1,
    width: int | None = None,
    height: int | None = None,
) -> Iterator[StereoFrame]:
    """Capture up to ``n_frames`` synchronised pairs from two sources, one at a time.

    Opens both sources (:func:`open_source`), yields :func:`read_pairs`' pairs, and
    releases the sources when the iteration ends. The caller keeps or saves each pair
    (:func:`pair_files`, :func:`timestamp_row`); the library writes no file.

    Raises
    ------
    InputError
        If a source cannot be opened (named), or yields no frame at all.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import cv2
    >>> import numpy as np
    >>> from firefleet.perception.capture import stereo_capture
    >>> folder = tempfile.TemporaryDirectory()
    >>> video = str(pathlib.Path(folder.name) / "clip.avi")
    >>> writer = cv2.VideoWriter(video, cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (32, 24))
    >>> for k in range(3):
    ...     writer.write(np.full((24, 32, 3), 40 * k, np.uint8))
    >>> writer.release()
    >>> [pair.skew_s for pair in stereo_capture(video, video, n_frames=3)]
    [0.0, 0.0, 0.0]
    >>> folder.cleanup()
    """
    devices = (_is_device(left), _is_device(right))
    produced = 0
    with (
        _opened(left, width=width, height=height) as cap_l,
        _opened(right, width=width, height=height) as cap_r,
    ):
        for f in read_pairs(
            cap_l,
            cap_r,
            n_frames=n_frames,
            offset_frames=offset_frames,
            every=every,
            devices=devices,
        ):
            produced += 1
            yield f
    if produced == 0:
        raise InputError(f"no frame pair could be read from {left} and {right}")
    if produced < n_frames:
        log.warning("a source ended after %d of %d pairs", produced, n_frames)
