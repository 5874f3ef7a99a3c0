"""Frontier-based exploration of an unknown building, coordinated over a team.

A *frontier* (Yamauchi 1997) is a free cell of the team's map next to an unknown one;
neighbouring frontier cells (8-connected) form one frontier, and frontiers smaller than
``min_cells`` (narrower than a robot) are dropped. Each frontier's target is its cell
nearest to its centroid.

Coordination follows Burgard, Moors, Stachniss and Schneider (2005), algorithm 1: every
target starts with utility 1; robots choose one after another the target maximising
``U(t) - beta * V(i, t)`` (``V``: the robot's travel distance to it, in metres, scaled by
``beta``), and each choice lowers the utility of the targets near it by the probability
that the chosen robot's sensors will cover them, ``P(d) = max(0, 1 - d / range)``, so
robots spread over different frontiers instead of all driving to the nearest one. Targets
a robot cannot reach (infinite distance) are never chosen by it.

References
----------
B. Yamauchi, "A frontier-based approach for autonomous exploration", IEEE CIRA 1997.
W. Burgard, M. Moors, C. Stachniss, F. E. Schneider, "Coordinated multi-robot
exploration", IEEE Transactions on Robotics 21(3), 2005, 376-386.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.ndimage as ndi
from numpy.typing import ArrayLike

from firefleet._typing import IntArray
from firefleet.errors import InputError

__all__ = ["Frontiers", "assign_frontiers", "find_frontiers"]

_FOUR = ndi.generate_binary_structure(2, 1)
_EIGHT = ndi.generate_binary_structure(2, 2)


@dataclass(frozen=True)
class Frontiers:
    """The frontiers of a map.

    Attributes
    ----------
    target : ndarray of int, shape (F, 2)
        (row, col) of each frontier's target cell.
    size : ndarray of int, shape (F,)
        Cells in each frontier.
    labels : ndarray of int, shape (H, W)
        Frontier index + 1 per frontier cell, 0 elsewhere.
    """

    target: IntArray
    size: IntArray
    labels: IntArray

    def __len__(self) -> int:
        return int(self.size.shape[0])


def find_frontiers(free: ArrayLike, unknown: ArrayLike, *, min_cells: int = 3) -> Frontiers:
    """The frontiers between a map's known free cells and its unknown cells.

    Parameters
    ----------
    free : array_like of bool, shape (H, W)
        Cells observed free.
    unknown : array_like of bool, shape (H, W)
        Cells never observed.
    min_cells : int, keyword-only
        Smallest frontier kept [cells].

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.planning.exploration import find_frontiers
    >>> free = np.zeros((5, 8), bool); free[:, :3] = True     # explored: the left
    >>> unknown = np.zeros((5, 8), bool); unknown[:, 3:] = True
    >>> f = find_frontiers(free, unknown)
    >>> len(f), f.size.tolist(), f.target.tolist()  # the column next to the unknown
    (1, [5], [[2, 2]])
    """
    fr = np.asarray(free, dtype=bool)
    un = np.asarray(unknown, dtype=bool)
    if fr.shape != un.shape or fr.ndim != 2:
        raise InputError(f"free {fr.shape} and unknown {un.shape} must be the same (H, W)")
    if min_cells < 1:
        raise InputError(f"min_cells must be >= 1, got {min_cells}")
    cells = fr & ndi.binary_dilation(un, structure=_FOUR)
    labels, n = ndi.label(cells, structure=_EIGHT)
    sizes = np.bincount(labels.ravel(), minlength=n + 1)[1:]
    keep = np.flatnonzero(sizes >= min_cells) + 1
    targets = []
    new_labels = np.zeros_like(labels)
    for k, lab in enumerate(keep):
        rc = np.argwhere(labels == lab)
        centroid = rc.mean(axis=0)
        targets.append(rc[np.argmin(((rc - centroid) ** 2).sum(axis=1))])
        new_labels[labels == lab] = k + 1
    target = np.asarray(targets, dtype=np.int64).reshape(-1, 2)
    return Frontiers(target=target, size=sizes[keep - 1].astype(np.int64), labels=new_labels)


def assign_frontiers(
    distance_m: ArrayLike,
    target_xy_m: ArrayLike,
    *,
    sensor_range_m: float,
    beta: float = 1.0,
    taken: ArrayLike | None = None,
    exclusive: bool = False,
) -> IntArray:
    """Each robot's frontier target, coordinated (module notes: Burgard et al. 2005).

    Parameters
    ----------
    distance_m : array_like, shape (R, F)
        Travel distance of each robot to each target [m] (``inf``: unreachable).
    target_xy_m : array_like, shape (F, 2)
        The targets' positions [m] (for the utility reduction).
    sensor_range_m : float, keyword-only
        Range within which a robot at a target covers the targets around it [m].
    beta : float, keyword-only
        Weight of the travel cost against the utility [1/m]; with ``beta`` times the
        largest distance below 1, utility dominates (robots spread out).
    taken : array_like of int, shape (M,), optional, keyword-only
        Targets already held by robots that keep them (a team re-planning only its
        robots that need a new target): their utility reduction is applied first, as if
        they had been chosen before these robots.
    exclusive : bool, keyword-only
        Never give one target to two robots (the held ones included); a robot left
        without a target gets -1. Burgard et al.'s algorithm alone only makes it
        unlikely (the chosen target's utility drops to 0).

    Returns
    -------
    ndarray of int, shape (R,)
        Target index per robot, -1 for a robot that can reach none.

    Examples
    --------
    Two robots side by side, two frontiers: one near both of them, one far. The nearest
    for both is target 0; coordination sends the second robot to the other one.

    >>> from firefleet.planning.exploration import assign_frontiers
    >>> assign_frontiers([[2.0, 9.0], [2.5, 8.0]], [[0.0, 0.0], [9.0, 0.0]],
    ...                  sensor_range_m=4.0, beta=0.05).tolist()
    [0, 1]

    With target 1 already held by a teammate and exclusive targets, only target 0 is left,
    and only one of the two robots gets it.

    >>> assign_frontiers([[2.0, 9.0], [2.5, 8.0]], [[0.0, 0.0], [9.0, 0.0]],
    ...                  sensor_range_m=4.0, beta=0.05, taken=[1], exclusive=True).tolist()
    [0, -1]
    """
    d = np.asarray(distance_m, dtype=float)
    xy = np.asarray(target_xy_m, dtype=float).reshape(-1, 2)
    if d.ndim != 2 or d.shape[1] != xy.shape[0]:
        raise InputError(f"distance_m {d.shape} must be (robots, {xy.shape[0]} targets)")
    if not sensor_range_m > 0.0:
        raise InputError(f"sensor_range_m must be > 0, got {sensor_range_m}")
    n_robots, n_targets = d.shape
    chosen = np.full(n_robots, -1, dtype=np.int64)
    if n_targets == 0:
        return chosen
    utility = np.ones(n_targets)
    gap = np.linalg.norm(xy[:, None, :] - xy[None, :, :], axis=-1)
    coverage = np.clip(1.0 - gap / sensor_range_m, 0.0, 1.0)
    held = np.zeros(n_targets, dtype=bool)
    for t in np.asarray([] if taken is None else taken, dtype=np.int64).reshape(-1):
        if not 0 <= t < n_targets:
            raise InputError(f"taken target {int(t)} is not one of the {n_targets} targets")
        utility = utility - coverage[t]
        held[t] = True
    free_robots = list(range(n_robots))
    while free_robots:
        score = utility[None, :] - beta * d[free_robots]
        score[~np.isfinite(d[free_robots])] = -np.inf
        if exclusive:
            score[:, held] = -np.inf
        flat = int(np.argmax(score))
        i, t = divmod(flat, n_targets)
        if not np.isfinite(score[i, t]):
            break  # the robots left can reach nothing
        robot = free_robots.pop(i)
        chosen[robot] = t
        held[t] = True
        utility = utility - coverage[t]
    return chosen
