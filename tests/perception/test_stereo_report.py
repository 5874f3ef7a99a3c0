"""The colour-mapped disparity PNG."""

from __future__ import annotations

import cv2
import numpy as np
from matplotlib import colormaps

from firefleet.report.stereo import disparity_png, rectified_pair_png


def test_disparity_png_maps_values_and_draws_nan_black() -> None:
    disp = np.tile(np.linspace(0.0, 30.0, 31, dtype=np.float32), (12, 1))
    disp[3, 5] = np.nan
    img = cv2.imdecode(np.frombuffer(disparity_png(disp, vmin=0.0, vmax=30.0), np.uint8), 1)
    assert img is not None
    assert img.shape == (12, 31, 3)  # one image pixel per disparity pixel
    np.testing.assert_array_equal(img[3, 5], [0, 0, 0])
    # Each column's colour is turbo at (d - vmin) / (vmax - vmin), to 8-bit rounding.
    expected = colormaps["turbo"](np.linspace(0.0, 1.0, 31))[:, :3] * 255
    np.testing.assert_allclose(img[0, :, ::-1], expected, atol=0.51)


def test_rectified_pair_png_is_a_png() -> None:
    left = np.zeros((40, 60, 3), np.uint8)
    data = rectified_pair_png(left, left, lines=4)
    img = cv2.imdecode(np.frombuffer(data, np.uint8), 1)
    assert img is not None
    assert img.shape[1] == 120  # two 60 px images side by side at 100 dpi
