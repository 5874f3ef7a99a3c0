"""Sums over a grid cell's neighbours, zero off the grid (the fire's and the fields' one
stencil)."""

from __future__ import annotations

import numpy as np

from firefleet._typing import FloatArray


def neighbour_sum(values: FloatArray, diagonal_weight: float = 0.0) -> FloatArray:
    """Each cell's four edge neighbours summed, plus ``diagonal_weight`` times its four
    diagonal ones, shape (H, W) like ``values``."""
    padded = np.pad(values, 1)
    out: FloatArray = padded[:-2, 1:-1] + padded[2:, 1:-1] + padded[1:-1, :-2] + padded[1:-1, 2:]
    if diagonal_weight:
        diag = padded[:-2, :-2] + padded[:-2, 2:] + padded[2:, :-2] + padded[2:, 2:]
        out = out + diagonal_weight * diag
    return out
