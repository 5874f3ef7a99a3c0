"""Compiled grid geometry: the metre -> cell map of :class:`~firefleet.world.OccupancyGrid`
as the kernels use it, and the cells a beam crosses (Bresenham).

The kernels cannot call a Python method, so :func:`grid_frame` reads the grid's constants
once and :func:`cell_rc` applies exactly :meth:`OccupancyGrid.cell_of`'s formula
(``col = floor((x - ox) / r)``, ``row = H - 1 - floor((y - oy) / r)``);
tests/estimation/test_grid_mapping.py checks the two agree.

References
----------
J. E. Bresenham, "Algorithm for computer control of a digital plotter", IBM Systems
Journal 4(1), 1965.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from firefleet.world import OccupancyGrid

__all__ = ["grid_frame"]


def grid_frame(grid: OccupancyGrid) -> tuple[float, float, float, int, int]:
    """``(ox, oy, resolution, H, W)``: the constants of ``grid.cell_of`` for the kernels."""
    h, w = grid.shape
    return grid.origin_m[0], grid.origin_m[1], grid.resolution_m, h, w


@njit(cache=True)
def cell_rc(x: float, y: float, ox: float, oy: float, res: float, h: int) -> tuple[int, int]:
    """The (row, col) holding point (x, y), as ``OccupancyGrid.cell_of``."""
    col = math.floor((x - ox) / res)
    row = h - 1 - math.floor((y - oy) / res)
    return row, col


@njit(cache=True)
def _visit(
    marks: np.ndarray,
    values: np.ndarray,
    r0: int,
    c0: int,
    r1: int,
    c1: int,
    include_end: bool,
    mode: int,
    l_free: float,
    l_occ: float,
    lo: float,
    hi: float,
) -> None:
    """Walk the Bresenham line r0,c0 -> r1,c1 over the cells on the grid.

    mode 0 marks unmarked cells free (1); mode 1 applies the marks to ``values`` (free:
    ``+l_free``, occupied: ``+l_occ``, clamped to [lo, hi]) and clears them.
    """
    h, w = marks.shape
    dr = abs(r1 - r0)
    dc = abs(c1 - c0)
    sr = 1 if r1 > r0 else -1
    sc = 1 if c1 > c0 else -1
    err = dc - dr
    r, c = r0, c0
    while True:
        last = r == r1 and c == c1
        if last and not include_end:
            return
        if r < 0 or r >= h or c < 0 or c >= w:
            return  # the ray has left the grid (it started on it): nothing further
        m = marks[r, c]
        if mode == 0:
            if m == 0:
                marks[r, c] = 1
        elif m != 0:
            v = values[r, c] + (l_occ if m == 2 else l_free)
            values[r, c] = min(max(v, lo), hi)
            marks[r, c] = 0
        if last:
            return
        e2 = 2 * err
        if e2 > -dr:
            err -= dr
            c += sc
        if e2 < dc:
            err += dc
            r += sr


@njit(cache=True)
def scan_update(
    values: np.ndarray,
    marks: np.ndarray,
    r0: int,
    c0: int,
    end_r: np.ndarray,
    end_c: np.ndarray,
    hit: np.ndarray,
    l_free: float,
    l_occ: float,
    lo: float,
    hi: float,
) -> None:
    """One scan's inverse sensor model, in place on the log-odds ``values`` (H, W).

    Each cell the scan touches is updated once: occupied if it holds a beam's hit
    (``hit[b]``, end cell ``end_r[b], end_c[b]``), else free if a beam crosses it (the
    hit cell excluded, a no-return beam's end cell included). ``marks`` (H, W) int8 is
    zero on entry and on exit.
    """
    h, w = values.shape
    for b in range(end_r.shape[0]):
        if hit[b] and 0 <= end_r[b] < h and 0 <= end_c[b] < w:
            marks[end_r[b], end_c[b]] = 2
    for b in range(end_r.shape[0]):
        _visit(marks, values, r0, c0, end_r[b], end_c[b], not hit[b], 0, 0.0, 0.0, lo, hi)
    for b in range(end_r.shape[0]):
        _visit(marks, values, r0, c0, end_r[b], end_c[b], True, 1, l_free, l_occ, lo, hi)
