"""Travel distances through a grid's free cells (8-connected, no corner cutting).

The distance a robot must drive from a cell to every other, around walls: Dijkstra on
the grid graph (``scipy.sparse.csgraph.dijkstra``, compiled), edges of one cell side
between edge neighbours and sqrt(2) sides between diagonal ones, a diagonal step allowed
only when both cells it passes beside are free too (a robot does not squeeze between
two wall corners touching at a point). The exploration and the task allocation of a
team cost their choices with it.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse
from numpy.typing import ArrayLike
from scipy.sparse.csgraph import dijkstra

from firefleet._typing import FloatArray
from firefleet.errors import InputError

__all__ = ["grid_graph", "travel_distance_m"]


def grid_graph(free: ArrayLike, resolution_m: float) -> scipy.sparse.csr_matrix:
    """The free cells as a weighted graph: node ``r * W + c``, edges in metres.

    Parameters
    ----------
    free : array_like of bool, shape (H, W)
        Cells a robot may occupy.
    resolution_m : float
        Cell side [m].

    Returns
    -------
    scipy.sparse.csr_matrix, shape (H W, H W)

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.planning.geodesic import grid_graph
    >>> g = grid_graph(np.ones((2, 2), dtype=bool), 0.5)
    >>> g.nnz, round(float(g[0, 3]), 4)  # 4 edges and 2 diagonals, both ways; one diagonal
    (12, 0.7071)
    """
    f = np.asarray(free, dtype=bool)
    if f.ndim != 2:
        raise InputError(f"free cells must be an (H, W) grid, got shape {f.shape}")
    h, w = f.shape
    idx = np.arange(h * w).reshape(h, w)
    rows, cols, weights = [], [], []
    diagonal = np.sqrt(2.0) * resolution_m
    for dr, dc, length in (
        (0, 1, resolution_m),
        (1, 0, resolution_m),
        (1, 1, diagonal),
        (1, -1, diagonal),
    ):
        c0, c1 = max(0, -dc), w - max(0, dc)  # cells (r, c) whose neighbour (r+dr, c+dc) exists
        ok = f[: h - dr, c0:c1] & f[dr:, c0 + dc : c1 + dc]
        if dr and dc:  # both cells beside the diagonal free: no corner cutting
            ok &= f[: h - dr, c0 + dc : c1 + dc] & f[dr:, c0:c1]
        rows.append(idx[: h - dr, c0:c1][ok])
        cols.append(idx[dr:, c0 + dc : c1 + dc][ok])
        weights.append(np.full(int(ok.sum()), length))
    r = np.concatenate(rows + cols)
    c = np.concatenate(cols + rows)
    wt = np.concatenate(weights + weights)
    return scipy.sparse.csr_matrix((wt, (r, c)), shape=(h * w, h * w))


def travel_distance_m(free: ArrayLike, sources: ArrayLike, resolution_m: float) -> FloatArray:
    """Distance from each source cell to every cell through free cells [m].

    Parameters
    ----------
    free : array_like of bool, shape (H, W)
        Cells a robot may occupy.
    sources : array_like of int, shape (K, 2)
        (row, col) of each source; each must be free.
    resolution_m : float
        Cell side [m].

    Returns
    -------
    ndarray, shape (K, H, W)
        Distances [m]; ``inf`` where a cell cannot be reached (or is not free).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.planning.geodesic import travel_distance_m
    >>> free = np.ones((3, 5), dtype=bool); free[:2, 2] = False  # a wall with a gap below
    >>> d = travel_distance_m(free, [[0, 0]], 1.0)
    >>> round(float(d[0, 0, 4]), 4)  # down and round the wall's end, no corner cut: 4 + 2 sqrt(2)
    6.8284
    """
    f = np.asarray(free, dtype=bool)
    src = np.asarray(sources, dtype=np.int64).reshape(-1, 2)
    h, w = f.shape
    inside = (src[:, 0] >= 0) & (src[:, 0] < h) & (src[:, 1] >= 0) & (src[:, 1] < w)
    if not np.all(inside) or not np.all(f[src[:, 0].clip(0, h - 1), src[:, 1].clip(0, w - 1)]):
        bad = src[~inside | ~f[src[:, 0].clip(0, h - 1), src[:, 1].clip(0, w - 1)]][0]
        raise InputError(f"source cell (row {bad[0]}, col {bad[1]}) is not a free cell of the grid")
    graph = grid_graph(f, resolution_m)
    d = dijkstra(graph, directed=False, indices=src[:, 0] * w + src[:, 1])
    out: FloatArray = np.asarray(d, dtype=float).reshape(-1, h, w)
    return out
