"""The compiled destripe steps and 3 x 3 median equal their NumPy / SciPy references."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.ndimage as ndi

from firefleet.perception.thermal._frames import _column_steps, _median3_nearest


def _reference_steps(f: np.ndarray, max_step: float) -> np.ndarray:
    diff = f[:, 1:] - f[:, :-1]
    masked = np.where(np.abs(diff) < max_step, diff, np.nan)
    steps = np.zeros(diff.shape[1])
    usable = np.isfinite(masked).any(axis=0)
    if usable.any():
        steps[usable] = np.nanmedian(masked[:, usable], axis=0)
    return steps


@pytest.mark.parametrize("seed", range(6))
def test_compiled_filters_equal_the_references(seed: int) -> None:
    rng = np.random.default_rng(seed)
    h, w = (60, 80) if seed < 3 else (int(rng.integers(3, 12)), int(rng.integers(3, 12)))
    frame = 25.0 + rng.normal(0.0, 0.7, (h, w)) + rng.normal(0.0, 0.3, w)
    frame[rng.random((h, w)) < 0.05] = 400.0  # hot pixels and edges
    frame[:, : w // 3] += 30.0 * (seed % 2)  # a scene edge
    np.testing.assert_array_equal(_column_steps(frame, 1.0), _reference_steps(frame, 1.0))
    np.testing.assert_array_equal(
        _median3_nearest(frame), ndi.median_filter(frame, size=3, mode="nearest")
    )


def test_no_usable_row_is_a_zero_step() -> None:
    frame = np.zeros((4, 3))
    frame[:, 1] = 5.0  # every difference is an edge
    assert _column_steps(frame, 1.0).tolist() == [0.0, 0.0]
