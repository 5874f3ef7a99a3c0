"""Formation forces (eqs. 6-8, the regular law) against hand-computed cases and loops."""

from __future__ import annotations

import math
import tracemalloc
from collections.abc import Callable

import numpy as np
import pytest
from numpy.typing import NDArray
from scipy.optimize import brentq

from firefleet.control.formation import (
    FormationParams,
    circle_attraction,
    contact_repulsion,
    coulomb_repulsion,
    formation_force,
    formation_force_and_stiffness,
    obstacle_repulsion,
    ring_spacing,
    stiffness_bound,
    tangential_part,
)
from firefleet.errors import InputError

FloatArray = NDArray[np.float64]


def _polygon(n: int, radius: float, centre: tuple[float, float] = (0.0, 0.0)) -> FloatArray:
    ang = 2.0 * np.pi * np.arange(n) / n + 0.3
    out: FloatArray = np.column_stack([np.cos(ang), np.sin(ang)]) * radius + np.array(centre)
    return out


def test_attraction_by_hand() -> None:
    c = np.array([1.0, -2.0])
    pos = c + np.array([[4.0, 0.0], [0.0, 3.0], [1.0, 0.0]])
    f = circle_attraction(pos, c, alpha_m=3.0)
    # eq. 6: -(p - c)(|p - c|^2 - alpha^2): (4,0) -> -(4)(16 - 9) = -28; on the circle 0;
    # (1,0) inside -> -(1)(1 - 9) = +8 (outward). Exact in floating point.
    np.testing.assert_array_equal(f, [[-28.0, 0.0], [0.0, 0.0], [8.0, 0.0]])
    capped = circle_attraction(pos, c, alpha_m=3.0, gain=2.0, limit_n=10.0)
    # gain 2 doubles it, the 10 N cap scales -56 N down to -10 N and leaves 16 N -> 10 N
    np.testing.assert_allclose(capped, [[-10.0, 0.0], [0.0, 0.0], [10.0, 0.0]], atol=1e-14)


def test_coulomb_by_hand() -> None:
    pos = np.array([[0.0, 0.0], [2.0, 0.0]])
    f = coulomb_repulsion(pos, k_r=10.0, charge=np.array([1.0, 2.0]))
    # eq. 7: k_r q1 q2 / r^2 = 10 * 2 / 4 = 5 N, pushing the robots apart along x
    np.testing.assert_allclose(f, [[-5.0, 0.0], [5.0, 0.0]], rtol=1e-15)
    three = np.array([[0.0, 0.0], [1.0, 0.0], [3.0, 0.0]])
    f3 = coulomb_repulsion(three, k_r=10.0)
    # eq. 8 on the middle robot: +10/1 from the left one, -10/4 from the right one
    # on the left one: -10/1 - 10/9; on the right one: 10/4 + 10/9
    expected = [[-10.0 - 10.0 / 9.0, 0.0], [10.0 - 2.5, 0.0], [2.5 + 10.0 / 9.0, 0.0]]
    np.testing.assert_allclose(f3, expected, rtol=1e-14)


def test_symmetric_team_repulsion_sums_to_zero_and_is_radial() -> None:
    pos = _polygon(7, 2.5, centre=(40.0, -12.0))
    f = coulomb_repulsion(pos, k_r=10.0)
    # Newton's third law: the forces cancel in pairs; each is ~1 N, so rounding ~1e-15
    np.testing.assert_allclose(f.sum(axis=0), 0.0, atol=1e-13)
    # by symmetry each robot is pushed straight out from the polygon's centre
    t = tangential_part(f, pos, np.array([40.0, -12.0]))
    np.testing.assert_allclose(t, 0.0, atol=1e-13)
    radial = np.einsum("ij,ij->i", f, (pos - [40.0, -12.0]) / 2.5)
    # analytic radial push on a regular N-gon: k_r sum_j 1 / (4 r^2 sin(pi j / N))
    expected = 10.0 * sum(1.0 / (4.0 * 2.5**2 * math.sin(math.pi * j / 7)) for j in range(1, 7))
    np.testing.assert_allclose(radial, expected, rtol=1e-13)


def test_random_team_repulsion_sums_to_zero() -> None:
    pos = np.random.default_rng(1).uniform(-20, 20, (300, 2))
    f = coulomb_repulsion(pos, k_r=10.0)
    scale = np.abs(f).max()
    # third law; rounding of 300-term sums relative to the largest force: 1e-12
    assert np.abs(f.sum(axis=0)).max() <= 1e-12 * scale * 300


