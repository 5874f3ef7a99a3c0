"""Which points lie near any of a set of points, by a k-d tree, decided exactly.

The team asks it of thousands of believed flames against each other (``_fight.dry_flames``)
and of a robot's reach against the hot places and flames (``_hot.retreat_point``): as a
full distance matrix that was a third of a late minute of mission-large. The tree
(:class:`scipy.spatial.cKDTree`) finds each point's nearest neighbour; a distance within
a micrometre of the radius is decided by ``np.hypot`` over the candidates, so the answer
is the matrix's exactly.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from firefleet._typing import BoolArray, FloatArray

__all__ = ["any_within"]

_EDGE_M = 1e-6
"""Distances this close to the radius are recomputed as the matrix computes them [m]."""


def any_within(a_xy_m: FloatArray, b_xy_m: FloatArray, r_m: float, inclusive: bool) -> BoolArray:
    """Whether each point of ``a`` (M, 2) has a point of ``b`` (K, 2) within ``r_m`` (M,):
    ``hypot <= r_m`` if ``inclusive``, else ``hypot < r_m`` [m].

    Examples
    --------
    >>> import numpy as np
    >>> a = np.array([[0.0, 0.0], [3.0, 0.0], [10.0, 0.0]])
    >>> b = np.array([[1.5, 0.0]])
    >>> any_within(a, b, 1.5, True).tolist(), any_within(a, b, 1.5, False).tolist()
    ([True, True, False], [False, False, False])
    """
    a = np.asarray(a_xy_m, dtype=float).reshape(-1, 2)
    b = np.asarray(b_xy_m, dtype=float).reshape(-1, 2)
    out = np.zeros(len(a), dtype=bool)
    if len(a) == 0 or len(b) == 0:
        return out
    tree = cKDTree(b)
    d, _ = tree.query(a, k=1)
    out = np.asarray(d, dtype=float) < r_m - _EDGE_M
    edge = np.flatnonzero(np.abs(np.asarray(d, dtype=float) - r_m) <= _EDGE_M)
    if len(edge):
        near = tree.query_ball_point(a[edge], r_m + 2 * _EDGE_M)
        for i, idx in zip(edge.tolist(), near, strict=True):
            h = np.hypot(a[i, 0] - b[idx, 0], a[i, 1] - b[idx, 1])
            out[i] = bool(np.any(h <= r_m if inclusive else h < r_m))
    return out
