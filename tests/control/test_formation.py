"""Formation forces (eqs. 6-8, the regular law) against hand-computed cases and loops."""

from __future__ import annotations

import math
import tracemalloc

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
    obstacle_repulsion,
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


def test_regular_polygon_on_the_circle_is_an_equilibrium_of_the_regular_law() -> None:
    params = FormationParams(alpha_m=3.0)
    c = np.array([2.0, 1.0])
    for n in (3, 4, 5, 8):
        f = formation_force(_polygon(n, 3.0, (2.0, 1.0)), c, params, law="regular")
        # attraction 0 on the circle, equal angular gaps, contact out of
        # range (sides >= 2.3 m): rounding of forces of order 1 N
        np.testing.assert_allclose(f, 0.0, atol=1e-12)


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
