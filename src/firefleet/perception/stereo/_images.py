"""Images of a stereo pair: reading and checking (``uint8``, OpenCV's BGR order)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet.errors import InputError
from firefleet.perception._opencv import quiet_opencv

Image = NDArray[np.uint8]


def read_image(path: str | Path) -> Image:
    """Read an image file as ``uint8`` BGR (or grey), raising :class:`InputError`.

    Raises
    ------
    InputError
        If the file is missing, empty or not an image OpenCV can decode.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import cv2
    >>> import numpy as np
    >>> from firefleet.perception.stereo import read_image
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = pathlib.Path(folder.name) / "grey.png"
    >>> _ = cv2.imwrite(str(path), np.full((4, 6), 200, np.uint8))
    >>> image = read_image(path)
    >>> image.shape[:2], image.dtype
    ((4, 6), dtype('uint8'))
    >>> folder.cleanup()
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: no such image file")
    data = np.fromfile(p, dtype=np.uint8)
    with quiet_opencv():
        image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data.size else None
    if image is None:
        raise InputError(f"{p}: not a readable image (empty or corrupt)")
    if image.dtype != np.uint8:
        raise InputError(f"{p}: expected an 8-bit image, got {image.dtype}")
    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    return np.asarray(image, dtype=np.uint8)


def _check_image(image: ArrayLike, name: str) -> Image:
    arr = np.asarray(image)
    if arr.dtype != np.uint8:
        raise InputError(f"{name} must be a uint8 image, got dtype {arr.dtype}")
    if not (arr.ndim == 2 or (arr.ndim == 3 and arr.shape[2] == 3)):
        raise InputError(f"{name} must have shape (H, W) or (H, W, 3), got {arr.shape}")
    if min(arr.shape[:2]) < 8:
        raise InputError(f"{name} is too small: {arr.shape[1]} x {arr.shape[0]} px")
    return np.ascontiguousarray(arr)


def check_pair(left: ArrayLike, right: ArrayLike) -> tuple[Image, Image]:
    """Check a stereo pair: two ``uint8`` images of the same size and channel count.

    Returns
    -------
    left, right : ndarray of uint8
        Contiguous ``(H, W)`` or ``(H, W, 3)`` arrays.

    Raises
    ------
    InputError
        If an image is not ``uint8`` grey or 3-channel, or the two differ in shape.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.errors import InputError
    >>> from firefleet.perception.stereo import check_pair
    >>> left, right = check_pair(np.zeros((120, 160), np.uint8), np.zeros((120, 160), np.uint8))
    >>> try:
    ...     check_pair(np.zeros((120, 160), np.uint8), np.zeros((120, 161), np.uint8))
    ... except InputError as error:
    ...     print(error)
    left and right images differ in size: 160 x 120 vs 161 x 120 px
    """
    lft, rgt = _check_image(left, "left image"), _check_image(right, "right image")
    if lft.shape != rgt.shape:
        raise InputError(
            f"left and right images differ in size: {lft.shape[1]} x {lft.shape[0]} "
            f"vs {rgt.shape[1]} x {rgt.shape[0]} px"
            + (" (their channel counts differ)" if lft.shape[:2] == rgt.shape[:2] else "")
        )
    return lft, rgt


def _grey(image: Image) -> Image:
    return image if image.ndim == 2 else np.asarray(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY))
