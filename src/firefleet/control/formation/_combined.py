"""The formation force of a whole team and its stiffness bound (the step divider's
input), and the contact pairs found with a k-d tree.

See :mod:`firefleet.control.formation` for the laws and their references.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet._typing import BoolArray, FloatArray
from firefleet.control.formation._forces import (
    BLOCK_ELEMS,
    FormationParams,
    _contact,
    _coulomb_sums,
    _firas,
    _firas_slope,
    _positions,
    _ring_spacing,
    obstacle_repulsion,
)
from firefleet.errors import InputError, as_float_array


def formation_force_and_stiffness(
    pos: ArrayLike,
    leader_xy: ArrayLike,
    params: FormationParams,
    *,
    law: Literal["deliverable", "regular"] = "deliverable",
    active: ArrayLike | None = None,
    obstacles: tuple[ArrayLike, ArrayLike] | None = None,
    body_radius_m: float | None = None,
    contact_range_m: float | None = None,
    pairs: NDArray[np.intp] | None = None,
    block_elems: int = BLOCK_ELEMS,
) -> tuple[FloatArray, float]:
    """The formation force and a bound on its stiffness (see :func:`formation_force`).

    Parameters
    ----------
    pos, leader_xy, params, law, active, obstacles, body_radius_m, block_elems
        As :func:`formation_force`.
    contact_range_m : float, optional
        Range of the robot-robot contact force [m] (default ``params.contact_range_m``).
    pairs : ndarray of int, shape (P, 2), optional
        Candidate pairs for the contact force, including every pair of robots closer
        than ``2 body_radius_m + contact_range_m`` (default: found now,
        :func:`contact_pairs`).

    Returns
    -------
    force : ndarray, shape (N, 2)
        Force [N] (zero for inactive robots).
    stiffness_n_m : float
        An upper bound on the spectral radius of the force's Jacobian [N/m], from
        Gershgorin's theorem: per robot, the attraction's ``a max(|3 r^2 - alpha^2|,
        |r^2 - alpha^2|)`` (``limit / r`` where capped), ``2 sum_i`` of each pair's
        stiffness (Coulomb ``2 k_r q_k q_i / r^3``, contact ``max(|F'(g)|, F / r)``),
        the obstacles' ``max(|F'(g)|, F / r)``; the largest over the robots, plus the
        spacing law's ``K_s (2 + max |g+ - g-|)`` (its Jacobian is similar, by the
        robots' radii, to one of spectral radius 2 K_s; the rest is the turning of the
        tangent and the radius' lever).

    Examples
    --------
    >>> from firefleet.control.formation import FormationParams, formation_force_and_stiffness
    >>> f, k = formation_force_and_stiffness([[3.0, 0.0]], [0.0, 0.0], FormationParams(alpha_m=3.0))
    >>> (f + 0.0).tolist(), k  # on the circle: no force, radial stiffness 2 a alpha^2
    ([[0.0, 0.0]], 18.0)
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
    reach = params.contact_range_m if contact_range_m is None else contact_range_m
    c = as_float_array(leader_xy, "leader_xy", (2,))
    alpha = params.alpha_m
    a = params.attraction_gain
    limit = params.attraction_limit_n
    # eq. 6, as circle_attraction (the same arithmetic), and its stiffness per robot
    d = p - c
    r2 = (d * d).sum(axis=1)
    off = r2 - alpha * alpha
    f = -a * d * off[:, None]
    stiff = a * np.maximum(np.abs(3.0 * r2 - alpha * alpha), np.abs(off))
    if math.isfinite(limit):
        mag = np.sqrt((f * f).sum(axis=1))
        f *= np.minimum(1.0, limit / np.maximum(mag, 1e-300))[:, None]
        capped = mag > limit
        if capped.any():
            stiff = np.where(capped, limit / np.maximum(np.sqrt(r2), 1e-300), stiff)
    spacing_bound = 0.0
    if law == "deliverable":
        q = np.where(alive, params.charge_c, 0.0)
        if params.k_r != 0 and n >= 2:
            row = np.empty(n)
            rep = _coulomb_sums(p, q, block_elems, row)
            rep *= (params.k_r * q)[:, None]
            f += rep
            stiff += 4.0 * params.k_r * q * row
    else:
        ks = params.spacing_stiffness_n_m
        spacing, widest = _ring_spacing(d, alive & (r2 > 0), ks)
        f += spacing
        spacing_bound = ks * (2.0 + widest)
        contact, contact_stiff = _contact(
            p, radius_m=radius, range_m=reach, gain=params.contact_gain, pairs=pairs
        )
        f += contact
        stiff += contact_stiff
    if obstacles is not None:
        f += obstacle_repulsion(
            p,
            obstacles[0],
            obstacles[1],
            robot_radius_m=radius,
            range_m=params.contact_range_m,
            gain=params.contact_gain,
        )
        stiff += _obstacle_stiffness(
            p, obstacles, radius, params.contact_range_m, params.contact_gain
        )
    f[~alive] = 0.0
    stiff[~alive] = 0.0
    return f, float(stiff.max(initial=0.0)) + spacing_bound


def _obstacle_stiffness(
    p: FloatArray,
    obstacles: tuple[ArrayLike, ArrayLike],
    robot_radius_m: float,
    range_m: float,
    gain: float,
) -> FloatArray:
    """Per robot, the obstacles' ``sum max(|F'(g)|, F / r)`` [N/m]."""
    o = as_float_array(obstacles[0], "centres_m", (None, 2))
    ro = as_float_array(obstacles[1], "radii_m", (o.shape[0],))
    if o.shape[0] == 0 or gain == 0:
        return np.zeros(p.shape[0])
    d = p[:, None, :] - o[None, :, :]
    r = np.sqrt((d * d).sum(axis=2))
    gap = r - robot_radius_m - ro[None, :]
    per = np.maximum(
        _firas_slope(gap, range_m, gain), _firas(gap, range_m, gain) / np.maximum(r, 1e-12)
    )
    out: FloatArray = per.sum(axis=1)
    return out


def stiffness_bound(
    pos: ArrayLike,
    leader_xy: ArrayLike,
    params: FormationParams,
    *,
    law: Literal["deliverable", "regular"] = "deliverable",
    active: ArrayLike | None = None,
    obstacles: tuple[ArrayLike, ArrayLike] | None = None,
    body_radius_m: float | None = None,
    contact_range_m: float | None = None,
    block_elems: int = BLOCK_ELEMS,
) -> float:
    """An upper bound on the stiffness of the formation force at ``pos`` [N/m].

    The second value of :func:`formation_force_and_stiffness` (see there).

    Examples
    --------
    >>> import numpy as np
    >>> # one robot on the 3 m circle: the attraction's radial stiffness 2 a alpha^2
    >>> stiffness_bound(np.array([[3.0, 0.0]]), [0.0, 0.0], FormationParams(alpha_m=3.0))
    18.0
    """
    return formation_force_and_stiffness(
        pos,
        leader_xy,
        params,
        law=law,
        active=active,
        obstacles=obstacles,
        body_radius_m=body_radius_m,
        contact_range_m=contact_range_m,
        block_elems=block_elems,
    )[1]


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

    Examples
    --------
    >>> from firefleet.control.formation import FormationParams, formation_force
    >>> # two robots on the 3 m circle: no attraction, Coulomb 10 / 6^2 N outwards
    >>> f = formation_force([[3.0, 0.0], [-3.0, 0.0]], [0.0, 0.0], FormationParams(alpha_m=3.0))
    >>> f.round(4).tolist(), round(10 / 36, 4)
    ([[0.2778, 0.0], [-0.2778, 0.0]], 0.2778)
    """
    return formation_force_and_stiffness(
        pos,
        leader_xy,
        params,
        law=law,
        active=active,
        obstacles=obstacles,
        body_radius_m=body_radius_m,
        block_elems=block_elems,
    )[0]
