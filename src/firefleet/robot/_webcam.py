"""The robot's USB webcams (one, or a stereo pair) through OpenCV's V4L2 capture.

The deliverable read each webcam with its own process (``fswebcam``, ``motion``); here
one thread reads both through :mod:`firefleet.perception.capture` (the ``stereo
capture`` command's reader: grab both, then decode both, each frame with its
timestamp), a few times a second, and the on-board loop takes the newest pair without
waiting for a camera (a grab waits for the next exposure, up to 33 ms at 30 fps: three
control periods). Live cameras keep one driver buffer, so the pair taken is the newest,
not one queued seconds ago.

A read that fails (no frame: a camera unplugged, a file at its end) is counted in
``dropped``; a frame that cannot be decoded in ``failed``; neither stops the robot.
A camera that gives frames of another size than configured is an error naming both
sizes at open (the stereo calibration is for one size), and counted in ``failed``
afterwards. Video files stand in for the cameras in tests and with ``--fake``, as
they do for ``firefleet stereo capture``: their timestamps are the position in the
file, their frames are taken one per period.
"""

from __future__ import annotations

import dataclasses
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from firefleet.errors import InputError
from firefleet.perception._opencv import quiet_opencv
from firefleet.perception.capture import StereoFrame, open_source, read_pairs

__all__ = ["WebcamFrame", "Webcams"]


@dataclass(frozen=True, eq=False)
class WebcamFrame:
    """One capture from every camera.

    Attributes
    ----------
    index : int
        Capture number, from 0.
    t_s : tuple of float
        Each camera's timestamp [s]: the monotonic clock at the grab for a camera, the
        position in the file for a video file.
    images : tuple of ndarray of uint8, shape (H, W, 3)
        BGR frames, left first.
    scan : dict or None
        What the adapter's ``process`` made of the capture (the stereo scan's numbers),
        None without one.
    """

    index: int
    t_s: tuple[float, ...]
    images: tuple[NDArray[np.uint8], ...]
    scan: dict[str, Any] | None = None

    @property
    def pair(self) -> StereoFrame:
        """The two cameras' frames as a stereo pair (the stereo pipeline's input)."""
        if len(self.images) != 2:
            raise InputError(f"a stereo pair needs two cameras, this frame has {len(self.images)}")
        return StereoFrame(self.index, self.t_s[0], self.t_s[1], *self.images)


def _is_device(spec: str) -> bool:
    return spec.isdigit() or spec.startswith("/dev/video")


