"""Heat and smoke against the diffusion equation's analytic cases: the variance of a
spreading point, conservation behind walls, the steady profile of a held source, decay
and the smoke mass balance."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.world import HEAT, SMOKE, FieldParams, diffuse_step, stable_substeps


def _plain(
    kappa: float, decay: float = 0.0, source: float = 0.0, pinned: bool = False
) -> FieldParams:
    return FieldParams(
        diffusivity_m2_s=kappa, decay_per_s=decay, ambient=0.0, source=source, pinned=pinned
    )


def test_a_point_spreads_with_variance_two_kappa_t_per_axis() -> None:
    n, h, kappa, dt = 101, 0.1, 0.05, 1.0
    u = np.zeros((n, n))
    u[50, 50] = 1.0
    open_cells = np.ones((n, n), dtype=bool)
    none = np.zeros((n, n), dtype=bool)
    for _ in range(10):
        u = diffuse_step(u, open_cells, none, _plain(kappa), dt, h)
    x = (np.arange(n) - 50) * h
    mass = u.sum()
    var_x = float((u.sum(axis=0) * x**2).sum() / mass)
    var_y = float((u.sum(axis=1) * x**2).sum() / mass)
    # the explicit scheme's random walk adds exactly 2 kappa dt per axis per step
    assert mass == pytest.approx(1.0, abs=1e-12)
    assert var_x == pytest.approx(2 * kappa * 10.0, rel=1e-5)  # the edge, 5 sigma away
    assert var_y == pytest.approx(2 * kappa * 10.0, rel=1e-5)


def test_walls_insulate_and_a_closed_room_conserves_its_heat() -> None:
    n, h = 30, 0.25
    open_cells = np.ones((n, 2 * n + 1), dtype=bool)
    open_cells[:, n] = False  # a wall between two rooms
    u = np.zeros(open_cells.shape)
    u[5:10, 5:10] = 100.0
    none = np.zeros_like(open_cells)
    for _ in range(200):
        u = diffuse_step(u, open_cells, none, _plain(0.05), 20.0, h)  # 4,000 s
    assert u[:, :n].sum() == pytest.approx(2500.0, rel=1e-12)
    assert np.all(u[:, n:] == 0.0)  # not a trace through the wall
    assert u[:, :n].max() - u[:, :n].min() < 0.5  # and spread over its room (mean 2.78)


def test_a_held_source_in_a_corridor_decays_as_the_discrete_exponential() -> None:
    length, h, kappa, k = 200, 0.1, 0.05, 0.02
    open_cells = np.ones((1, length), dtype=bool)
    burning = np.zeros_like(open_cells)
    burning[0, 0] = True
    params = FieldParams(
        diffusivity_m2_s=kappa, decay_per_s=k, ambient=20.0, source=820.0, pinned=True
    )
    u = np.full((1, length), 20.0)
    for _ in range(25):
        u = diffuse_step(u, open_cells, burning, params, 60.0, h)  # 25 min: steady
    # steady state of kappa/h^2 (u[i-1] - 2u[i] + u[i+1]) = k (u[i] - 20): u - 20 = 800 r^i
    a = 2.0 + k * h**2 / kappa
    r = (a - np.sqrt(a * a - 4.0)) / 2.0
    i = np.arange(length)
    np.testing.assert_allclose(u[0, :60], 20.0 + 800.0 * r ** i[:60], rtol=1e-6)
    # which is the continuous exp(-x sqrt(k / kappa)) to the grid's accuracy
    np.testing.assert_allclose(
        u[0, :60], 20.0 + 800.0 * np.exp(-i[:60] * h * np.sqrt(k / kappa)), rtol=2e-3 * 60
    )


def test_decay_and_the_smoke_mass_balance() -> None:
    n = 20
    open_cells = np.ones((n, n), dtype=bool)
    burning = np.zeros_like(open_cells)
    burning[3:5, 3:5] = True  # four cells making smoke
    u = np.zeros((n, n))
    times = np.arange(1, 301)
    mass = []
    for _ in times:
        u = diffuse_step(u, open_cells, burning, SMOKE, 1.0, 0.25)
        mass.append(u.sum())
    # dM/dt = q N - mu M: M = q N / mu (1 - exp(-mu t)); Euler sub-steps within 1 %
    expected = SMOKE.source * 4 / SMOKE.decay_per_s * -np.expm1(-SMOKE.decay_per_s * times)
    np.testing.assert_allclose(mass, expected, rtol=1e-2)
    cool = diffuse_step(
        np.full((2, 2), 120.0), np.ones((2, 2), bool), np.zeros((2, 2), bool), HEAT, 30.0, 0.25
    )
    assert cool[0, 0] == pytest.approx(20.0 + 100.0 * np.exp(-HEAT.decay_per_s * 30.0), rel=2e-3)


def test_substeps_keep_the_explicit_scheme_stable() -> None:
    assert stable_substeps(HEAT, dt_s=1.0, resolution_m=0.05) == 100  # 0.05/0.0025/0.2
    u = np.zeros((40, 40))
    u[20, 20] = 1e6
    out = diffuse_step(
        u, np.ones((40, 40), bool), np.zeros((40, 40), bool), _plain(0.05), 10.0, 0.05
    )
    assert out.min() >= 0.0  # no checkerboard oscillation from too long a step


def test_bad_field_input_names_what_is_wrong() -> None:
    with pytest.raises(InputError, match="same"):
        diffuse_step(
            np.zeros((3, 3)), np.ones((3, 2), bool), np.zeros((3, 3), bool), HEAT, 1.0, 0.1
        )
    with pytest.raises(InputError, match="diffusivity_m2_s"):
        _plain(-1.0)
