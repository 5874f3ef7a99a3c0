"""The formation forces one by one: attraction to the circle (eq. 6), Coulomb
repulsion (eqs. 7-8), contact and obstacle repulsion, ring spacing (the regular law).

See :mod:`firefleet.control.formation` for the laws and their references.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from firefleet._typing import BoolArray, FloatArray
from firefleet.errors import InputError, as_float_array, check_fields

BLOCK_ELEMS = 1 << 15
"""Default number of robot pairs per block of the pairwise sums (32,768: a block's
arrays, 256 kB each, stay in a core's L2 cache; measured fastest in bench/formation.py)."""

_MIN_GAP_M = 1e-3
"""Body gaps below this count as this in the FIRAS force (its pole at 0 is capped)."""


@dataclass(frozen=True)
class FormationParams:
    """Parameters of the formation laws (defaults: the deliverable's section 2.3.2).

    Attributes
    ----------
    alpha_m : float
        Radius alpha of the formation circle about the leader [m], > 0.
    k_r : float
        Coulomb constant k_r of eqs. 7-8 [N m^2 / C^2], >= 0 (10 in section 2.3.2).
    charge_c : float
        Charge q of every robot [C], >= 0 (1 in section 2.3.2).
    attraction_gain : float
        Gain a of eq. 6 [N / m^3], > 0 (eq. 6 as printed: 1).
    attraction_limit_n : float
        Largest magnitude of the attraction [N] (an actuator's limit, 10 N: 5 m/s at
        the deliverable's damping; ``inf``: eq. 6 as printed, which grows with the cube
        of the distance: 280 N at 7 m from a 3 m circle, enough to throw robots into
        each other at 140 m/s, a stiffness no 10 ms step follows).
    spacing_stiffness_n_m : float
        K_s, stiffness of the ``"regular"`` law's angular-neighbour spacing [N/m], >= 0
        (its fastest mode has the stiffness 2 K_s, whatever the team's size).
    robot_radius_m : float
        Radius of a robot's body [m], >= 0 (for contact and obstacle forces).
    contact_gain : float
        Gain of the FIRAS contact and obstacle forces [N m^2], >= 0.
    contact_range_m : float
        Body gap below which the FIRAS force acts [m], > 0.

    Examples
    --------
    >>> from firefleet.control.formation import FormationParams
    >>> p = FormationParams(alpha_m=2.0)
    >>> p.alpha_m, p.k_r, p.charge_c
    (2.0, 10.0, 1.0)
    """

    alpha_m: float = 3.0
    k_r: float = 10.0
    charge_c: float = 1.0
    attraction_gain: float = 1.0
    attraction_limit_n: float = 10.0
    spacing_stiffness_n_m: float = 20.0
    robot_radius_m: float = 0.15
    contact_gain: float = 0.05
    contact_range_m: float = 0.5

    def __post_init__(self) -> None:
        check_fields(
            self,
            "",
            positive=("alpha_m", "attraction_gain", "contact_range_m"),
            non_negative=(
                "k_r",
                "charge_c",
                "spacing_stiffness_n_m",
                "robot_radius_m",
                "contact_gain",
            ),
        )
        if not self.attraction_limit_n > 0:  # inf allowed, NaN not
            raise InputError(f"attraction_limit_n must be > 0, got {self.attraction_limit_n}")


def _positions(pos: ArrayLike, name: str = "pos") -> FloatArray:
    return as_float_array(pos, name, (None, 2))


def _block_rows(n: int, block_elems: int) -> int:
    if block_elems < 1:
        raise InputError(f"block_elems must be >= 1, got {block_elems}")
    return max(1, min(n, block_elems // max(n, 1)))


def circle_attraction(
    pos: ArrayLike,
    leader_xy: ArrayLike,
    *,
    alpha_m: float,
    gain: float = 1.0,
    limit_n: float = math.inf,
) -> FloatArray:
    """Attraction of every robot to the circle of radius alpha about the leader (eq. 6).

    Parameters
    ----------
    pos : array_like, shape (N, 2)
        Robot positions [m].
    leader_xy : array_like, shape (2,)
        The virtual leader's position (x_c, y_c) [m].
    alpha_m : float
        Circle radius alpha [m].
    gain : float
        a [N/m^3]; eq. 6 as printed is a = 1.
    limit_n : float
        Magnitude cap [N] (``inf``: none).

    Returns
    -------
    ndarray, shape (N, 2)
        ``-a (p - c) (|p - c|^2 - alpha^2)`` [N], scaled down to ``limit_n`` where larger.

    Examples
    --------
    >>> from firefleet.control.formation import circle_attraction
    >>> # -a (p - c)(|p - c|^2 - alpha^2): -1 * 2 * (4 - 1) = -6 N at 2 m from a 1 m circle
    >>> (circle_attraction([[2.0, 0.0], [0.0, 1.0]], [0.0, 0.0], alpha_m=1.0) + 0.0).tolist()
    [[-6.0, 0.0], [0.0, 0.0]]
    >>> (circle_attraction([[2.0, 0.0]], [0.0, 0.0], alpha_m=1.0, limit_n=4.0) + 0.0).tolist()
    [[-4.0, 0.0]]
    """
    p = _positions(pos)
    c = as_float_array(leader_xy, "leader_xy", (2,))
    d = p - c
    f: FloatArray = -gain * d * ((d * d).sum(axis=1) - alpha_m * alpha_m)[:, None]
    if math.isfinite(limit_n):
        mag = np.sqrt((f * f).sum(axis=1))
        f *= np.minimum(1.0, limit_n / np.maximum(mag, 1e-300))[:, None]
    return f


def _charges(charge: ArrayLike, n: int) -> FloatArray:
    q = np.asarray(charge, dtype=np.float64)
    if q.ndim == 0:
        q = np.full(n, float(q))
    return as_float_array(q, "charge", (n,))


def _coulomb_sums(
    p: FloatArray, q: FloatArray, block_elems: int, stiffness: FloatArray | None = None
) -> FloatArray:
    """``sum_i q_i (p_k - p_i) / r_ki^3`` for every k (eq. 8 without ``k_r q_k``).

    Rows are taken in blocks of ``block_elems // N`` robots; every temporary is
    (rows, N), never (N, N, 2). If ``stiffness`` (N,) is given, ``sum_i q_i / r_ki^3``
    is written into it (for :func:`stiffness_bound`).
    """
    n = p.shape[0]
    out = np.zeros((n, 2))
    if n < 2:
        if stiffness is not None:
            stiffness[:] = 0.0
        return out
    p = p - p.mean(axis=0)  # translation-invariant; keeps the numbers near 0
    x, y = p[:, 0], p[:, 1]
    rows = _block_rows(n, block_elems)
    for a in range(0, n, rows):
        b = min(n, a + rows)
        dx = np.subtract(x[a:b, None], x[None, :])
        dy = np.subtract(y[a:b, None], y[None, :])
        r2 = dx * dx
        r2 += dy * dy
        r2[np.arange(b - a), np.arange(a, b)] = np.inf  # no self-force
        # coincident robots (r = 0) have dx = dy = 0: a floored r2 gives them 0 force
        np.maximum(r2, 1e-200, out=r2)
        w = np.sqrt(r2)
        w *= r2
        np.divide(q, w, out=w)  # q_i / r^3
        out[a:b, 0] = np.einsum("ij,ij->i", w, dx)
        out[a:b, 1] = np.einsum("ij,ij->i", w, dy)
        if stiffness is not None:
            stiffness[a:b] = w.sum(axis=1)
    return out


def coulomb_repulsion(
    pos: ArrayLike,
    *,
    k_r: float = 10.0,
    charge: ArrayLike = 1.0,
    block_elems: int = BLOCK_ELEMS,
) -> FloatArray:
    """Coulomb repulsion on every robot from all the others (eqs. 7-8).

    Parameters
    ----------
    pos : array_like, shape (N, 2)
        Robot positions [m].
    k_r : float
        Coulomb constant [N m^2 / C^2].
    charge : float or array_like, shape (N,)
        Charges q [C]; a robot of charge 0 neither pushes nor is pushed.
    block_elems : int
        Pairs per block of the sum (memory O(block_elems), not O(N^2)).

    Returns
    -------
    ndarray, shape (N, 2)
        ``F_k = k_r q_k sum_{i != k} q_i (p_k - p_i) / |p_k - p_i|^3`` [N]: magnitude
        ``k_r q_k q_i / r^2`` per pair (eq. 7), summed over the team (eq. 8). Coincident
        robots (r = 0) exert no force on each other (the direction is undefined).

    Examples
    --------
    >>> from firefleet.control.formation import coulomb_repulsion
    >>> # k_r q^2 / r^2 = 10 / 4 = 2.5 N, pushing the two robots apart
    >>> coulomb_repulsion([[0.0, 0.0], [2.0, 0.0]], k_r=10.0).tolist()
    [[-2.5, 0.0], [2.5, 0.0]]
    """
    p = _positions(pos)
    q = _charges(charge, p.shape[0])
    if k_r == 0:
        return np.zeros_like(p)
    coulomb = _coulomb_sums(p, q, block_elems)
    coulomb *= (k_r * q)[:, None]
    return coulomb


def _firas(gap: FloatArray, range_m: float, gain: float) -> FloatArray:
    """FIRAS magnitude ``gain (1/g - 1/rho) / g^2`` for gaps g < rho, else 0 [N]."""
    g = np.maximum(gap, _MIN_GAP_M)
    out: FloatArray = np.where(gap < range_m, gain * (1.0 / g - 1.0 / range_m) / (g * g), 0.0)
    return out


def contact_repulsion(
    pos: ArrayLike,
    *,
    radius_m: float,
    range_m: float,
    gain: float,
) -> FloatArray:
    """Short-range repulsion between robot bodies (FIRAS, Khatib 1986).

    Parameters
    ----------
    pos : array_like, shape (N, 2)
        Robot centres [m].
    radius_m : float
        Body radius R [m]; the gap between robots k and i is ``|p_k - p_i| - 2 R``.
    range_m : float
        Gap rho below which the force acts [m].
    gain : float
        eta [N m^2].

    Returns
    -------
    ndarray, shape (N, 2)
        ``sum_i eta (1/g - 1/rho) / g^2 * (p_k - p_i) / |p_k - p_i|`` over the robots
        i with gap g < rho [N] (g is floored at 1 mm, where the force is capped).

    Notes
    -----
    The pairs within reach come from a k-d tree (``scipy.spatial.cKDTree``), in
    O(N log N) time and O(pairs) memory.

    Examples
    --------
    >>> from firefleet.control.formation import contact_repulsion
    >>> # gap g = 1 - 2 * 0.375 = 0.25 m: eta (1/g - 1/rho) / g^2 = (4 - 2) / 0.0625 = 32 N
    >>> f = contact_repulsion([[0.0, 0.0], [1.0, 0.0]], radius_m=0.375, range_m=0.5, gain=1.0)
    >>> f.round(12).tolist()
    [[-32.0, 0.0], [32.0, 0.0]]
    """
    return _contact(_positions(pos), radius_m=radius_m, range_m=range_m, gain=gain)[0]


def obstacle_repulsion(
    pos: ArrayLike,
    centres_m: ArrayLike,
    radii_m: ArrayLike,
    *,
    robot_radius_m: float,
    range_m: float,
    gain: float,
) -> FloatArray:
    """Repulsion of circular obstacles on the robots (FIRAS on the body-obstacle gap).

    Parameters
    ----------
    pos : array_like, shape (N, 2)
        Robot centres [m].
    centres_m : array_like, shape (M, 2)
        Obstacle centres [m].
    radii_m : array_like, shape (M,)
        Obstacle radii [m].
    robot_radius_m, range_m, gain : float
        Body radius R [m], gap rho below which the force acts [m], eta [N m^2].

    Returns
    -------
    ndarray, shape (N, 2)
        Sum over the obstacles of ``eta (1/g - 1/rho) / g^2`` along the outward normal,
        with gap ``g = |p - o| - R - R_o`` [N].

    Examples
    --------
    >>> from firefleet.control.formation import obstacle_repulsion
    >>> # gap 1 - 0.25 - 0.5 = 0.25 m: (1/0.25 - 1/0.5) / 0.25^2 = 32 N, away from the obstacle
    >>> f = obstacle_repulsion(
    ...     [[1.0, 0.0]], [[0.0, 0.0]], [0.5], robot_radius_m=0.25, range_m=0.5, gain=1.0
    ... )
    >>> f.round(12).tolist()
    [[32.0, 0.0]]
    """
    p = _positions(pos)
    o = as_float_array(centres_m, "centres_m", (None, 2))
    ro = as_float_array(radii_m, "radii_m", (o.shape[0],))
    if o.shape[0] == 0 or gain == 0:
        return np.zeros_like(p)
    d = p[:, None, :] - o[None, :, :]  # (N, M, 2), M small
    r = np.sqrt((d * d).sum(axis=2))
    gap = r - robot_radius_m - ro[None, :]
    mag = _firas(gap, range_m, gain) / np.maximum(r, 1e-12)
    out: FloatArray = (mag[:, :, None] * d).sum(axis=1)
    return out


def tangential_part(force: ArrayLike, pos: ArrayLike, leader_xy: ArrayLike) -> FloatArray:
    """The component of each force along the circle about the leader through its robot.

    Parameters
    ----------
    force, pos : array_like, shape (N, 2)
        Forces [N] and robot positions [m].
    leader_xy : array_like, shape (2,)
        Leader position [m].

    Returns
    -------
    ndarray, shape (N, 2)
        ``(f . t) t`` with ``t`` the unit tangent at the robot (0 for a robot on the
        leader, where the tangent is undefined).

    Examples
    --------
    >>> from firefleet.control.formation import tangential_part
    >>> (tangential_part([[1.0, 1.0]], [[1.0, 0.0]], [0.0, 0.0]).round(12) + 0.0).tolist()
    [[0.0, 1.0]]
    """
    f = _positions(force, "force")
    p = _positions(pos)
    d = p - as_float_array(leader_xy, "leader_xy", (2,))
    r = np.sqrt((d * d).sum(axis=1))
    safe = np.where(r > 0, r, 1.0)
    tx, ty = -d[:, 1] / safe, d[:, 0] / safe
    ft = np.where(r > 0, f[:, 0] * tx + f[:, 1] * ty, 0.0)
    return np.stack([ft * tx, ft * ty], axis=1)


def ring_spacing(
    pos: ArrayLike,
    leader_xy: ArrayLike,
    *,
    stiffness_n_m: float,
    active: ArrayLike | None = None,
) -> FloatArray:
    """Angular-neighbour spacing force of the ``"regular"`` law (Wang, Xie and Cao 2013).

    Parameters
    ----------
    pos : array_like, shape (N, 2)
        Robot positions [m].
    leader_xy : array_like, shape (2,)
        The virtual leader [m].
    stiffness_n_m : float
        K_s [N/m].
    active : array_like of bool, shape (N,), optional
        Robots in the team (default all); the others neither push nor are pushed.

    Returns
    -------
    ndarray, shape (N, 2)
        ``K_s r_k (g_k+ - g_k-) / 2 t_k`` [N]: ``g_k+`` the angle about the leader from
        robot k to the next active robot counter-clockwise, ``g_k-`` from the previous
        one to robot k, ``r_k`` the robot's distance from the leader and ``t_k`` the
        unit tangent (counter-clockwise). Zero for one robot, for an inactive robot and
        for a robot on the leader (no angle).

    Examples
    --------
    >>> import numpy as np
    >>> pos = np.array([[2.0, 0.0], [0.0, 2.0], [-2.0, 0.0]])  # at 0, 90 and 180 deg
    >>> # gaps 90, 90 and 180 deg: robots 1 and 3 move into the empty half, robot 2 stays
    >>> ring_spacing(pos, [0.0, 0.0], stiffness_n_m=1.0).round(4) + 0.0
    array([[ 0.    , -1.5708],
           [ 0.    ,  0.    ],
           [ 0.    , -1.5708]])
    """
    p = _positions(pos)
    d = p - as_float_array(leader_xy, "leader_xy", (2,))
    use = (d * d).sum(axis=1) > 0
    if active is not None:
        use &= np.asarray(active, dtype=bool).reshape(-1)
    return _ring_spacing(d, use, stiffness_n_m)[0]


def _ring_spacing(d: FloatArray, use: BoolArray, stiffness_n_m: float) -> tuple[FloatArray, float]:
    """:func:`ring_spacing` from the offsets ``d = p - c`` (N, 2) of the robots ``use``
    (not on the leader), and the largest ``|g+ - g-|`` [rad]."""
    out = np.zeros_like(d)
    idx = np.flatnonzero(use)
    if idx.size < 2 or stiffness_n_m == 0:
        return out, 0.0
    theta = np.arctan2(d[idx, 1], d[idx, 0])
    order = np.argsort(theta, kind="stable")
    th = theta[order]
    ahead = np.empty_like(th)  # gap to the next robot counter-clockwise
    ahead[:-1] = th[1:] - th[:-1]
    ahead[-1] = th[0] + 2.0 * math.pi - th[-1]
    behind = np.roll(ahead, 1)
    k = idx[order]
    diff = ahead - behind
    ft = (0.5 * stiffness_n_m) * diff  # per unit radius [N/m]
    out[k, 0] = -ft * d[k, 1]  # ft r t, with r t = (-dy, dx)
    out[k, 1] = ft * d[k, 0]
    return out, float(np.abs(diff).max())


def _firas_slope(gap: FloatArray, range_m: float, gain: float) -> FloatArray:
    """``|dF/dg|`` of the FIRAS magnitude for gaps g < rho (0 beyond) [N/m]."""
    g = np.maximum(gap, _MIN_GAP_M)
    slope = gain * np.abs(3.0 / g**4 - 2.0 / (range_m * g**3))
    out: FloatArray = np.where((gap < range_m) & (gap > _MIN_GAP_M), slope, 0.0)
    return out


def contact_pairs(pos: ArrayLike, reach_m: float) -> NDArray[np.intp]:
    """Every pair of robots closer than ``reach_m`` (a k-d tree, O(N log N)).

    Parameters
    ----------
    pos : array_like, shape (N, 2)
        Robot centres [m].
    reach_m : float
        Distance [m].

    Returns
    -------
    ndarray of int, shape (P, 2)
        Pairs (i, j), i < j, with ``|p_i - p_j| <= reach_m``.

    Notes
    -----
    Found with a reach ``2 R + rho + s`` (a skin s), the list stays a superset of the
    pairs within ``2 R + rho`` until some robot has moved s / 2 (Verlet's neighbour
    list, Phys. Rev. 159, 1967); the runner rebuilds it only then.

    Examples
    --------
    >>> from firefleet.control.formation import contact_pairs
    >>> contact_pairs([[0.0, 0.0], [1.0, 0.0], [5.0, 0.0]], 1.5).tolist()
    [[0, 1]]
    """
    p = _positions(pos)
    if p.shape[0] < 2:
        return np.zeros((0, 2), dtype=np.intp)
    out: NDArray[np.intp] = cKDTree(p).query_pairs(reach_m, output_type="ndarray")
    return out


def _contact(
    p: FloatArray,
    *,
    radius_m: float,
    range_m: float,
    gain: float,
    pairs: NDArray[np.intp] | None = None,
) -> tuple[FloatArray, FloatArray]:
    """:func:`contact_repulsion` and each robot's Gershgorin row sum of its stiffness.

    ``pairs`` (P, 2): candidate pairs including every pair within ``2 R + rho``
    (default: :func:`contact_pairs`)."""
    n = p.shape[0]
    out = np.zeros_like(p)
    stiff = np.zeros(n)
    if n < 2 or gain == 0:
        return out, stiff
    if pairs is None:
        pairs = contact_pairs(p, 2.0 * radius_m + range_m)
    if pairs.shape[0] == 0:
        return out, stiff
    k, i = pairs[:, 0], pairs[:, 1]
    d = p[k] - p[i]
    r = np.sqrt((d * d).sum(axis=1))
    keep = (r > 0) & (r < 2.0 * radius_m + range_m)  # coincident bodies: no direction
    k, i, d, r = k[keep], i[keep], d[keep], r[keep]
    gap = r - 2.0 * radius_m
    mag = _firas(gap, range_m, gain)
    push = (mag / r)[:, None] * d
    out[:, 0] = np.bincount(k, push[:, 0], n) - np.bincount(i, push[:, 0], n)
    out[:, 1] = np.bincount(k, push[:, 1], n) - np.bincount(i, push[:, 1], n)
    pair = 2.0 * np.maximum(_firas_slope(gap, range_m, gain), mag / r)
    total = np.asarray(np.bincount(k, pair, n) + np.bincount(i, pair, n), dtype=np.float64)
    return out, total
