"""The formation's neighbours over the team's link (issue 16, :mod:`firefleet.sim.link`).

With an impaired ``link:`` a formation robot no longer reads its neighbours' true
positions: each tick every robot broadcasts its formation point and that point's
velocity, the world loop's link stage (:class:`firefleet.sim.link.LinkModel`, the very
object :func:`firefleet.sim.loop.default_stages` builds, per directed pair and seeded)
carries them, and each receiver holds the last value from each neighbour with the tick
it was sent. The receiver predicts the neighbour to now from its last known velocity::

    p_hat_ij = p_j(t_sent) + v_j(t_sent) age_ij       age_ij = (k - sent_tick_ij) dt

and leaves out a neighbour whose value is older than the link's ``timeout_s`` (or was
never heard): it carries no charge, has no place in the spacing and no body in the
contact force of that receiver's law. Ignored, not down-weighted: the prediction's
error grows with the age (a constant-velocity extrapolation of a robot that is itself
turning about the leader), so a stale neighbour is a phantom whose Coulomb or spacing
push is wrong in direction as well as size, while the rest of the law (the attraction
to the circle, the fresh neighbours) holds the robot on the circle by itself; the
coordination law of path following drops stale robots for the same reason
(:mod:`firefleet.control.coordination`).

Each robot's own point is its own (true) one. A failed robot's radio goes on
broadcasting its stopped point; which robots are in the team is known to all, as without
the link (the kind's failure model). The force on robot ``i`` is the law
evaluated on robot ``i``'s view of the team (:func:`view_forces`): N evaluations of
:func:`firefleet.control.formation.formation_force_and_stiffness` a tick, one per
receiver, each on that receiver's fresh neighbours.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from firefleet._typing import BoolArray, FloatArray
from firefleet.sim.link import ages

__all__ = ["KEYS", "Views", "outbox", "predicted_views", "view_forces"]

KEYS = ("x_m", "y_m", "vx_m_s", "vy_m_s")
"""What each robot broadcasts: its formation point [m] and its velocity [m/s]."""

Views = tuple[FloatArray, BoolArray, FloatArray]
"""(positions (N, N, 2) as each receiver predicts them, fresh (N, N), ages (N, N) [s])."""

LawAt = Callable[[FloatArray, BoolArray, int], tuple[FloatArray, float]]
"""``force_i, stiffness = law_at(positions (M, 2), active (M,), row of i)``."""


def outbox(point: FloatArray, velocity: FloatArray) -> dict[str, FloatArray]:
    """The broadcast of the team: each robot's point (N, 2) [m] and velocity (N, 2) [m/s].

    Examples
    --------
    >>> import numpy as np
    >>> sorted(outbox(np.zeros((2, 2)), np.ones((2, 2))))
    ['vx_m_s', 'vy_m_s', 'x_m', 'y_m']
    """
    return {
        "x_m": point[:, 0].copy(),
        "y_m": point[:, 1].copy(),
        "vx_m_s": velocity[:, 0].copy(),
        "vy_m_s": velocity[:, 1].copy(),
    }


def predicted_views(
    inbox: Mapping[str, FloatArray],
    own: FloatArray,
    step: int,
    dt_s: float,
    timeout_s: float,
    ahead_s: float = 0.0,
) -> Views:
    """Each receiver's view of the team, predicted to ``step dt + ahead_s``.

    Parameters
    ----------
    inbox : mapping
        The link stage's inbox: (N, N) arrays for :data:`KEYS` (row ``i``: what robot
        ``i`` holds) and ``sent_tick`` (N, N) (-1: nothing heard).
    own : ndarray, shape (N, 2)
        Each robot's own point [m] (the diagonal of the view).
    step : int
        The tick.
    dt_s : float
        The tick [s].
    timeout_s : float
        Values older than this are stale [s].
    ahead_s : float
        Extra prediction time (a sub-step within the tick) [s].

    Returns
    -------
    positions : ndarray, shape (N, N, 2)
        ``p_j + v_j age_ij`` (module notes); NaN where nothing was heard.
    fresh : ndarray of bool, shape (N, N)
        Heard within the timeout (the diagonal always).
    age_s : ndarray, shape (N, N)
        Age of each held value [s] (0 on the diagonal, inf where nothing was heard).

    Examples
    --------
    >>> import numpy as np
    >>> nan = np.nan
    >>> inbox = {"x_m": np.array([[nan, 1.0], [0.0, nan]]), "y_m": np.zeros((2, 2)),
    ...          "vx_m_s": np.array([[nan, 2.0], [0.0, nan]]), "vy_m_s": np.zeros((2, 2)),
    ...          "sent_tick": np.array([[-1.0, 7.0], [-1.0, -1.0]])}
    >>> pos, fresh, age = predicted_views(inbox, np.zeros((2, 2)), 10, 0.01, 1.0)
    >>> pos[0, 1].round(3).tolist(), fresh.tolist(), age[0, 1].round(3)
    ([1.06, 0.0], [[True, True], [False, True]], np.float64(0.03))
    """
    sent = np.asarray(inbox["sent_tick"], dtype=np.float64)
    age = ages(sent, step, dt_s)
    np.fill_diagonal(age, 0.0)
    fresh = age <= timeout_s
    lead = np.where(fresh, age + ahead_s, 0.0)
    nothing = np.full(sent.shape, np.nan)  # before the first broadcast
    x, y, vx, vy = (np.asarray(inbox.get(key, nothing), dtype=np.float64) for key in KEYS)
    pos = np.stack([x + vx * lead, y + vy * lead], axis=2)
    diag = np.arange(own.shape[0])
    pos[diag, diag] = own
    return pos, fresh, age


def view_forces(views: Views, active: BoolArray, law_at: LawAt) -> tuple[FloatArray, float]:
    """The force on each robot from its own view of the team, and the largest stiffness.

    Parameters
    ----------
    views : Views
        From :func:`predicted_views`.
    active : ndarray of bool, shape (N,)
        Robots in the team (an inactive robot gets no force; its body is still seen).
    law_at : callable
        The formation law on a subset of the team (see :data:`LawAt`).

    Returns
    -------
    force : ndarray, shape (N, 2)
        [N].
    stiffness_n_m : float
        The largest of the receivers' stiffness bounds [N/m].

    Examples
    --------
    >>> import numpy as np
    >>> views = (np.zeros((2, 2, 2)), np.array([[True, False], [True, True]]), np.zeros((2, 2)))
    >>> def count(pos, act, row):  # the force on the row: how many robots it sees
    ...     return np.full((pos.shape[0], 2), float(pos.shape[0])), 1.0
    >>> view_forces(views, np.array([True, True]), count)[0].tolist()
    [[1.0, 1.0], [2.0, 2.0]]
    """
    pos, fresh, _ = views
    n = pos.shape[0]
    force = np.zeros((n, 2))
    stiffness = 0.0
    for i in np.nonzero(active)[0]:
        keep = np.nonzero(fresh[i])[0]
        row = int(np.searchsorted(keep, i))
        f, s = law_at(pos[i, keep], active[keep], row)
        force[i] = f[row]
        stiffness = max(stiffness, s)
    return force, stiffness
