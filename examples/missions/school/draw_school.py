"""Draw ``school.pgm`` and ``school.yaml``: a school wing, 24 m x 14 m at 0.05 m.

A fourth floor for issue 15's acceptance ("a building you did not tune for"), unlike
the office, the house, the apartment, the maze and the warehouse: a T of corridors (a
main corridor 2.4 m wide along x at y 5.8-8.2 m, a side corridor 2 m wide north from it
at x 11-13 m), six classrooms with rows of desks (0.6 m x 1.2 m, 0.9 m apart: clutter
the robots pass between), a staff room with a table and a store room with shelves
along its walls. 0.2 m walls, 1 m doors, an entrance at the west end of the main
corridor. Drawn once, with its fire and people placed (``mission-school.yaml``), before
any mission ran on it. Run from this folder: ``python draw_school.py`` (then ``git
diff`` shows nothing).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from firefleet.world._plans import boxes_plan, encode_pgm, map_yaml

W_M, H_M = 24.0, 14.0
T_M = 0.2


def _desks(x0: float, y0: float, cols: int, rows: int) -> list[tuple[float, float, float, float]]:
    """Rows of desks 1.2 m x 0.6 m, 0.9 m apart both ways, from (x0, y0)."""
    out = []
    for i in range(cols):
        for j in range(rows):
            x, y = x0 + i * 2.1, y0 + j * 1.5
            out.append((x, y, x + 1.2, y + 0.6))
    return out


def school() -> np.ndarray:
    """The wing's occupied cells (row 0 at the top), shape (280, 480)."""
    walls = [
        # the outline
        (0, 0, W_M, T_M), (0, H_M - T_M, W_M, H_M), (0, 0, T_M, H_M), (W_M - T_M, 0, W_M, H_M),
        # the main corridor's walls (y 5.8 and 8.2)
        (0, 5.8 - T_M, W_M, 5.8), (0, 8.2, 11.0, 8.2 + T_M), (13.0, 8.2, W_M, 8.2 + T_M),
        # the side corridor's walls (x 11 and 13), north of the main corridor
        (11.0 - T_M, 8.2, 11.0, H_M), (13.0, 8.2, 13.0 + T_M, H_M),
        # south classrooms: walls at x 8 and 16
        (8.0, 0, 8.0 + T_M, 5.8), (16.0, 0, 16.0 + T_M, 5.8),
        # north-west: a classroom (x 0-11, y 8.4-14) split at x 5.5 (staff room west)
        (5.5, 8.2, 5.5 + T_M, H_M),
        # north-east: a classroom and the store room, split at x 20
        (20.0, 8.2, 20.0 + T_M, H_M),
    ]  # fmt: skip
    furniture = [
        *_desks(1.0, 0.9, 3, 3),  # south-west classroom
        *_desks(9.0, 0.9, 3, 3),  # south-middle classroom
        *_desks(17.0, 0.9, 3, 3),  # south-east classroom
        *_desks(6.4, 9.3, 2, 3),  # north classroom, east of the staff room
        *_desks(14.0, 9.3, 2, 3),  # north-east classroom
        (1.5, 10.2, 4.0, 11.4),  # the staff room's table
        (20.2, 8.4, 20.8, 13.8), (23.2, 8.4, 23.8, 13.8),  # the store's shelves, flush
    ]  # fmt: skip
    doors = [
        (3.0, 5.55, 4.0, 5.85), (12.0, 5.55, 13.0, 5.85), (19.0, 5.55, 20.0, 5.85),  # south
        (3.5, 8.15, 4.5, 8.45), (8.0, 8.15, 9.0, 8.45),  # staff room, north classroom
        (10.75, 11.0, 11.05, 12.0),  # north classroom from the side corridor
        (12.95, 11.0, 13.25, 12.0),  # north-east classroom from the side corridor
        (21.5, 8.15, 22.5, 8.45),  # the store room
        (0, 6.5, 0.25, 7.5),  # the entrance
    ]  # fmt: skip
    return boxes_plan(W_M, H_M, walls + furniture, doors)


if __name__ == "__main__":
    here = Path(__file__).resolve().parent
    (here / "school.pgm").write_bytes(encode_pgm(school()))
    (here / "school.yaml").write_text(map_yaml("school.pgm"), encoding="utf-8")
