"""The team's coarse view of the building: coverage, line of sight, travel distances.

The map's cells (0.05 m) are too many for what the team decides a few times a second,
so the team works on a coarse grid of ``plan_cell_m`` (default 0.25 m; a whole number
``f`` of map cells per side). A coarse cell is

- *opaque* when any of its map cells is occupied (or it lies off the map): line of
  sight (the camera's coverage, the nozzle's reach) stops there;
- *floor* when any of its map cells is free: the building to explore;
- *standable* when any of its map cells is open in the navigation costmap (free and
  farther than robot radius + margin from a wall); its *goal cell* is that open map
  cell nearest to its centre, where the team sends a robot.

Coverage: a robot's thermal camera covers the cells where a person standing would be
named by the detector (:func:`in_view`): from ``near_m`` to ``range_m`` away, inside the
cone narrowed at each range by the person's half width (the whole person in the frame:
:func:`firefleet.perception.thermal.detect` leaves a region cut by the frame's left or
right border "warm"), up to and including the first opaque cell along each ray (rays
every half cell of arc at full range, samples every half cell). Measured with the
mission's renderer and the detector (a person at 37 C in 20 C air, Lepton 80 x 60,
51 deg): named from 1.8 m on, not at 1.6 m or nearer (the person fills too much of
the frame); at 2 m named 10 deg off the axis, not 20 deg off.

Travel distances: Dijkstra on the standable cells' 8-connected graph
(:func:`firefleet.planning.geodesic.grid_graph`, built once), optionally cut off at a
distance limit (``scipy.sparse.csgraph.dijkstra``'s ``limit``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np
import scipy.ndimage as ndi
import scipy.sparse
from numpy.typing import ArrayLike
from scipy.sparse.csgraph import dijkstra

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.navigation import Costmap
from firefleet.planning.geodesic import grid_graph
from firefleet.world import OccupancyGrid

__all__ = [
    "CoarseMap",
    "clear_sight",
    "coarse_map",
    "cone_coverage",
    "in_view",
    "line_of_sight",
    "lines_of_sight",
    "viewpoints",
]


@dataclass(frozen=True, eq=False)
class CoarseMap:
    """The coarse grid the team decides on (module notes).

    Attributes
    ----------
    grid : OccupancyGrid
        The map (the cell <-> metre conversion of the fine cells).
    factor : int
        Map cells per coarse cell side.
    cell_m : float
        Coarse cell side [m].
    opaque, floor, standable : ndarray of bool, shape (Hc, Wc)
        The coarse cells' kinds.
    goal_cell : ndarray of int, shape (Hc, Wc, 2)
        Each standable coarse cell's open map cell (row, col) nearest its centre
        (-1 elsewhere).
    nearest_standable : ndarray of int, shape (Hc, Wc, 2)
        The standable coarse cell nearest to each coarse cell.
    free_count : ndarray of int, shape (Hc, Wc)
        Free map cells in each coarse cell (the explored fraction without the map grid).
    graph : scipy.sparse.csr_matrix, shape (Hc Wc, Hc Wc)
        Travel graph of the standable cells [m].
    cache : dict
        Tables computed once per map and kept (``._views.view_table``'s, by their
        parameters); it changes no result.
    """

    grid: OccupancyGrid
    factor: int
    cell_m: float
    opaque: BoolArray
    floor: BoolArray
    standable: BoolArray
    goal_cell: IntArray
    nearest_standable: IntArray
    graph: scipy.sparse.csr_matrix
    free_count: IntArray
    cache: dict[tuple[object, ...], object] = field(default_factory=dict, repr=False)

    @property
    def shape(self) -> tuple[int, int]:
        """``(Hc, Wc)``."""
        h, w = self.opaque.shape
        return int(h), int(w)

    def cell_of(self, xy_m: FloatArray) -> IntArray:
        """Coarse (row, col) of points (..., 2), clipped onto the grid (the map's cell
        floored by ``factor``; finite points in one compiled pass, the same numbers)."""
        xy = np.asarray(xy_m, dtype=float)
        hc, wc = self.shape
        if not np.isfinite(xy).all():  # NaN's cell is NumPy's cast's business
            rc = self.grid.cell_of(xy) // self.factor
            return np.stack([np.clip(rc[..., 0], 0, hc - 1), np.clip(rc[..., 1], 0, wc - 1)], -1)
        flat = np.ascontiguousarray(xy.reshape(-1, 2))
        out = np.empty((flat.shape[0], 2), dtype=np.int64)
        ox, oy = (float(v) for v in self.grid.origin_m)
        _coarse_cells(
            flat, ox, oy, float(self.grid.resolution_m), int(self.grid.shape[0]),
            int(self.factor), hc, wc, out,
        )  # fmt: skip
        return out.reshape((*xy.shape[:-1], 2))

    def _centre_rc(self, cells: IntArray) -> FloatArray:
        """The map's (fractional) row and column (..., 2) of coarse cells' centres."""
        out: FloatArray = (np.asarray(cells).astype(float) + 0.5) * self.factor - 0.5
        return out

    def centre_xy(self, cells: IntArray) -> FloatArray:
        """Centres [m] (..., 2) of coarse cells (..., 2) (row, col)."""
        out: FloatArray = self.grid.center_of(self._centre_rc(cells))
        return out

    def goal_xy(self, cells: IntArray) -> FloatArray:
        """The goal point [m] (..., 2) of coarse cells (..., 2) (their centre when not
        standable)."""
        g = self.goal_cell[cells[..., 0], cells[..., 1]]
        out: FloatArray = self.grid.center_of(np.where(g[..., :1] >= 0, g, self._centre_rc(cells)))
        return out

    def node_of(self, xy_m: FloatArray) -> IntArray:
        """Graph node (M,) of the standable cell nearest each point (M, 2)."""
        rc = self.cell_of(xy_m)
        near = self.nearest_standable[rc[..., 0], rc[..., 1]]
        out: IntArray = near[..., 0] * self.shape[1] + near[..., 1]
        return out

    def distances(self, nodes: IntArray, limit_m: float = math.inf) -> FloatArray:
        """Travel distance [m] from each node to every cell, (K, Hc Wc) (``inf``: not
        reached within ``limit_m``).

        The graph holds every edge both ways (:func:`~firefleet.planning.geodesic.grid_graph`),
        so it is searched as directed: the same distances as an undirected search, without
        SciPy's symmetrising copy of the graph at every call (on floor100 that copy took
        most of a call cut at 8 m)."""
        if len(nodes) == 0:
            return np.zeros((0, self.shape[0] * self.shape[1]))
        out: FloatArray = np.asarray(
            dijkstra(self.graph, directed=True, indices=nodes, limit=limit_m), dtype=float
        ).reshape(len(nodes), -1)
        return out


def _blocks(a: BoolArray, f: int, fill: bool) -> BoolArray:
    """``a`` (H, W) padded with ``fill`` to multiples of ``f``, as (Hc, Wc, f * f)."""
    h, w = a.shape
    hc, wc = -(-h // f), -(-w // f)
    p = np.full((hc * f, wc * f), fill, dtype=bool)
    p[:h, :w] = a
    return p.reshape(hc, f, wc, f).transpose(0, 2, 1, 3).reshape(hc, wc, f * f)


def coarse_map(costmap: Costmap, cell_m: float) -> CoarseMap:
    """The coarse grid of a navigation costmap (module notes).

    Parameters
    ----------
    costmap : Costmap
        The map inflated for navigation.
    cell_m : float
        Wanted coarse cell side [m] (rounded to a whole number of map cells, >= 1).

    Returns
    -------
    CoarseMap

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> from firefleet.control.navigation import build_costmap
    >>> occ = np.zeros((20, 40), bool); occ[:, 19:21] = True   # a wall down the middle
    >>> cm = coarse_map(build_costmap(OccupancyGrid(occ, ~occ, 0.05), 0.2), 0.25)
    >>> cm.shape, cm.factor, int(cm.opaque.sum()), bool(cm.standable[2, 1])
    ((4, 8), 5, 8, True)
    """
    grid = costmap.grid
    f = max(1, round(cell_m / grid.resolution_m))
    opaque: BoolArray = np.any(_blocks(np.asarray(grid.occupied), f, True), axis=-1)
    free_blocks = _blocks(np.asarray(grid.free), f, False)
    floor: BoolArray = np.any(free_blocks, axis=-1)
    open_ = _blocks(~np.asarray(costmap.blocked), f, False)
    standable: BoolArray = np.any(open_, axis=-1)
    hc, wc = opaque.shape
    # the open map cell nearest each coarse cell's centre
    rr, cc = np.divmod(np.arange(f * f), f)
    d2 = (rr - (f - 1) / 2) ** 2 + (cc - (f - 1) / 2) ** 2
    pick = np.argmin(np.where(open_, d2[None, None, :], np.inf), axis=-1)
    base_r, base_c = np.mgrid[:hc, :wc]
    goal = np.stack([base_r * f + rr[pick], base_c * f + cc[pick]], axis=-1)
    goal[~standable] = -1
    if standable.any():
        _, idx = ndi.distance_transform_edt(~standable, return_indices=True)
        nearest = np.stack([idx[0], idx[1]], axis=-1)
    else:
        nearest = np.stack([base_r, base_c], axis=-1)
    return CoarseMap(
        grid=grid,
        factor=f,
        cell_m=f * grid.resolution_m,
        opaque=opaque,
        floor=floor,
        standable=standable,
        goal_cell=goal.astype(np.int64),
        nearest_standable=nearest.astype(np.int64),
        graph=grid_graph(standable, f * grid.resolution_m),
        free_count=free_blocks.sum(axis=-1).astype(np.int64),
    )


def in_view(
    dist_m: ArrayLike,
    off_rad: ArrayLike,
    range_m: float,
    hfov_rad: float,
    near_m: float,
    half_width_m: float,
) -> BoolArray:
    """Whether a person at distance ``dist_m`` [m], ``off_rad`` [rad] off the camera's
    axis, is named by the detector (module notes), ignoring walls.

    Examples
    --------
    >>> import numpy as np
    >>> in_view(np.array([1.0, 2.0, 2.0, 3.0, 5.0]), np.radians([0, 10, 20, 15, 0]),
    ...         4.0, np.radians(51.0), 2.0, 0.3).tolist()
    [False, True, False, True, False]
    """
    d = np.asarray(dist_m, dtype=float)
    half = 0.5 * hfov_rad - np.arctan2(half_width_m, np.maximum(d, 1e-9))
    out: BoolArray = (d >= near_m) & (d <= range_m) & (np.abs(np.asarray(off_rad)) <= half)
    return out


def cone_coverage(
    cm: CoarseMap,
    pose: FloatArray,
    range_m: float,
    hfov_rad: float,
    near_m: float = 0.0,
    half_width_m: float = 0.0,
) -> tuple[IntArray, IntArray]:
    """The coarse cells the robots' cameras cover (module notes).

    Parameters
    ----------
    cm : CoarseMap
    pose : ndarray, shape (N, 3)
        Poses x [m], y [m], heading [rad].
    range_m, hfov_rad : float
        The cone's length [m] and opening [rad].
    near_m : float
        Nearest covered distance [m] (the detector's nearest range for a person).
    half_width_m : float
        The cone narrows by ``atan((half_width_m + cell_m / 2) / d)`` on each side at
        distance ``d`` (the whole person in the frame, wherever in the cell).

    Returns
    -------
    rows, cols : ndarray of int, shape (M,)
        Covered cells (with repeats).
    """
    step = 0.5 * cm.cell_m
    n_rays = max(2, math.ceil(hfov_rad * range_m / step) + 1)
    rel = np.linspace(-0.5 * hfov_rad, 0.5 * hfov_rad, n_rays)
    ang = pose[:, 2:3] + rel[None]  # (N, R)
    dist = np.arange(1, math.floor(range_m / step) + 1) * step  # (S,)
    if np.isfinite(pose).all():  # the samples below in one compiled pass (_cone_kernel)
        margin = 0.5 * cm.cell_m
        view = in_view(
            dist[None, :], rel[:, None], range_m, hfov_rad, near_m, half_width_m + margin
        )
        size = ang.size * dist.size
        out_r, out_c = np.empty(size, dtype=np.int64), np.empty(size, dtype=np.int64)
        ox, oy = (float(v) for v in cm.grid.origin_m)
        hc, wc = cm.shape
        grid = cm.grid
        k = _cone_kernel(
            np.ascontiguousarray(pose[:, 0]), np.ascontiguousarray(pose[:, 1]), np.cos(ang),
            np.sin(ang), np.asarray(dist, dtype=np.float64), view, ox, oy,
            float(grid.resolution_m), int(grid.shape[0]), int(grid.shape[1]), int(cm.factor),
            hc, wc, cm.opaque, float(cm.cell_m), out_r, out_c,
        )  # fmt: skip
        return out_r[:k], out_c[:k]
    x = pose[:, 0, None, None] + dist * np.cos(ang)[..., None]  # (N, R, S)
    y = pose[:, 1, None, None] + dist * np.sin(ang)[..., None]
    xy = np.stack([x, y], axis=-1)
    on = cm.grid.contains(xy)
    rc = cm.cell_of(xy)
    blocked = ~on | cm.opaque[rc[..., 0], rc[..., 1]]
    blocked[..., dist < cm.cell_m] = False  # a robot beside a wall still looks out
    # visible: no opaque sample before this one (the first opaque one is seen)
    before = np.zeros_like(blocked)
    before[..., 1:] = np.logical_or.accumulate(blocked, axis=-1)[..., :-1]
    # a cell is covered when a sample in it is: half a cell more of margin, so that a
    # person anywhere in it is in view
    margin = 0.5 * cm.cell_m
    view = in_view(dist[None, :], rel[:, None], range_m, hfov_rad, near_m, half_width_m + margin)
    seen = on & ~before & view[None]
    return rc[..., 0][seen], rc[..., 1][seen]


def line_of_sight(cm: CoarseMap, a_m: FloatArray, b_m: FloatArray) -> BoolArray:
    """Whether nothing opaque lies between points ``a`` and ``b`` (M, 2) [m].

    The coarse cells within one cell of either end are not checked (a robot beside a
    wall, a fire in a cell touching one).
    """
    a = np.asarray(a_m, dtype=float).reshape(-1, 2)
    b = np.asarray(b_m, dtype=float).reshape(-1, 2)
    if len(a) == 0:
        return np.zeros(0, dtype=bool)
    seg = np.hypot(*(b - a).T)
    n = max(2, math.ceil(float(seg.max()) / (0.5 * cm.cell_m)) + 1)
    s = np.linspace(0.0, 1.0, n)
    out = np.empty(len(a), dtype=bool)
    _sight(cm, a, b, s, np.zeros(len(a), np.int64), np.full(len(a), n, np.int64), seg, out)
    return out


def lines_of_sight(
    cm: CoarseMap, a_m: FloatArray, b_m: FloatArray, group: IntArray, n_groups: int
) -> BoolArray:
    """:func:`line_of_sight` of each group of the pairs ``a``, ``b`` (M, 2) [m] on its own,
    in one pass: pair ``m`` belongs to group ``group[m]`` (``0 <= group < n_groups``), and
    each group's lines are sampled as one call with only its pairs samples them (the
    samples' count follows the group's longest line), so the answers are those calls'.
    """
    a = np.asarray(a_m, dtype=float).reshape(-1, 2)
    b = np.asarray(b_m, dtype=float).reshape(-1, 2)
    g = np.asarray(group, dtype=np.int64).reshape(-1)
    if len(a) == 0:
        return np.zeros(0, dtype=bool)
    seg = np.hypot(*(b - a).T)
    longest = np.full(n_groups, -math.inf)
    np.maximum.at(longest, g, seg)
    # each group's sample count, as line_of_sight counts it from its longest line
    counts = [
        max(2, math.ceil(float(x) / (0.5 * cm.cell_m)) + 1) if x != -math.inf else 0
        for x in longest.tolist()  # NaN: ceil raises, as in line_of_sight
    ]
    tables: dict[int, int] = {}  # sample count -> its table's start in ``s``
    parts: list[FloatArray] = []
    size = 0
    for n in counts:
        if n and n not in tables:
            tables[n] = size
            parts.append(np.linspace(0.0, 1.0, n))
            size += n
    s = np.concatenate(parts)
    lo = np.array([tables.get(n, 0) for n in counts], dtype=np.int64)[g]
    count = np.array(counts, dtype=np.int64)[g]
    out = np.empty(len(a), dtype=bool)
    _sight(cm, a, b, s, lo, count, seg, out)
    return out


def _sight(
    cm: CoarseMap,
    a: FloatArray,
    b: FloatArray,
    s: FloatArray,
    lo: IntArray,
    count: IntArray,
    seg: FloatArray,
    out: BoolArray,
) -> None:
    """Run :func:`_sight_kernel` on the map's numbers."""
    ox, oy = (float(v) for v in cm.grid.origin_m)
    _sight_kernel(
        np.ascontiguousarray(a), np.ascontiguousarray(b), s, lo, count, seg, ox, oy,
        float(cm.grid.resolution_m), int(cm.grid.shape[0]), int(cm.factor), cm.opaque,
        float(cm.cell_m), out,
    )  # fmt: skip


