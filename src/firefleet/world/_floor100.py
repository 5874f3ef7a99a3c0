"""``floor100``: one storey of a large building, 100 m x 100 m, drawn cell by cell.

The plan of issue 15's ``mission-large``: four east-west corridors (2.5 m wide, centres
at y = 12.5, 37.5, 62.5, 87.5 m) crossed by three north-south ones (a 3 m spine at x =
50 m and 2.5 m corridors at x = 17 and 83 m); between them eight rows of rooms about
10.75 m deep, each row facing its corridor, cut into 84 rooms 3.75-10.75 m wide
(widths of 4-8 m drawn from a generator seeded with ``seed``, the last of a row taking
the rest), each with a 1.0 m door on its corridor at a drawn offset; four halls of
15-30 m x 22 m (two rows merged) with two 2 m double doors on each of their corridors
and 0.5 m pillars on a 6 m grid; and the entrance lobby (12 m x 10.75 m) at the south
end of the spine, where the team starts. Walls are one cell
(0.25 m) thick and lie on cell faces, so the range sensors' exact ray casting sees them
where they are drawn.

The resolution, 0.25 m, keeps the map at 400 x 400 cells (a 160 kB PGM) and makes the
mission's field grid (0.25 m by default) the map itself; a door of four cells leaves a
robot of radius 0.15 m a 0.5 m clearance at its centre.

References
----------
ROS ``map_server`` map format: http://wiki.ros.org/map_server#Map_format
"""

from __future__ import annotations

import numpy as np

from firefleet._typing import BoolArray, FloatArray

__all__ = ["FLOOR100_RESOLUTION_M", "floor100", "floor100_rooms"]

FLOOR100_RESOLUTION_M = 0.25
"""Cell side of ``floor100`` [m]."""

_SIZE_M = 100.0
_WALL_M = 0.25
_DOOR_M = 1.0
_HALL_DOOR_M = 2.0
_SEED = 15

# The east-west corridors: (south face, north face) of their free floor [m].
_CORRIDORS_Y = ((11.25, 13.75), (36.25, 38.75), (61.25, 63.75), (86.25, 88.75))
# The north-south corridors: (west face, east face) [m].
_CORRIDORS_X = ((15.75, 18.25), (48.5, 51.5), (81.75, 84.25))
# The rows of rooms: (y0, y1) of their free floor [m] and the corridor side of the row
# (+1: the corridor is north of the row, -1: south).
_ROWS = (
    (0.25, 11.0, +1),
    (14.0, 25.0, -1),
    (25.25, 36.0, +1),
    (39.0, 50.0, -1),
    (50.25, 61.0, +1),
    (64.0, 75.0, -1),
    (75.25, 86.0, +1),
    (89.0, 99.75, -1),
)
# The blocks between the north-south corridors: (x0, x1) of their free floor [m].
_BLOCKS = ((0.25, 15.5), (18.5, 48.25), (51.75, 81.5), (84.5, 99.75))
# The halls: (block index, first row index); each spans that row and the next.
_HALLS = ((1, 3), (2, 1), (0, 5), (3, 3))
# The entrance lobby: its free floor [m], at the south end of the spine.
_LOBBY = (44.0, 56.0, 0.25, 11.0)


def _cells(metres: float) -> int:
    return round(metres / FLOOR100_RESOLUTION_M)


def _fill(occupied: BoolArray, x0: float, y0: float, x1: float, y1: float, value: bool) -> None:
    """Set the rectangle ``[x0, x1) x [y0, y1)`` [m] (y up, row 0 at the top)."""
    h = occupied.shape[0]
    occupied[h - _cells(y1) : h - _cells(y0), _cells(x0) : _cells(x1)] = value


