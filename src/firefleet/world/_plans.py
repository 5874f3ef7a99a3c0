"""The built-in floor plans, drawn cell by cell, and their ``map_server`` encoding.

The maps shipped in ``firefleet/world/maps/`` (``office``, ``warehouse``, ``maze``, and
``floor100`` from :mod:`firefleet.world._floor100`) are the output of the functions
here, written by ``tools/make_maps.py``; a test checks the shipped files equal what
these functions draw, so the maps' provenance is this code. Every plan is at 0.05 m per
cell (``floor100``: 0.25 m) with its origin at (0, 0).

References
----------
ROS ``map_server`` map format: http://wiki.ros.org/map_server#Map_format
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from firefleet._typing import BoolArray
from firefleet.world._floor100 import FLOOR100_RESOLUTION_M, floor100

__all__ = [
    "PLANS",
    "RESOLUTION_M",
    "boxes_plan",
    "encode_pgm",
    "map_yaml",
    "maze",
    "office",
    "warehouse",
]

RESOLUTION_M = 0.05
"""Cell side of every built-in plan [m]."""

_WALL_M = 0.15
"""Thickness of inner walls [m]."""


def _cells(metres: float) -> int:
    return round(metres / RESOLUTION_M)


def _fill(
    occupied: BoolArray, x0_m: float, y0_m: float, x1_m: float, y1_m: float, value: bool
) -> None:
    """Set the rectangle ``[x0, x1) x [y0, y1)`` [m] to ``value`` (y up, row 0 at the
    top), clipped to the grid."""
    h = occupied.shape[0]
    c0, c1 = _cells(x0_m), _cells(x1_m)
    r0, r1 = h - _cells(y1_m), h - _cells(y0_m)
    occupied[max(r0, 0) : max(r1, 0), max(c0, 0) : max(c1, 0)] = value


def _box(occupied: BoolArray, x0_m: float, y0_m: float, x1_m: float, y1_m: float) -> None:
    """Mark the rectangle ``[x0, x1) x [y0, y1)`` [m] occupied (y up, row 0 at the top)."""
    _fill(occupied, x0_m, y0_m, x1_m, y1_m, True)


def _clear(occupied: BoolArray, x0_m: float, y0_m: float, x1_m: float, y1_m: float) -> None:
    """Mark the rectangle free again (a door in a wall)."""
    h = occupied.shape[0]
    c0, c1 = _cells(x0_m), _cells(x1_m)
    r0, r1 = h - _cells(y1_m), h - _cells(y0_m)
    occupied[r0:r1, c0:c1] = False


def _outline(width_m: float, height_m: float) -> BoolArray:
    """An empty floor of ``width_m`` x ``height_m`` with an outer wall all round."""
    occupied = np.zeros((_cells(height_m), _cells(width_m)), dtype=bool)
    _box(occupied, 0.0, 0.0, width_m, _WALL_M)
    _box(occupied, 0.0, height_m - _WALL_M, width_m, height_m)
    _box(occupied, 0.0, 0.0, _WALL_M, height_m)
    _box(occupied, width_m - _WALL_M, 0.0, width_m, height_m)
    return occupied


def office() -> BoolArray:
    """An office floor, 20 m x 10 m: a corridor along x (y 4.2-5.8 m) between four
    rooms on each side, of unequal widths (south: walls at x 4, 9, 15 m; north: 6, 10,
    14 m), each with a 0.9 m door on the corridor off its centre, a cabinet in the
    south-west room and a pillar in the north-east one: no two places look alike, so a
    robot can localise on it (a symmetric plan would leave MCL two equal answers).

    Examples
    --------
    >>> from firefleet.world._plans import office
    >>> office().shape  # rows (10 m), columns (20 m) at 0.05 m
    (200, 400)
    """
    width, height, door = 20.0, 10.0, 0.9
    occupied = _outline(width, height)
    low, high = 4.2, 5.8  # the corridor's walls, inner faces
    _box(occupied, 0.0, low - _WALL_M, width, low)
    _box(occupied, 0.0, high, width, high + _WALL_M)
    for x in (4.0, 9.0, 15.0):  # walls between the south rooms
        _box(occupied, x - _WALL_M / 2, 0.0, x + _WALL_M / 2, low)
    for x in (6.0, 10.0, 14.0):  # and between the north rooms
        _box(occupied, x - _WALL_M / 2, high, x + _WALL_M / 2, height)
    for x in (2.0, 6.0, 12.5, 17.0):  # the south rooms' doors (centres)
        _clear(occupied, x - door / 2, low - _WALL_M, x + door / 2, low)
    for x in (3.0, 8.5, 11.5, 17.5):  # the north rooms' doors
        _clear(occupied, x - door / 2, high, x + door / 2, high + _WALL_M)
    _box(occupied, 0.6, 0.15, 1.6, 0.75)  # a cabinet against the south wall
    _box(occupied, 18.0, 8.0, 18.4, 8.4)  # a pillar
    return occupied


def warehouse() -> BoolArray:
    """A warehouse, 30 m x 20 m: eight shelving racks (1.2 m deep, 13 m long) along y
    with 2 m aisles between them, cross aisles along both ends, and a loading area.

    Examples
    --------
    >>> from firefleet.world._plans import warehouse
    >>> warehouse().shape
    (400, 600)
    """
    width, height = 30.0, 20.0
    occupied = _outline(width, height)
    for k in range(8):
        x = 4.0 + 3.2 * k
        _box(occupied, x, 3.5, x + 1.2, 16.5)
    # the loading area's pallets, off the bottom cross aisle's far end
    _box(occupied, 1.0, 1.0, 2.5, 2.2)
    return occupied


def maze(seed: int = 7) -> BoolArray:
    """A 10 x 7 cell maze of 1.2 m cells (12 m x 8.4 m), carved by a depth-first search
    from a seeded generator (a perfect maze: one way between any two cells).

    Examples
    --------
    >>> from firefleet.world._plans import maze
    >>> grid = maze()
    >>> grid.shape, bool(grid[0, 0]), bool(grid[-30, 30])  # a wall corner, a free cell
    ((168, 240), True, False)
    """
    cols, rows, cell = 10, 7, 1.2
    rng = np.random.default_rng(seed)
    width, height = cols * cell, rows * cell
    occupied = _outline(width, height)
    # walls: east of (i, j) and north of (i, j), i along x, j along y; all up to start
    east = np.ones((cols, rows), dtype=bool)
    north = np.ones((cols, rows), dtype=bool)
    seen = np.zeros((cols, rows), dtype=bool)
    stack = [(0, 0)]
    seen[0, 0] = True
    while stack:
        i, j = stack[-1]
        nexts = [
            (a, b)
            for a, b in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1))
            if 0 <= a < cols and 0 <= b < rows and not seen[a, b]
        ]
        if not nexts:
            stack.pop()
            continue
        a, b = nexts[int(rng.integers(len(nexts)))]
        if a != i:
            east[min(a, i), j] = False
        else:
            north[i, min(b, j)] = False
        seen[a, b] = True
        stack.append((a, b))
    half = _WALL_M / 2
    for i in range(cols):
        for j in range(rows):
            x1, y1 = (i + 1) * cell, (j + 1) * cell
            if east[i, j] and i < cols - 1:
                _box(occupied, x1 - half, j * cell - half, x1 + half, y1 + half)
            if north[i, j] and j < rows - 1:
                _box(occupied, i * cell - half, y1 - half, x1 + half, y1 + half)
    return occupied


PLANS = {"office": office, "warehouse": warehouse, "maze": maze, "floor100": floor100}
"""The built-in plans by name."""

_FREE_VALUE = 254
_OCCUPIED_VALUE = 0


def boxes_plan(
    width_m: float,
    height_m: float,
    solid: Sequence[tuple[float, float, float, float]],
    openings: Sequence[tuple[float, float, float, float]] = (),
) -> BoolArray:
    """A floor plan at ``RESOLUTION_M`` drawn from rectangles: the ``solid`` ones
    (walls, furniture) occupied, then the ``openings`` (doors) free again; each
    ``(x0, y0, x1, y1)`` [m] covers ``[x0, x1) x [y0, y1)`` (y up, row 0 at the top),
    clipped to the floor. The drawing scripts of ``examples/missions/`` use it.

    Examples
    --------
    >>> plan = boxes_plan(1.0, 0.5, [(0.0, 0.0, 1.0, 0.5)], [(0.4, 0.0, 0.6, 0.5)])
    >>> plan.shape, int(plan.sum()), bool(plan[:, 8:12].any())  # a 0.2 m door
    ((10, 20), 160, False)
    """
    occupied = np.zeros((_cells(height_m), _cells(width_m)), dtype=bool)
    for boxes, value in ((solid, True), (openings, False)):
        for box in boxes:
            _fill(occupied, *box, value)
    return occupied


def encode_pgm(occupied: BoolArray) -> bytes:
    """A binary PGM (P5) of the plan: occupied 0 (black), free 254 (white).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world._plans import encode_pgm
    >>> encode_pgm(np.array([[True, False]]))
    b'P5\\n2 1\\n255\\n\\x00\\xfe'
    """
    h, w = occupied.shape
    pixels = np.where(occupied, _OCCUPIED_VALUE, _FREE_VALUE).astype(np.uint8)
    return f"P5\n{w} {h}\n255\n".encode("ascii") + pixels.tobytes()


def map_yaml(image: str) -> str:
    """The ``map_server`` YAML of a built-in plan whose image is ``image``.

    Examples
    --------
    >>> from firefleet.world._plans import map_yaml
    >>> print(map_yaml("office.pgm").splitlines()[0])
    image: office.pgm
    >>> print(map_yaml("floor100.pgm").splitlines()[1])
    resolution: 0.25
    """
    resolution = FLOOR100_RESOLUTION_M if image == "floor100.pgm" else RESOLUTION_M
    return (
        f"image: {image}\n"
        f"resolution: {resolution}\n"
        "origin: [0.0, 0.0, 0.0]\n"
        "negate: 0\n"
        "occupied_thresh: 0.65\n"
        "free_thresh: 0.196\n"
        "mode: trinary\n"
    )
