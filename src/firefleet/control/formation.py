"""Formation control about a virtual leader (deliverable section 2.3, eqs. 6-8).

Every robot is a point ``p_k`` (a point mass, eq. 5, or a differential-drive robot's
look-ahead point) and the virtual leader sits at ``c``, the centre of the formation.
Two laws are implemented, both decentralised: robot k uses only the leader's state and
the other robots' positions.

``"deliverable"`` (section 2.3.1, after Rezaee and Abdollahi 2014)::

    f_k = -a (p_k - c) (|p_k - c|^2 - alpha^2)                    attraction, eq. 6
          + k_r q_k sum_{i != k} q_i (p_k - p_i) / |p_k - p_i|^3    Coulomb, eqs. 7-8

The attraction pulls every robot onto the circle of radius alpha about the leader; the
repulsion (magnitude ``k_r q_k q_i / r^2``, eq. 7, along the line between the robots)
spreads them. Its radial part also pushes every robot a little outside the circle,
and its tangential part is weak near equilibrium, which is why the deliverable sees
"an irregular polygon with all the vertices lying on the circle".

``"regular"`` (beyond the deliverable)::

    f_k = attraction (eq. 6) + g_t (F_k . t_k) t_k + contact_k

where ``F_k`` is the Coulomb force of eq. 8 and ``t_k`` the unit tangent of the circle
about the leader at robot k. Keeping only the tangential part of the repulsion leaves
the radial equilibrium exactly on the circle (|p_k - c| = alpha), and on the circle the
tangential part is minus the gradient of the Coulomb energy ``sum k_r q q / r_ki`` with
respect to the robot's arc position, whose minimum on a circle is the regular polygon
(equal angular spacing; Thomson's problem in one dimension). ``g_t`` (``spacing_gain``)
speeds the spacing up. Because the radial repulsion is gone, robots on the same ray
would no longer repel: ``contact_k``, a short-range repulsion on the gap between the
robots' bodies (Khatib's FIRAS potential, 1986), keeps them apart; it is zero once the
gaps exceed ``contact_range_m``, so it leaves the polygon untouched.

Obstacles (circles) repel with the same FIRAS force on the gap between a robot's body
and the obstacle (Rezaee and Abdollahi 2014 treat obstacles as repulsive too).

The Coulomb sums are evaluated in row blocks of at most ``block_elems`` pairs, so the
memory is O(N + block), not O(N^2): no N x N x k temporaries at any team size. The
short-range contact pairs come from a k-d tree (O(N log N)).

References
----------
H. Rezaee and F. Abdollahi, "A decentralized cooperative control scheme with obstacle
avoidance for a team of mobile robots", IEEE Trans. Industrial Electronics 61(1), 2014.
O. Khatib, "Real-time obstacle avoidance for manipulators and mobile robots",
Int. J. Robotics Research 5(1), 1986 (the FIRAS potential).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from firefleet.errors import InputError, as_float_array, check_fields

__all__ = [
    "BLOCK_ELEMS",
    "FormationParams",
    "circle_attraction",
    "contact_repulsion",
    "coulomb_repulsion",
    "formation_force",
    "obstacle_repulsion",
    "tangential_part",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

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
        Largest magnitude of the attraction [N] (an actuator's limit; ``inf``: eq. 6 as
        printed, which grows with the cube of the distance).
    spacing_gain : float
        g_t, gain on the tangential Coulomb force of the ``"regular"`` law, >= 0.
    robot_radius_m : float
        Radius of a robot's body [m], >= 0 (for contact and obstacle forces).
    contact_gain : float
        Gain of the FIRAS contact and obstacle forces [N m^2], >= 0.
    contact_range_m : float
        Body gap below which the FIRAS force acts [m], > 0.
    """

    alpha_m: float = 3.0
    k_r: float = 10.0
    charge_c: float = 1.0
    attraction_gain: float = 1.0
    attraction_limit_n: float = math.inf
    spacing_gain: float = 1.0
    robot_radius_m: float = 0.15
    contact_gain: float = 0.05
    contact_range_m: float = 0.5

    def __post_init__(self) -> None:
        check_fields(
            self,
            "",
            positive=("alpha_m", "attraction_gain", "contact_range_m"),
            non_negative=("k_r", "charge_c", "spacing_gain", "robot_radius_m", "contact_gain"),
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


def _coulomb_sums(p: FloatArray, q: FloatArray, block_elems: int) -> FloatArray:
    """``sum_i q_i (p_k - p_i) / r_ki^3`` for every k (eq. 8 without ``k_r q_k``).

    Rows are taken in blocks of ``block_elems // N`` robots; every temporary is
    (rows, N), never (N, N, 2).
    """
    n = p.shape[0]
    out = np.zeros((n, 2))
    if n < 2:
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
    """
    p = _positions(pos)
    out = np.zeros_like(p)
    if p.shape[0] < 2 or gain == 0:
        return out
    pairs = cKDTree(p).query_pairs(2.0 * radius_m + range_m, output_type="ndarray")
    if pairs.shape[0] == 0:
        return out
    k, i = pairs[:, 0], pairs[:, 1]
    d = p[k] - p[i]
    r = np.sqrt((d * d).sum(axis=1))
    keep = r > 0  # coincident bodies: no defined direction
    k, i, d, r = k[keep], i[keep], d[keep], r[keep]
    push = (_firas(r - 2.0 * radius_m, range_m, gain) / r)[:, None] * d
    np.add.at(out, k, push)
    np.add.at(out, i, -push)
    return out


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
    """
    f = _positions(force, "force")
    p = _positions(pos)
    d = p - as_float_array(leader_xy, "leader_xy", (2,))
    r = np.sqrt((d * d).sum(axis=1))
    safe = np.where(r > 0, r, 1.0)
    tx, ty = -d[:, 1] / safe, d[:, 0] / safe
    ft = np.where(r > 0, f[:, 0] * tx + f[:, 1] * ty, 0.0)
    return np.stack([ft * tx, ft * ty], axis=1)


def formation_force(
    pos: ArrayLike,
    leader_xy: ArrayLike,
    params: FormationParams,
    *,
    law: Literal["deliverable", "regular"] = "deliverable",
    active: ArrayLike | None = None,
    obstacles: tuple[ArrayLike, ArrayLike] | None = None,
    body_radius_m: float | None = None,
    block_elems: int = BLOCK_ELEMS,
) -> FloatArray:
    """The formation force on every robot (see the module notes for both laws).

    Parameters
    ----------
    pos : array_like, shape (N, 2)
        Controlled points [m] (point masses, or look-ahead points).
    leader_xy : array_like, shape (2,)
        The virtual leader [m].
    params : FormationParams
    law : {"deliverable", "regular"}
        Eqs. 6-8 as in the deliverable, or the regular-polygon law.
    active : array_like of bool, shape (N,), optional
        Robots still in the team (default all). An inactive (failed) robot gets no
        force, carries no charge and has no place in the formation, but its body is
        still there: the contact and obstacle forces see it.
    obstacles : (centres (M, 2), radii (M,)), optional
        Circular obstacles [m].
    body_radius_m : float, optional
        Radius of the disc about each controlled point that must stay clear
        (default ``params.robot_radius_m``; a look-ahead point ``l`` ahead of the centre
        needs ``R + l``).
    block_elems : int
        Pairs per block of the pairwise sums.

    Returns
    -------
    ndarray, shape (N, 2)
        Force [N] (zero for inactive robots).
    """
    p = _positions(pos)
    n = p.shape[0]
    if law not in ("deliverable", "regular"):
        raise InputError(f"law must be 'deliverable' or 'regular', got {law!r}")
    alive: BoolArray = (
        np.ones(n, dtype=bool) if active is None else np.asarray(active, dtype=bool).reshape(-1)
    )
    if alive.shape != (n,):
        raise InputError(f"active must have shape ({n},), got {alive.shape}")
    radius = params.robot_radius_m if body_radius_m is None else body_radius_m
    c = as_float_array(leader_xy, "leader_xy", (2,))
    f = circle_attraction(
        p,
        c,
        alpha_m=params.alpha_m,
        gain=params.attraction_gain,
        limit_n=params.attraction_limit_n,
    )
    q = np.where(alive, params.charge_c, 0.0)
    rep = coulomb_repulsion(p, k_r=params.k_r, charge=q, block_elems=block_elems)
    if law == "deliverable":
        f += rep
    else:
        f += params.spacing_gain * tangential_part(rep, p, c)
        f += contact_repulsion(
            p, radius_m=radius, range_m=params.contact_range_m, gain=params.contact_gain
        )
    if obstacles is not None:
        f += obstacle_repulsion(
            p,
            obstacles[0],
            obstacles[1],
            robot_radius_m=radius,
            range_m=params.contact_range_m,
            gain=params.contact_gain,
        )
    f[~alive] = 0.0
    return f
