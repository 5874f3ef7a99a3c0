"""Draw ``house.pgm`` and ``house.yaml``: a 16 m x 12 m bungalow at 0.05 m per cell.

The floor issue 15's acceptance asks for ("a building you did not tune for"): drawn
once, with its fire and people placed (``mission-house.yaml``), before any mission ran
on it. A hall along y (x 6.0-7.5 m) from the front door (south) to a closet; a living
room and a kitchen west of it; two bedrooms, a third with a bathroom east; 0.15 m walls,
0.9 m doors, a sofa, a table and two beds. Run from this folder:
``python draw_house.py`` (then ``git diff`` shows nothing).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from firefleet.world._plans import boxes_plan, encode_pgm, map_yaml

W_M, H_M = 16.0, 12.0
T_M = 0.15


def house() -> np.ndarray:
    """The bungalow's occupied cells (row 0 at the top), shape (240, 320)."""
    walls = [
        (0, 0, W_M, T_M), (0, H_M - T_M, W_M, H_M), (0, 0, T_M, H_M), (W_M - T_M, 0, W_M, H_M),
        (6.0, 0, 6.0 + T_M, 12), (7.4, 0, 7.4 + T_M, 12), (0, 6.0, 6.0, 6.0 + T_M),
        (7.4, 4.0, W_M, 4.0 + T_M), (7.4, 8.0, W_M, 8.0 + T_M), (12.0, 8.0, 12.0 + T_M, 12),
        (6.0, 10.0, 7.4, 10.0 + T_M),
        (1.0, 1.0, 3.0, 1.8), (2.5, 8.5, 4.0, 9.5), (13.5, 0.5, 15.5, 2.5), (13.5, 4.5, 15.5, 6.5),
    ]  # fmt: skip
    doors = [
        (5.99, 2.0, 6.16, 2.9), (5.99, 8.0, 6.16, 8.9), (7.39, 1.0, 7.56, 1.9),
        (7.39, 5.5, 7.56, 6.4), (7.39, 8.8, 7.56, 9.7), (11.99, 9.0, 12.16, 9.9),
        (2.0, 5.99, 2.9, 6.16), (6.2, 9.99, 7.2, 10.16), (6.2, 0.0, 7.2, T_M),
    ]  # fmt: skip
    return boxes_plan(W_M, H_M, walls, doors)


if __name__ == "__main__":
    here = Path(__file__).resolve().parent
    (here / "house.pgm").write_bytes(encode_pgm(house()))
    (here / "house.yaml").write_text(map_yaml("house.pgm"), encoding="utf-8")
