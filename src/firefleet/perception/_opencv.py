"""OpenCV's own log lines kept off the terminal while the library calls it.

OpenCV prints ``[ WARN:0@...]`` and ``[ERROR:0@...]`` lines straight to the process's
standard error when a camera or file cannot be opened or an image is corrupt. Our
functions report those cases themselves (an :class:`~firefleet.errors.InputError`
naming the file), so the calls that can print are wrapped in :func:`quiet_opencv`,
which silences OpenCV's logger for their duration and restores the level after.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import cv2

_SILENT = 0  # cv2.utils.logging.LOG_LEVEL_SILENT


@contextmanager
def quiet_opencv() -> Iterator[None]:
    """Silence OpenCV's log lines inside the ``with`` block (the old level comes back).

    Examples
    --------
    >>> import numpy as np
    >>> with quiet_opencv():
    ...     cv2.imdecode(np.frombuffer(b"not an image", np.uint8), cv2.IMREAD_UNCHANGED)
    """
    before = int(cv2.utils.logging.getLogLevel())
    cv2.utils.logging.setLogLevel(_SILENT)
    try:
        yield
    finally:
        cv2.utils.logging.setLogLevel(before)
