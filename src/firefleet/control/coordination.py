"""Closed-loop x-coordination of a path-following team (deliverable 2.6.2.6).

The deliverable asks the robots to keep their segment counters equal
(``zeta_i = zeta_j``) and a robot ahead to "wait for other robots to catch up"; its
trajectory planner (2.6.3) does it open loop, releasing the same point index to every
robot on a common clock. Here the coordination is closed through the robots' progress
as they hear it, the discrete and saturated form of the coordination law of
Ghabcheloo et al. [1]_, where each vehicle's path parameter ``gamma_i`` is sped up or
slowed down by its differences to the parameters its neighbours broadcast, and which
stays stable under lost messages and delays.

Each robot ``i`` broadcasts its progress ``zeta_i`` [segments] (its desired point's
index less the along-path distance still to go to it, in segments:
``zeta_i = j_i - x_err_i / spacing_i``, i.e. its segment index and the fraction along
it) and the rate ``v_i / spacing_i`` [segments/s] at which it moves. Robot ``i``'s
desired point is then released by the law::

    zhat_ij  = zeta_j + rate_j * age_ij                 prediction from the last value heard
    zmin_i   = min over fresh j (age_ij <= timeout) of zhat_ij
    c_i(k)   = floor((k - h_i) dt / period) + 1         robot i's release clock
    if c_i(k) > j_i(k - 1) and c_i(k) > floor(zmin_i) + lead:
        h_i += 1, j_i(k) = j_i(k - 1)                   hold: the point waits
    else:
        j_i(k) = c_i(k)

so no robot's next point is released more than ``lead`` segments ahead of the
slowest progress it has heard: each robot's release clock (the deliverable's common
schedule, ``h_i = 0``) stops while it would run too far ahead and goes on at the
nominal pace afterwards, the whole schedule shifted by the time held. With every robot
on time the law never holds (``lead`` above the robots' usual lag behind their points)
and the release is the clock's, bit for bit. A robot not heard for longer than the
timeout is flagged stale and left out (the team goes on without it, as it does when
the middleware reports a robot gone).

References
----------
.. [1] R. Ghabcheloo, A. P. Aguiar, A. Pascoal, C. Silvestre, I. Kaminer and
   J. Hespanha, "Coordinated path-following in the presence of communication losses
   and time delays", SIAM J. Control Optim. 48(1), 234-265, 2009.
"""

from __future__ import annotations

import numpy as np

from firefleet._typing import FloatArray, IntArray

__all__ = ["coordinated_release", "heard_minimum"]


def heard_minimum(
    zeta: FloatArray,
    rate: FloatArray,
    age_s: FloatArray,
    timeout_s: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The slowest progress each robot has heard, predicted to now.

    Parameters
    ----------
    zeta : ndarray, shape (N, M)
        Row ``i``: the last progress robot ``i`` holds from each of M senders [segments]
        (NaN: never heard).
    rate : ndarray, shape (N, M)
        The rates that came with them [segments/s].
    age_s : ndarray, shape (N, M)
        Their ages [s] (inf: never heard).
    timeout_s : float
        Older values are stale and left out [s].

    Returns
    -------
    zmin : ndarray, shape (N,)
        ``min_j zeta_ij + rate_ij age_ij`` over the fresh values (NaN if none).
    age_max_s : ndarray, shape (N,)
        The oldest fresh value's age [s] (NaN if none).
    stale : ndarray, shape (N,)
        How many senders are stale (never heard or older than the timeout).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.coordination import heard_minimum
    >>> zeta = np.array([[10.0, 8.0, 3.0]])
    >>> rate = np.array([[1.0, 2.0, 1.0]])
    >>> age = np.array([[0.01, 0.5, 2.0]])  # robot 3 was last heard 2 s ago
    >>> zmin, age_max, stale = heard_minimum(zeta, rate, age, timeout_s=1.0)
    >>> zmin.tolist(), age_max.tolist(), stale.tolist()
    ([9.0], [0.5], [1.0])
    """
    fresh = age_s <= timeout_s
    zhat = np.where(fresh, zeta + rate * np.where(fresh, age_s, 0.0), np.inf)
    zmin = zhat.min(axis=1)
    any_fresh = fresh.any(axis=1)
    zmin = np.where(any_fresh, zmin, np.nan)
    age_max = np.where(any_fresh, np.where(fresh, age_s, -np.inf).max(axis=1), np.nan)
    stale = (~fresh).sum(axis=1).astype(np.float64)
    return zmin, age_max, stale


def coordinated_release(
    released: IntArray,
    held: IntArray,
    step: int,
    dt_s: float,
    period_s: float,
    zmin: FloatArray,
    lead: int,
) -> tuple[IntArray, IntArray]:
    """Each robot's desired point index under the law (module notes), one tick on.

    Parameters
    ----------
    released : ndarray of int, shape (N,)
        The indices released at the last tick (0 at the start).
    held : ndarray of int, shape (N,)
        How many ticks each robot's release clock has been held so far.
    step : int
        The tick k (wall clock ``k dt_s``).
    dt_s, period_s : float
        The tick and the time between two releases [s].
    zmin : ndarray, shape (N,)
        The slowest progress each robot has heard [segments]; NaN: nothing heard (the
        clock alone).
    lead : int
        How far a point may run ahead of it [segments].

    Returns
    -------
    released, held : ndarray of int, shape (N,)

    Examples
    --------
    Point 41 falls due at tick 400 (4 s, a point every 0.1 s); robot 2 has heard a
    progress 12 segments behind it and holds it, robot 3 has heard nothing and releases
    it:

    >>> import numpy as np
    >>> from firefleet.control.coordination import coordinated_release
    >>> released, held = np.array([40, 40, 40]), np.array([0, 0, 0])
    >>> zmin = np.array([38.5, 29.0, np.nan])
    >>> j, held = coordinated_release(released, held, 400, 0.01, 0.1, zmin, 10)
    >>> j.tolist(), held.tolist()
    ([41, 40, 41], [0, 1, 0])
    """
    clock = np.floor((step - held) * dt_s / period_s + 1e-9).astype(np.int64) + 1
    with np.errstate(invalid="ignore"):
        hold = (clock > released) & (clock > np.floor(zmin) + lead)
    j = np.where(hold, released, clock)
    return j.astype(np.int64), (held + hold).astype(np.int64)