def floor100_rooms(seed: int = _SEED) -> FloatArray:
    """The rooms of :func:`floor100`: each one's free floor ``(x0, x1, y0, y1)`` [m] and
    its door's centre ``(x, y)`` [m], shape (R, 6); halls give one row per door, the
    lobby is the last row (its "door" is its centre).

    Examples
    --------
    >>> from firefleet.world._floor100 import floor100_rooms
    >>> rooms = floor100_rooms()
    >>> rooms.shape[1], bool((rooms[:, 1] - rooms[:, 0] >= 3.0).all())
    (6, True)
    """
    rng = np.random.default_rng(seed)
    out: list[tuple[float, ...]] = []
    halls = {(b, r) for b, r in _HALLS} | {(b, r + 1) for b, r in _HALLS}
    for r, (y0, y1, side) in enumerate(_ROWS):
        door_y = y1 + _WALL_M / 2 if side > 0 else y0 - _WALL_M / 2
        for b, (bx0, bx1) in enumerate(_BLOCKS):
            if (b, r) in halls:
                continue
            spans = [(bx0, bx1)]
            if r == 0 and bx0 < _LOBBY[1] and bx1 > _LOBBY[0]:  # the lobby cuts the row
                spans = [(bx0, _LOBBY[0] - _WALL_M)] if bx1 <= 50.0 else []
                spans += [(_LOBBY[1] + _WALL_M, bx1)] if bx0 >= 50.0 else []
            for sx0, sx1 in spans:
                x = sx0
                while sx1 - x >= 3.0:
                    width = float(rng.choice([4.0, 5.0, 6.0, 7.0, 8.0]))
                    end = sx1 if sx1 - (x + width) < 4.0 else x + width
                    slack = end - x - _DOOR_M - 1.0
                    door_x = (
                        x + 0.5 + _DOOR_M / 2 + 0.25 * int(rng.integers(0, int(slack / 0.25) + 1))
                    )
                    out.append((x, end, y0, y1, door_x, door_y))
                    x = end + _WALL_M
    for b, r in _HALLS:
        x0, x1 = _BLOCKS[b]
        y0, y1 = _ROWS[r][0], _ROWS[r + 1][1]
        for door_y in (y0 - _WALL_M / 2, y1 + _WALL_M / 2):
            for door_x in (x0 + 0.3 * (x1 - x0), x0 + 0.7 * (x1 - x0)):
                out.append((x0, x1, y0, y1, round(door_x * 4) / 4, door_y))
    lx0, lx1, ly0, ly1 = _LOBBY
    out.append((lx0, lx1, ly0, ly1, (lx0 + lx1) / 2, (ly0 + ly1) / 2))
    return np.asarray(out, dtype=float)


def floor100(seed: int = _SEED) -> BoolArray:
    """The plan (module notes): occupied cells, shape (400, 400), 0.25 m per cell.

    Examples
    --------
    >>> from firefleet.world._floor100 import floor100
    >>> plan = floor100()
    >>> plan.shape, round(float(plan.mean()), 2)  # rows (100 m), columns; wall share
    ((400, 400), 0.06)
    """
    n = _cells(_SIZE_M)
    occupied = np.ones((n, n), dtype=bool)
    halls = {(b, r) for b, r in _HALLS}
    for y0, y1 in _CORRIDORS_Y:
        _fill(occupied, _WALL_M, y0, _SIZE_M - _WALL_M, y1, False)
    for x0, x1 in _CORRIDORS_X:
        _fill(occupied, x0, _WALL_M, x1, _SIZE_M - _WALL_M, False)
    rooms = floor100_rooms(seed)
    for x0, x1, y0, y1, door_x, door_y in rooms:
        _fill(occupied, x0, y0, x1, y1, False)
        wide = _HALL_DOOR_M if y1 - y0 > 20.0 else _DOOR_M  # a hall spans two rows
        if (x0, x1, y0, y1) != _LOBBY:
            half = wide / 2
            _fill(
                occupied, door_x - half, door_y - _WALL_M / 2, door_x + half, door_y + 0.125, False
            )
    lx0, lx1, _, ly1 = _LOBBY  # the lobby opens 10 m wide onto the first corridor
    _fill(occupied, lx0 + 1.0, ly1, lx1 - 1.0, ly1 + _WALL_M, False)
    for b, r in halls:  # the pillars
        x0, x1 = _BLOCKS[b]
        y0, y1 = _ROWS[r][0], _ROWS[r + 1][1]
        for px in np.arange(x0 + 6.0, x1 - 3.0, 6.0):
            for py in np.arange(y0 + 5.5, y1 - 3.0, 6.0):
                _fill(occupied, float(px), float(py), float(px) + 0.5, float(py) + 0.5, True)
    return occupied