class Webcams:
    """One camera or a stereo pair, read at ``rate_hz`` (module notes).

    Parameters
    ----------
    sources : sequence of str
        One or two sources, left first: ``/dev/videoN``, ``N``, or a video file.
    width, height : int
        The frame size expected (and requested from cameras) [px].
    rate_hz : float
        Captures per second of the background thread (:meth:`start`).
    process : callable, optional
        Run by the background thread on each capture (e.g. the stereo pipeline); its
        dict becomes the frame's ``scan``. Slower than ``1 / rate_hz``, it lowers the
        rate, never the control loop's.

    Raises
    ------
    InputError
        A source that cannot be opened (named), no first frame, or frames of another
        size than ``width`` x ``height``.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import cv2
    >>> import numpy as np
    >>> from firefleet.robot import Webcams
    >>> folder = tempfile.TemporaryDirectory()
    >>> video = str(pathlib.Path(folder.name) / "clip.avi")
    >>> writer = cv2.VideoWriter(video, cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (32, 24))
    >>> for k in range(2):
    ...     writer.write(np.full((24, 32, 3), 80 * k, np.uint8))
    >>> writer.release()
    >>> with Webcams([video, video], width=32, height=24) as cams:
    ...     frames = [cams.read(), cams.read(), cams.read()]
    >>> [f.t_s for f in frames[:2]], frames[2], cams.dropped
    ([(0.0, 0.0), (0.1, 0.1)], None, 1)
    >>> folder.cleanup()
    """

    def __init__(
        self,
        sources: list[str] | tuple[str, ...],
        *,
        width: int = 640,
        height: int = 480,
        rate_hz: float = 2.0,
        process: Callable[[WebcamFrame], dict[str, Any]] | None = None,
    ) -> None:
        if len(sources) not in (1, 2):
            raise InputError(f"webcams: {len(sources)} sources, expected 1 or 2 (left, right)")
        if not (width > 0 and height > 0 and rate_hz > 0.0):
            raise InputError(f"webcams: width {width}, height {height}, rate_hz {rate_hz}: > 0")
        self.sources = tuple(sources)
        self.shape = (height, width, 3)
        self.rate_hz = rate_hz
        self._process = process
        self.dropped = 0
        """Reads that gave no frame (camera gone, file ended)."""
        self.failed = 0
        """Frames that could not be decoded or had the wrong size."""
        self.captured = 0
        self._devices = tuple(_is_device(s) for s in sources)
        self._caps: list[cv2.VideoCapture] = []
        self._latest: WebcamFrame | None = None
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        try:
            for spec, device in zip(sources, self._devices, strict=True):
                cap = open_source(spec, width=width, height=height)
                self._caps.append(cap)
                if device:
                    cap.set(cv2.CAP_PROP_BUFFERSIZE, 1)
            first = self._grab()
            if first is None:
                raise InputError(f"webcams {', '.join(sources)}: no frame could be read")
            self._held: WebcamFrame | None = first
        except BaseException:
            self.close()
            raise

    def _check_shape(self, frame: WebcamFrame) -> None:
        for spec, image in zip(self.sources, frame.images, strict=True):
            if image.shape != self.shape:
                h, w = self.shape[:2]
                channels = image.shape[2] if image.ndim == 3 else 1
                got = f"{image.shape[1]}x{image.shape[0]}x{channels}"
                raise InputError(
                    f"webcam {spec}: frames of {got} (width x height x channels), "
                    f"expected {w}x{h}x3 (hardware.webcams.width/height)"
                )

    def _grab(self) -> WebcamFrame | None:
        """One capture from every camera (None: no frame, counted in ``dropped``).

        Raises InputError if a frame cannot be decoded or the cameras' sizes differ.
        """
        index = self.captured
        if len(self._caps) == 2:
            pairs = list(read_pairs(*self._caps, n_frames=1, devices=self._devices))  # type: ignore[arg-type]
            if not pairs:
                self.dropped += 1
                return None
            p = pairs[0]
            frame = WebcamFrame(index, (p.t_left_s, p.t_right_s), (p.left, p.right))
        else:
            cap = self._caps[0]
            with quiet_opencv():
                grabbed = cap.grab()
                t = time.monotonic() if self._devices[0] else cap.get(cv2.CAP_PROP_POS_MSEC)
                got, image = cap.retrieve() if grabbed else (False, None)
            if not grabbed:
                self.dropped += 1
                return None
            if not got or image is None:
                raise InputError(f"webcam {self.sources[0]}: a frame could not be decoded")
            t_s = float(t) if self._devices[0] else float(t) / 1000.0
            frame = WebcamFrame(index, (t_s,), (np.asarray(image),))
        self._check_shape(frame)
        self.captured += 1
        return frame

    def read(self) -> WebcamFrame | None:
        """Capture now, in the caller's thread (None: nothing read, counted in
        ``dropped`` or ``failed``)."""
        held = self._held
        if held is not None:  # the frame read at open
            self._held = None
            return held
        try:
            return self._grab()
        except InputError:  # undecodable, or not the configured size
            self.failed += 1
            return None

    def start(self) -> None:
        """Capture in a background thread at ``rate_hz``; :meth:`poll` takes the newest."""
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name="webcams", daemon=True)
            self._thread.start()

    def _run(self) -> None:
        period = 1.0 / self.rate_hz
        deadline = time.monotonic()
        while not self._stop.is_set():
            frame = self.read()
            if frame is not None and self._process is not None:
                try:
                    frame = dataclasses.replace(frame, scan=self._process(frame))
                except (InputError, cv2.error):  # a pair the pipeline cannot take
                    self.failed += 1
            if frame is not None:
                with self._lock:
                    self._latest = frame
            deadline = max(deadline + period, time.monotonic())
            self._stop.wait(deadline - time.monotonic())

    def poll(self) -> WebcamFrame | None:
        """The newest capture not taken yet (None if there is none); never blocks."""
        with self._lock:
            frame, self._latest = self._latest, None
        return frame

    def close(self) -> None:
        """Stop the thread and release the cameras."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
        for cap in self._caps:
            cap.release()
        self._caps = []

    def __enter__(self) -> Webcams:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