@pytest.mark.parametrize("block_elems", [1, 50, 1000, 1 << 20])
def test_batched_force_equals_a_double_loop(block_elems: int) -> None:
    rng = np.random.default_rng(5)
    n = 37
    pos = rng.uniform(-3, 3, (n, 2))
    q = rng.uniform(0.5, 2.0, n)
    ref = np.zeros((n, 2))
    for k in range(n):
        for i in range(n):
            if i == k:
                continue
            d = pos[k] - pos[i]
            r = math.hypot(d[0], d[1])
            ref[k] += 10.0 * q[k] * q[i] / r**2 * d / r  # eq. 7 along the unit vector
    f = coulomb_repulsion(pos, k_r=10.0, charge=q, block_elems=block_elems)
    # same sums, different order of operations: relative 1e-12
    np.testing.assert_allclose(f, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


def test_contact_force_equals_a_double_loop() -> None:
    rng = np.random.default_rng(8)
    pos = rng.uniform(0, 3, (60, 2))  # dense: many bodies within reach of each other
    ref = np.zeros((60, 2))
    for k in range(60):
        for i in range(60):
            d = pos[k] - pos[i]
            r = math.hypot(d[0], d[1])
            gap = r - 0.3
            if i != k and gap < 0.5:
                g = max(gap, 1e-3)
                ref[k] += 0.05 * (1 / g - 1 / 0.5) / g**2 * d / r  # FIRAS, Khatib 1986
    f = contact_repulsion(pos, radius_m=0.15, range_m=0.5, gain=0.05)
    assert np.abs(ref).max() > 1.0  # some bodies are close
    # same terms, summed in another order: relative 1e-12
    np.testing.assert_allclose(f, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


def test_coincident_robots_exert_no_force() -> None:
    pos = np.array([[1.0, 1.0], [1.0, 1.0], [3.0, 1.0]])
    f = coulomb_repulsion(pos, k_r=10.0)
    assert np.all(np.isfinite(f))
    # the two coincident robots only feel the third: 10 / 2^2 = 2.5 N to the left
    np.testing.assert_allclose(f[:2], [[-2.5, 0.0], [-2.5, 0.0]], rtol=1e-15)


def test_contact_and_obstacle_forces_by_hand() -> None:
    # two bodies of radius 0.15 with centres 0.4 m apart: gap 0.1 m < range 0.5 m
    pos = np.array([[0.0, 0.0], [0.4, 0.0], [5.0, 0.0]])
    f = contact_repulsion(pos, radius_m=0.15, range_m=0.5, gain=0.05)
    # FIRAS: 0.05 (1/0.1 - 1/0.5) / 0.1^2 = 40 N; the third robot is out of range
    np.testing.assert_allclose(f, [[-40.0, 0.0], [40.0, 0.0], [0.0, 0.0]], rtol=1e-12)
    fo = obstacle_repulsion(
        np.array([[0.0, 1.45], [0.0, 5.0]]),
        np.array([[0.0, 0.0]]),
        np.array([1.0]),
        robot_radius_m=0.15,
        range_m=0.5,
        gain=0.05,
    )
    # gap 1.45 - 0.15 - 1.0 = 0.3: 0.05 (1/0.3 - 2) / 0.09 = 0.7407 N, outward (+y)
    np.testing.assert_allclose(fo, [[0.0, 0.05 * (1 / 0.3 - 2.0) / 0.09], [0.0, 0.0]], rtol=1e-12)


@pytest.mark.parametrize(
    ("n", "alpha"), [(3, 3.0), (4, 3.0), (5, 3.0), (8, 3.0), (20, 3.0), (200, 30.0), (1000, 150.0)]
)
def test_regular_polygon_on_the_circle_is_an_equilibrium_of_the_regular_law(
    n: int, alpha: float
) -> None:
    params = FormationParams(alpha_m=alpha)
    c = np.array([2.0, 1.0])
    f = formation_force(_polygon(n, alpha, (2.0, 1.0)), c, params, law="regular")
    # attraction 0 on the circle up to the rounding of r^2 - alpha^2 (~4 alpha^2 eps,
    # times a r: ~4 a alpha^3 eps, 3e-9 N at 150 m), equal angular gaps (the spacing
    # force is K_s alpha times differences of equal gaps), contact out of range (sides
    # >= 0.94 m: gaps 0.64 m > 0.5 m)
    eps = np.finfo(float).eps
    np.testing.assert_allclose(f, 0.0, atol=max(1e-11, 10.0 * alpha**3 * eps))
    # and a perturbed polygon is not
    moved = _polygon(n, alpha, (2.0, 1.0))
    moved[0] += 0.1 * (moved[0] - c) / alpha
    assert np.abs(formation_force(moved, c, params, law="regular")[0]).max() > 0.1


def _spacing_by_loop(
    pos: FloatArray, c: FloatArray, k_s: float, alive: NDArray[np.bool_]
) -> FloatArray:
    """Each robot's nearest active neighbours by angle, found by trying every other."""
    out = np.zeros_like(pos)
    d = pos - c
    theta = np.arctan2(d[:, 1], d[:, 0])
    for k in range(len(pos)):
        if not alive[k]:
            continue
        ahead = behind = 2.0 * math.pi
        for i in range(len(pos)):
            if i == k or not alive[i]:
                continue
            ahead = min(ahead, (theta[i] - theta[k]) % (2.0 * math.pi))
            behind = min(behind, (theta[k] - theta[i]) % (2.0 * math.pi))
        r = math.hypot(d[k, 0], d[k, 1])
        t = np.array([-d[k, 1], d[k, 0]]) / r
        out[k] = k_s * r * (ahead - behind) / 2.0 * t
    return out


def test_ring_spacing_equals_a_loop_over_all_robots() -> None:
    rng = np.random.default_rng(8)
    pos = rng.uniform(-5.0, 5.0, (40, 2))
    c = np.array([0.3, -0.2])
    alive = rng.uniform(size=40) > 0.2
    f = ring_spacing(pos, c, stiffness_n_m=7.0, active=alive)
    np.testing.assert_allclose(f, _spacing_by_loop(pos, c, 7.0, alive), rtol=1e-12, atol=1e-12)
    # the spacing only moves robots along their circles, and the gaps' differences sum
    # to zero: the tangential forces over r sum to zero
    d = pos - c
    ft = (f * np.column_stack([-d[:, 1], d[:, 0]])).sum(axis=1) / (d * d).sum(axis=1)
    np.testing.assert_allclose((f * d).sum(axis=1), 0.0, atol=1e-12)
    assert abs(ft.sum()) < 1e-11


def test_ring_spacing_is_minus_the_gradient_of_the_gap_energy() -> None:
    # on the circle, U = K_s alpha^2 / 4 sum_k g_k^2 and the force along the arc is
    # -dU/ds_k (s = alpha theta): central differences in theta
    alpha, k_s = 2.0, 3.0
    rng = np.random.default_rng(3)
    theta = np.sort(rng.uniform(0.0, 2.0 * math.pi, 7))

    def energy(th: FloatArray) -> float:
        srt = np.sort(th % (2.0 * math.pi))
        gaps = np.diff(np.r_[srt, srt[0] + 2.0 * math.pi])
        return float(k_s * alpha**2 / 4.0 * (gaps**2).sum())

    pos = alpha * np.column_stack([np.cos(theta), np.sin(theta)])
    f = ring_spacing(pos, np.zeros(2), stiffness_n_m=k_s)
    along = f[:, 0] * -np.sin(theta) + f[:, 1] * np.cos(theta)
    h = 1e-6
    for k in range(7):
        up, down = theta.copy(), theta.copy()
        up[k] += h
        down[k] -= h
        grad = (energy(up) - energy(down)) / (2.0 * h) / alpha
        # quadratic energy: central differences are exact up to rounding (1e-9 / 1e-6)
        assert along[k] == pytest.approx(-grad, abs=1e-7)


def _jacobian(
    fun: Callable[[FloatArray], FloatArray], pos: FloatArray, h: float = 1e-7
) -> FloatArray:
    n = pos.size
    jac = np.empty((n, n))
    for j in range(n):
        up, down = pos.copy().reshape(-1), pos.copy().reshape(-1)
        up[j] += h
        down[j] -= h
        diff = fun(up.reshape(pos.shape)) - fun(down.reshape(pos.shape))
        jac[:, j] = diff.reshape(-1) / (2 * h)
    return jac


@pytest.mark.parametrize("law", ["deliverable", "regular"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_stiffness_bound_bounds_the_jacobian(law: str, seed: int) -> None:
    # 12 robots within 3 m of a 2 m circle, some pairs within contact range, one obstacle
    rng = np.random.default_rng(seed)
    pos = rng.uniform(-3.0, 3.0, (12, 2))
    pos[1] = pos[0] + [0.42, 0.05]  # bodies 0.12 m apart: contact force and Coulomb act
    obstacles = (np.array([[0.0, 3.5]]), np.array([0.4]))
    params = FormationParams(alpha_m=2.0, attraction_limit_n=math.inf)
    c = np.array([0.1, 0.0])

    def force(p: FloatArray) -> FloatArray:
        return formation_force(p, c, params, law=law, obstacles=obstacles)  # type: ignore[arg-type]

    jac = _jacobian(force, pos)
    rho = float(np.abs(np.linalg.eigvals(jac)).max())
    bound = stiffness_bound(pos, c, params, law=law, obstacles=obstacles)  # type: ignore[arg-type]
    # the bound holds (finite differences ~1e-6 relative) and is not vacuous (Gershgorin
    # on symmetric pair terms: within a factor ~10 here)
    assert rho <= bound * (1 + 1e-6)
    assert bound < 20.0 * rho
    f, b2 = formation_force_and_stiffness(pos, c, params, law=law, obstacles=obstacles)  # type: ignore[arg-type]
    np.testing.assert_array_equal(f, force(pos))
    assert b2 == bound


@pytest.mark.parametrize("n", [3, 4, 5])
def test_deliverable_law_equilibrium_radius_is_analytic(n: int) -> None:
    # On a regular N-gon of radius r the law of eqs. 6-8 is radial; it vanishes where
    # r (r^2 - alpha^2) = k_r sum_j 1 / (4 r^2 sin(pi j / N)): just outside the circle.
    alpha, k_r = 3.0, 10.0
    push = sum(1.0 / (4.0 * math.sin(math.pi * j / n)) for j in range(1, n))

    def residual(r: float) -> float:
        return r * (r * r - alpha * alpha) - k_r * push / (r * r)

    r_star = brentq(residual, alpha, 2 * alpha, xtol=1e-15)
    f = formation_force(_polygon(n, r_star), np.zeros(2), FormationParams(), law="deliverable")
    # brentq's root to 1e-15 m, times the radial stiffness 3 r^2 - alpha^2 ~ 20 N/m
    np.testing.assert_allclose(f, 0.0, atol=1e-12)
    assert r_star > alpha


def test_failed_robot_is_excluded_but_still_a_body() -> None:
    params = FormationParams()
    pos = _polygon(4, 3.0)
    alive = np.array([True, False, True, True])
    f = formation_force(pos, np.zeros(2), params, law="deliverable", active=alive)
    assert np.all(f[1] == 0.0)
    # robots 1, 3, 4 feel only each other: the same as the three alone
    alone = formation_force(pos[alive], np.zeros(2), params, law="deliverable")
    np.testing.assert_allclose(f[alive], alone, rtol=1e-13, atol=1e-13)
    # but a live robot touching the failed one is pushed off it (regular law's contact)
    close = pos.copy()
    close[0] = pos[1] + [0.35, 0.0]  # gap 0.05 m
    fr = formation_force(close, np.zeros(2), params, law="regular", active=alive)
    contact = contact_repulsion(close, radius_m=0.15, range_m=0.5, gain=0.05)
    assert contact[0, 0] > 100.0  # 0.05 (20 - 2) / 0.0025 = 360 N
    assert fr[0, 0] > 0.5 * contact[0, 0]


def test_pairwise_sums_never_hold_n_by_n_arrays() -> None:
    n = 5000
    pos = np.random.default_rng(2).uniform(-100, 100, (n, 2))
    tracemalloc.start()
    try:
        formation_force(pos, np.zeros(2), FormationParams(), law="regular")
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    # one N x N float64 array is 200 MB; the blocked sums hold a few (block, N) arrays
    # of 32,768 elements (256 kB each) and O(N) vectors: well under 16 MB
    assert peak < 16e6, peak


@pytest.mark.parametrize(
    ("call", "fragment"),
    [
        (lambda: coulomb_repulsion(np.zeros((3, 3))), "pos must have shape (N, 2)"),
        (lambda: coulomb_repulsion([[0.0, np.nan], [1.0, 1.0]]), "pos must be finite"),
        (lambda: coulomb_repulsion(np.zeros((3, 2)), charge=[1.0, 2.0]), "charge must have"),
        (lambda: circle_attraction(np.zeros((2, 2)), [0.0], alpha_m=1.0), "leader_xy"),
        (
            lambda: formation_force(np.zeros((2, 2)), [0, 0], FormationParams(), law="x"),  # type: ignore[arg-type]
            "law must be",
        ),
        (
            lambda: formation_force(np.zeros((2, 2)), [0, 0], FormationParams(), active=[1]),
            "active must have shape (2,)",
        ),
        (lambda: FormationParams(alpha_m=-1.0), "alpha_m must be > 0, got -1.0"),
        (lambda: FormationParams(k_r=math.nan), "k_r must be >= 0"),
        (lambda: FormationParams(attraction_limit_n=0.0), "attraction_limit_n must be > 0"),
        (lambda: coulomb_repulsion(np.zeros((2, 2)), block_elems=0), "block_elems"),
    ],
)
def test_bad_input_names_the_problem(call: object, fragment: str) -> None:
    with pytest.raises(InputError) as info:
        call()  # type: ignore[operator]
    assert fragment in str(info.value)
