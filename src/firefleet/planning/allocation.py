"""Task allocation: which robot goes to which fire or victim.

An optimal assignment (Kuhn 1955, Munkres 1957; ``scipy.optimize.linear_sum_assignment``,
the Jonker-Volgenant algorithm) of robots to tasks minimising the summed cost, where a
task may need several robots (a fire to surround: ``demand`` copies of its column) and a
robot serves at most one task. The cost is the caller's (the mission: travel distance
on the map, plus a penalty for a robot whose tank is low); an infinite cost marks a
robot that cannot do a task (unreachable, or out of agent), and is never assigned. With
more robots than task slots, the cheapest robots are used and the rest stay free; with
fewer, the slots that cost least in total are served. The mission re-solves it whenever
a detection or a robot's state changes.

References
----------
H. W. Kuhn, "The Hungarian method for the assignment problem", Naval Research Logistics
Quarterly 2, 1955. R. Jonker, A. Volgenant, "A shortest augmenting path algorithm for
dense and sparse linear assignment problems", Computing 38, 1987.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import linear_sum_assignment

from firefleet._typing import IntArray
from firefleet.errors import InputError

__all__ = ["allocate_tasks"]


def allocate_tasks(cost: ArrayLike, *, demand: ArrayLike | None = None) -> IntArray:
    """The cheapest assignment of robots to tasks.

    Parameters
    ----------
    cost : array_like, shape (R, T)
        Cost of robot ``i`` doing task ``j`` (finite >= 0, or ``inf``: cannot).
    demand : array_like of int, shape (T,), optional, keyword-only
        Robots each task needs (default 1 each).

    Returns
    -------
    ndarray of int, shape (R,)
        Task index per robot, -1 for a robot left free.

    Examples
    --------
    Three robots, two fires; fire 1 needs two robots. Robot 2 is the cheapest for fire 0,
    yet the cheapest whole plan (1 + 2 + 2 = 5) sends it to fire 1 with robot 0:

    >>> from firefleet.planning.allocation import allocate_tasks
    >>> allocate_tasks([[5.0, 1.0], [2.0, 9.0], [1.0, 2.0]], demand=[1, 2]).tolist()
    [1, 0, 1]
    """
    c = np.asarray(cost, dtype=float)
    if c.ndim != 2:
        raise InputError(f"cost must be (robots, tasks), got shape {c.shape}")
    if np.any(np.isnan(c)) or np.any(c < 0.0):
        raise InputError("cost must hold numbers >= 0 or inf (NaN or negative found)")
    n_robots, n_tasks = c.shape
    need = np.ones(n_tasks, dtype=np.int64) if demand is None else np.asarray(demand, np.int64)
    if need.shape != (n_tasks,) or np.any(need < 0):
        raise InputError(f"demand must be {n_tasks} counts >= 0, got {need.tolist()}")
    out = np.full(n_robots, -1, dtype=np.int64)
    slots = np.repeat(np.arange(n_tasks), need)
    if n_robots == 0 or slots.size == 0:
        return out
    expanded = c[:, slots]
    finite = np.isfinite(expanded)
    if not finite.any():
        return out
    # an impossible pair costs more than any whole feasible assignment, so that the
    # solver takes it only where nothing else fills the slot; such pairs are dropped
    big = (expanded[finite].max() + 1.0) * (min(n_robots, slots.size) + 1)
    rows, cols = linear_sum_assignment(np.where(finite, expanded, big))
    ok = finite[rows, cols]
    out[rows[ok]] = slots[cols[ok]]
    return out