@numba.njit(cache=True)
def _cone_kernel(
    px: FloatArray,
    py: FloatArray,
    cos_a: FloatArray,
    sin_a: FloatArray,
    dist: FloatArray,
    view: BoolArray,
    ox: float,
    oy: float,
    res: float,
    rows: int,
    cols: int,
    factor: int,
    hc: int,
    wc: int,
    opaque: BoolArray,
    cell_m: float,
    out_r: IntArray,
    out_c: IntArray,
) -> int:  # pragma: no cover - compiled
    """:func:`cone_coverage`'s samples of finite poses in one pass, each the array
    expressions' arithmetic (``x + d cos``, :meth:`OccupancyGrid.contains`,
    :meth:`CoarseMap.cell_of`): the covered cells into ``out_r``, ``out_c`` in the
    array form's order (robot, ray, sample); how many."""
    k = 0
    for n in range(cos_a.shape[0]):
        for r in range(cos_a.shape[1]):
            ca = cos_a[n, r]
            sa = sin_a[n, r]
            before = False  # an opaque sample before this one on the ray
            for s in range(dist.size):
                x = px[n] + dist[s] * ca
                y = py[n] + dist[s] * sa
                col = math.floor((x - ox) / res)
                row = rows - 1 - math.floor((y - oy) / res)
                on = row >= 0 and row < rows and col >= 0 and col < cols
                cr = min(max(row // factor, 0), hc - 1)
                cc = min(max(col // factor, 0), wc - 1)
                if on and not before and view[r, s]:
                    out_r[k] = cr
                    out_c[k] = cc
                    k += 1
                if dist[s] >= cell_m and (not on or opaque[cr, cc]):
                    before = True
    return k


@numba.njit(cache=True)
def _coarse_cells(
    xy: FloatArray,
    ox: float,
    oy: float,
    res: float,
    rows: int,
    factor: int,
    hc: int,
    wc: int,
    out: IntArray,
) -> None:  # pragma: no cover - compiled
    """:meth:`CoarseMap.cell_of` of finite points (M, 2) into ``out`` (M, 2): the map's
    cell (:meth:`OccupancyGrid.cell_of`'s arithmetic) floored by ``factor``, clipped."""
    for m in range(xy.shape[0]):
        col = math.floor((xy[m, 0] - ox) / res) // factor
        row = (rows - 1 - math.floor((xy[m, 1] - oy) / res)) // factor
        out[m, 0] = min(max(row, 0), hc - 1)
        out[m, 1] = min(max(col, 0), wc - 1)


@numba.njit(cache=True)
def _sight_kernel(
    a: FloatArray,
    b: FloatArray,
    s: FloatArray,
    lo: IntArray,
    count: IntArray,
    seg: FloatArray,
    ox: float,
    oy: float,
    res: float,
    rows: int,
    factor: int,
    opaque: BoolArray,
    cell_m: float,
    out: BoolArray,
) -> None:  # pragma: no cover - compiled
    """:func:`line_of_sight`'s samples in one compiled pass, each the array expressions'
    arithmetic (``a + s (b - a)``, :meth:`CoarseMap.cell_of`: the map's cell floored by
    ``factor``, clipped), a line stopping at its first opaque sample off the ends; pair
    ``m``'s samples are ``s[lo[m] : lo[m] + count[m]]``."""
    hc, wc = opaque.shape
    for m in range(a.shape[0]):
        dx = b[m, 0] - a[m, 0]
        dy = b[m, 1] - a[m, 1]
        clear = True
        for jj in range(count[m]):
            j = lo[m] + jj
            along = s[j] * seg[m]
            if along < cell_m or along > seg[m] - cell_m:
                continue  # the cells by either end are not checked
            col = np.int64(math.floor((a[m, 0] + s[j] * dx - ox) / res))
            row = rows - 1 - np.int64(math.floor((a[m, 1] + s[j] * dy - oy) / res))
            r = min(max(row // factor, 0), hc - 1)
            c = min(max(col // factor, 0), wc - 1)
            if opaque[r, c]:
                clear = False
                break
        out[m] = clear


def clear_sight(cm: CoarseMap, a_m: FloatArray, b_m: FloatArray) -> BoolArray:
    """Whether no opaque cell lies between each point ``a`` (M, 2) and the point ``b``
    (2,), or its own point of ``b`` (M, 2) [m], the cells of both ends excepted
    (quarter-cell samples; :func:`line_of_sight` also lets a cell next to either end
    pass, so a viewpoint beside a wall would see through it).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> from firefleet.control.navigation import build_costmap
    >>> occ = np.zeros((40, 80), bool); occ[:, 39:41] = True   # a wall at x = 2 m
    >>> cm = coarse_map(build_costmap(OccupancyGrid(occ, ~occ, 0.05), 0.2), 0.25)
    >>> a = np.array([[1.6, 1.0], [0.5, 1.0]])
    >>> b = np.array([3.0, 1.0])
    >>> clear_sight(cm, a, b).tolist()
    [False, False]
    >>> clear_sight(cm, a, np.array([1.0, 1.5])).tolist()
    [True, True]
    >>> clear_sight(cm, a, np.array([[3.0, 1.0], [1.0, 1.5]])).tolist()  # one b each
    [False, True]
    """
    a = np.asarray(a_m, dtype=float).reshape(-1, 2)
    b = np.broadcast_to(np.asarray(b_m, dtype=float), a.shape)
    if len(a) == 0:
        return np.zeros(0, dtype=bool)
    seg = np.hypot(b[:, 0] - a[:, 0], b[:, 1] - a[:, 1])
    n = max(2, math.ceil(float(seg.max()) / (0.25 * cm.cell_m)) + 1)
    s = np.linspace(0.0, 1.0, n)
    pts = a[:, None] + s[None, :, None] * (b - a)[:, None]
    rc = cm.cell_of(pts)
    own_a = cm.cell_of(a)
    own_b = cm.cell_of(b)
    ends = np.all(rc == own_a[:, None], axis=-1) | np.all(rc == own_b[:, None], axis=-1)
    blocked = cm.opaque[rc[..., 0], rc[..., 1]] & ~ends
    out: BoolArray = ~blocked.any(axis=1)
    return out


def viewpoints(
    cm: CoarseMap,
    covered: BoolArray,
    cells: IntArray,
    look_m: float,
    near_m: float,
    far_m: float,
    toward: IntArray | None = None,
    look_xy_m: FloatArray | None = None,
    avoid: BoolArray | None = None,
    limit_m: float = 8.0,
) -> IntArray:
    """Standable cells (M, 2) from which to look at the uncovered floor by cells (M, 2).

    The place to look at is the uncovered floor cell nearest the mean of those within
    ``look_m`` of the cell (the cell itself when it is uncovered floor; none: the cell is
    returned). The viewpoint is the standable cell from ``near_m`` to ``far_m`` from that
    place (measured from the place's goal point, or ``look_xy_m`` (M, 2) when given, to
    the viewpoints' goal points), in line of sight of it, not in ``avoid`` (Hc, Wc),
    nearest by travel on the map (searched to ``limit_m``; then by straight line) to the
    cell (the side the team comes from) or to the cell ``toward`` (M, 2) when given
    (not a cell behind a wall); the cell itself when there is none. A robot standing
    there and turning covers the place (its camera names no person nearer than ``near_m``).
    """
    out = np.array(cells, dtype=np.int64).reshape(-1, 2)
    hc, wc = cm.shape
    todo = cm.floor & ~covered
    k = max(1, round(look_m / cm.cell_m))
    kv = math.ceil(far_m / cm.cell_m) + 1
    dr, dc = np.mgrid[-kv : kv + 1, -kv : kv + 1]
    ring_d = np.hypot(dr, dc) * cm.cell_m
    ring = (ring_d >= near_m - 1.5 * cm.cell_m) & (ring_d <= far_m + 1.5 * cm.cell_m)
    dr, dc = dr[ring], dc[ring]
    near_to = out.copy() if toward is None else np.asarray(toward, dtype=np.int64).reshape(-1, 2)
    for m, (r, c) in enumerate(out.tolist()):
        if r < 0:
            continue
        if todo[r, c]:
            look = np.array([r, c])
        else:
            r0, r1, c0, c1 = max(r - k, 0), min(r + k + 1, hc), max(c - k, 0), min(c + k + 1, wc)
            rc = np.argwhere(todo[r0:r1, c0:c1]) + np.array([r0, c0])
            if len(rc) == 0:
                continue
            mean = rc.mean(axis=0)
            look = rc[int(np.argmin(np.hypot(*(rc - mean).T)))]
        vr, vc = look[0] + dr, look[1] + dc
        ok = (vr >= 0) & (vr < hc) & (vc >= 0) & (vc < wc)
        vr, vc = vr[ok], vc[ok]
        ok = cm.standable[vr, vc] if avoid is None else cm.standable[vr, vc] & ~avoid[vr, vc]
        vr, vc = vr[ok], vc[ok]
        target = cm.goal_xy(look[None])[0] if look_xy_m is None else look_xy_m[m]
        vxy = cm.goal_xy(np.stack([vr, vc], axis=-1))
        d = np.hypot(vxy[:, 0] - target[0], vxy[:, 1] - target[1])
        ok = (d >= near_m) & (d <= far_m)
        vr, vc, vxy = vr[ok], vc[ok], vxy[ok]
        if len(vr) == 0:
            continue
        # nearest by travel on the map from the cell (or ``toward``), then by the crow
        node = np.asarray([near_to[m, 0] * wc + near_to[m, 1]], dtype=np.int64)
        if not cm.standable[near_to[m, 0], near_to[m, 1]]:
            node = cm.node_of(cm.goal_xy(near_to[m : m + 1]))
        travel = cm.distances(node, limit_m)[0][vr * wc + vc]
        crow = np.hypot(vr - near_to[m, 0], vc - near_to[m, 1])
        order = np.lexsort((crow, travel))
        vr, vc, vxy = vr[order], vc[order], vxy[order]
        sight = clear_sight(cm, vxy, target)
        if sight.any():
            j = int(np.argmax(sight))
            out[m] = (vr[j], vc[j])
    return out
