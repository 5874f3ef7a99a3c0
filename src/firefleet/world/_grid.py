"""The occupancy grid: the one place where cells and metres meet.

A grid follows ROS ``map_server``'s convention: a raster image whose row 0 is the map's
*top* edge, and an ``origin`` that is the world position of the *lower-left* corner of
the lower-left cell. Cell ``(row, col)`` therefore covers
``x in [ox + col r, ox + (col + 1) r)`` and ``y in [oy + (H - 1 - row) r, oy + (H - row) r)``
for resolution ``r`` and ``H`` rows. Every conversion between the two frames is written
here once (DESIGN.md: "grids (H, W) with row 0 at the map's top, converted in one place").

References
----------
ROS ``map_server`` map format: http://wiki.ros.org/map_server#Map_format
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.errors import InputError

__all__ = ["OccupancyGrid"]


@dataclass(frozen=True, eq=False)
class OccupancyGrid:
    """A static occupancy grid: occupied, free and unknown cells.

    Attributes
    ----------
    occupied : ndarray of bool, shape (H, W)
        Cells holding an obstacle (walls, shelves); row 0 is the map's top edge.
    free : ndarray of bool, shape (H, W)
        Cells known to be free. A cell neither occupied nor free is unknown; robots treat
        it as untraversable, range sensors see through it.
    resolution_m : float
        Cell side [m].
    origin_m : tuple of float
        World position (x, y) of the lower-left corner of the lower-left cell [m]
        (map_server's ``origin``; its yaw must be 0).
    name : str
        What the map is called (a built-in name, or its file), for messages.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> occupied = np.zeros((4, 6), dtype=bool)
    >>> occupied[0, :] = True  # the top row is a wall
    >>> grid = OccupancyGrid(occupied, ~occupied, resolution_m=0.5, origin_m=(-1.0, 0.0))
    >>> grid.shape, grid.width_m, grid.height_m
    ((4, 6), 3.0, 2.0)
    >>> grid.cell_of([[-0.9, 0.1], [1.9, 1.9]]).tolist()  # (row, col): bottom-left, top-right
    [[3, 0], [0, 5]]
    >>> grid.center_of([[3, 0]]).tolist()
    [[-0.75, 0.25]]
    >>> grid.occupied_at([[1.9, 1.9], [0.0, 1.0]]).tolist()
    [True, False]
    """

    occupied: BoolArray
    free: BoolArray
    resolution_m: float
    origin_m: tuple[float, float] = (0.0, 0.0)
    name: str = "grid"

    def __post_init__(self) -> None:
        occupied = np.asarray(self.occupied)
        free = np.asarray(self.free)
        if occupied.ndim != 2 or occupied.shape != free.shape or occupied.size == 0:
            raise InputError(
                f"map {self.name!r}: occupied {occupied.shape} and free {free.shape} must be "
                "the same non-empty (H, W) shape"
            )
        if occupied.dtype != np.bool_ or free.dtype != np.bool_:
            raise InputError(f"map {self.name!r}: occupied and free must be boolean arrays")
        if np.any(occupied & free):
            raise InputError(f"map {self.name!r}: a cell cannot be both occupied and free")
        if not (np.isfinite(self.resolution_m) and self.resolution_m > 0.0):
            raise InputError(
                f"map {self.name!r}: resolution {self.resolution_m!r} must be a positive "
                "number of metres per cell"
            )
        if len(self.origin_m) != 2 or not np.all(np.isfinite(self.origin_m)):
            raise InputError(f"map {self.name!r}: origin {self.origin_m!r} must be finite (x, y)")
        occupied.setflags(write=False)
        free.setflags(write=False)
        object.__setattr__(self, "occupied", occupied)
        object.__setattr__(self, "free", free)
        object.__setattr__(self, "origin_m", (float(self.origin_m[0]), float(self.origin_m[1])))
        object.__setattr__(self, "resolution_m", float(self.resolution_m))

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)``: rows and columns."""
        h, w = self.occupied.shape
        return int(h), int(w)

    @property
    def width_m(self) -> float:
        """Extent along x [m]."""
        return self.shape[1] * self.resolution_m

    @property
    def height_m(self) -> float:
        """Extent along y [m]."""
        return self.shape[0] * self.resolution_m

    @property
    def extent_m(self) -> tuple[float, float, float, float]:
        """``(x_min, x_max, y_min, y_max)`` [m], as matplotlib's ``imshow(extent=)`` takes it."""
        ox, oy = self.origin_m
        return ox, ox + self.width_m, oy, oy + self.height_m

    def cell_of(self, xy_m: ArrayLike) -> IntArray:
        """The (row, col) of the cell holding each point, shape (..., 2); may lie off the
        grid (see :meth:`contains`)."""
        xy = np.asarray(xy_m, dtype=float)
        col = np.floor((xy[..., 0] - self.origin_m[0]) / self.resolution_m).astype(np.int64)
        row_from_bottom = np.floor((xy[..., 1] - self.origin_m[1]) / self.resolution_m)
        row = self.shape[0] - 1 - row_from_bottom.astype(np.int64)
        return np.stack([row, col], axis=-1)

    def center_of(self, cells: ArrayLike) -> FloatArray:
        """The world position (x, y) [m] of each cell's centre, shape (..., 2)."""
        rc = np.asarray(cells, dtype=float)
        x = self.origin_m[0] + (rc[..., 1] + 0.5) * self.resolution_m
        y = self.origin_m[1] + (self.shape[0] - 1 - rc[..., 0] + 0.5) * self.resolution_m
        return np.stack([x, y], axis=-1)

    def contains(self, xy_m: ArrayLike) -> BoolArray:
        """Whether each point (..., 2) lies on the grid."""
        rc = self.cell_of(xy_m)
        h, w = self.shape
        return (rc[..., 0] >= 0) & (rc[..., 0] < h) & (rc[..., 1] >= 0) & (rc[..., 1] < w)

    def occupied_at(self, xy_m: ArrayLike) -> BoolArray:
        """Whether each point (..., 2) lies in an occupied cell (off the grid counts as
        occupied: the world ends at its edge)."""
        rc = self.cell_of(xy_m)
        inside = self.contains(xy_m)
        h, w = self.shape
        r = np.clip(rc[..., 0], 0, h - 1)
        c = np.clip(rc[..., 1], 0, w - 1)
        return ~inside | self.occupied[r, c]


def coarsen(grid: OccupancyGrid, factor: int, *, keep: str = "bottom") -> OccupancyGrid:
    """The grid with ``factor x factor`` blocks of cells merged into one.

    A block is occupied when any of its cells is (a thin wall stays a wall), free when
    all of its cells are free, unknown otherwise. The grid is cropped to whole blocks
    from its lower-left corner (the origin stays put), or from its upper-left corner
    (``keep="top"``: the rows a block grid counted from the array's first row keeps, as
    the mission team's plan grid does; the origin moves up by the rows cropped below).

    Parameters
    ----------
    grid : OccupancyGrid
    factor : int
        Cells per side of a block, >= 1.
    keep : {"bottom", "top"}, keyword-only
        Which rows stay when the rows are not a whole number of blocks.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid, coarsen
    >>> occupied = np.zeros((4, 6), dtype=bool); occupied[0, 5] = True
    >>> small = coarsen(OccupancyGrid(occupied, ~occupied, resolution_m=0.05), 2)
    >>> small.shape, small.resolution_m, small.occupied.astype(int).tolist()
    ((2, 3), 0.1, [[0, 0, 1], [0, 0, 0]])
    >>> odd = np.zeros((5, 4), dtype=bool); odd[0, 0] = True  # 5 rows: one left over
    >>> top = coarsen(OccupancyGrid(odd, ~odd, resolution_m=0.05), 2, keep="top")
    >>> top.occupied.astype(int).tolist(), top.origin_m  # the top row kept, the origin up
    ([[1, 0], [0, 0]], (0.0, 0.05))
    >>> coarsen(OccupancyGrid(odd, ~odd, resolution_m=0.05), 2).occupied.any()  # bottom: lost
    np.False_
    """
    if int(factor) != factor or factor < 1:
        raise InputError(f"coarsen: factor must be a whole number >= 1, got {factor!r}")
    if keep not in ("bottom", "top"):
        raise InputError(f"coarsen: keep must be 'bottom' or 'top', got {keep!r}")
    f = int(factor)
    h, w = grid.shape
    hc, wc = h // f, w // f
    if hc == 0 or wc == 0:
        raise InputError(
            f"coarsen: map {grid.name!r} {grid.shape} is smaller than one block of {f}"
        )
    origin = grid.origin_m
    if keep == "top":
        rows = slice(0, hc * f)
        below = (h - hc * f) * grid.resolution_m
        origin = (grid.origin_m[0], grid.origin_m[1] + below) if below else grid.origin_m
    else:
        rows = slice(h - hc * f, h)  # the bottom rows: the origin is the lower-left corner
    occ: BoolArray = np.asarray(
        grid.occupied[rows, : wc * f].reshape(hc, f, wc, f).any(axis=(1, 3))
    )
    free: BoolArray = np.asarray(grid.free[rows, : wc * f].reshape(hc, f, wc, f).all(axis=(1, 3)))
    return OccupancyGrid(
        occ, free & ~occ, resolution_m=grid.resolution_m * f, origin_m=origin, name=grid.name
    )
