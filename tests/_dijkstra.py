"""The travel distance on a grid by its definition, for tests: Dijkstra with a heap over
the free cells' 8-neighbour graph, a diagonal step only where both cells beside it are
free (no corner cutting), steps of ``cell_m`` and ``sqrt(2) cell_m``."""

from __future__ import annotations

import heapq
import math

import numpy as np


def grid_dijkstra(free: np.ndarray, start: tuple[int, int], cell_m: float) -> np.ndarray:
    """Travel [m] (H, W) from cell ``start`` (row, col) over the True cells of ``free``
    (H, W); inf where it cannot go."""
    h, w = free.shape
    dist = np.full((h, w), np.inf)
    dist[start] = 0.0
    heap = [(0.0, start)]
    while heap:
        d, (r, c) = heapq.heappop(heap)
        if d > dist[r, c]:
            continue
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                rr, cc = r + dr, c + dc
                if (dr, dc) == (0, 0) or not (0 <= rr < h and 0 <= cc < w) or not free[rr, cc]:
                    continue
                if dr and dc and not (free[r + dr, c] and free[r, c + dc]):
                    continue
                nd = d + cell_m * math.hypot(dr, dc)
                if nd < dist[rr, cc]:
                    dist[rr, cc] = nd
                    heapq.heappush(heap, (nd, (rr, cc)))
    return dist
