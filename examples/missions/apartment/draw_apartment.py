"""Draw ``apartment.pgm`` and ``apartment.yaml``: an L-shaped flat, 18 m x 14 m at 0.05 m.

A second floor issue 15's acceptance asks for ("a building you did not tune for"),
unlike the office (a straight corridor), the house, the maze and the warehouse: an
L-shaped outline (a south wing 18 m x 7 m, a west wing 7 m x 14 m; the notch north-east
of them solid), and a hallway 1.5 m wide that turns the corner (along x at y 3.0-4.5 m
from the front door at the east end, then north along y at x 3.0-4.5 m). Eight rooms
off it: three south of it (a kitchen, two rooms), two north of it, a living room and a
bedroom west of the north leg, a long bedroom east of it; 0.15 m walls, 0.9 m doors,
a counter, a sofa, a bed, a table and a wardrobe. Drawn once, with its fire and
people placed (``mission-apartment.yaml``), before any mission ran on it. Run from
this folder: ``python draw_apartment.py`` (then ``git diff`` shows nothing).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from firefleet.world._plans import boxes_plan, encode_pgm, map_yaml

W_M, H_M = 18.0, 14.0
T_M = 0.15


def apartment() -> np.ndarray:
    """The flat's occupied cells (row 0 at the top), shape (280, 360)."""
    walls = [
        # the L's outline and its solid notch (x 7-18 m, y 7-14 m)
        (0, 0, W_M, T_M), (0, 0, T_M, H_M), (W_M - T_M, 0, W_M, 7.0), (0, H_M - T_M, 7.0, H_M),
        (7.0 - T_M, 7.0 - T_M, W_M, H_M),
        # the hallway's walls: south (y 3.0), north (y 4.5), west (x 3.0), east (x 4.5)
        (0, 3.0 - T_M, W_M, 3.0), (4.5, 4.5, W_M, 4.5 + T_M),
        (3.0 - T_M, 3.0, 3.0, H_M), (4.5, 4.5, 4.5 + T_M, H_M),
        # partitions: south rooms (x 6, 12), north rooms (x 11), west rooms (y 8),
        # the north room and the long bedroom (y 7)
        (6.0, 0, 6.0 + T_M, 3.0), (12.0, 0, 12.0 + T_M, 3.0), (11.0, 4.5, 11.0 + T_M, 7.0),
        (0, 8.0, 3.0, 8.0 + T_M), (4.5, 7.0 - T_M, 7.0, 7.0),
        # furniture: a counter, a sofa, a bed, a table, a wardrobe
        (0.15, 0.15, 2.5, 0.8), (0.2, 4.0, 0.9, 6.0), (0.5, 12.0, 2.0, 13.85),
        (13.0, 5.2, 14.5, 6.2), (6.3, 12.0, 6.85, 13.5),
    ]  # fmt: skip
    doors = [
        (4.6, 2.8, 5.5, 3.05), (8.5, 2.8, 9.4, 3.05), (14.0, 2.8, 14.9, 3.05),  # south rooms
        (7.0, 4.45, 7.9, 4.7), (15.5, 4.45, 16.4, 4.7),  # north rooms
        (2.8, 5.5, 3.05, 6.4), (2.8, 11.0, 3.05, 11.9),  # the living room, the bedroom
        (4.45, 9.5, 4.7, 10.4),  # the long bedroom
        (W_M - 0.2, 3.3, W_M, 4.2),  # the front door
    ]  # fmt: skip
    return boxes_plan(W_M, H_M, walls, doors)


if __name__ == "__main__":
    here = Path(__file__).resolve().parent
    (here / "apartment.pgm").write_bytes(encode_pgm(apartment()))
    (here / "apartment.yaml").write_text(map_yaml("apartment.pgm"), encoding="utf-8")
