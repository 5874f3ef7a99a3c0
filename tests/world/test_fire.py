"""The fire automaton against its analytic rates: corridor front speed and crossing
probability, isotropy in uniform fuel, walls, burn-out."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.world import (
    BURNING,
    BURNT,
    UNBURNT,
    FireParams,
    corridor_front_speed,
    fire_init,
    fire_step,
)

H_M = 0.05


def _corridors(n: int, length: int) -> np.ndarray:
    """``n`` one-cell corridors of ``length`` cells, separated by wall rows."""
    fuel = np.zeros((2 * n - 1, length))
    fuel[::2] = 1.0
    return fuel


def test_corridor_front_speed_matches_the_geometric_wait() -> None:
    params = FireParams(spread_m_s=0.01, burn_s_per_fuel=1e6)  # no burn-out
    dt_s, n, length = 1.0, 150, 41
    fuel = _corridors(n, length)
    ignite = np.zeros_like(fuel, dtype=bool)
    ignite[::2, 0] = True
    fire = fire_init(fuel, ignite, params)
    rng = np.random.default_rng(7)
    arrival = np.full(n, -1)
    for k in range(1, 2000):
        fire = fire_step(fire, params, dt_s, H_M, rng=rng)
        reached = (fire.state[::2, -1] != UNBURNT) & (arrival < 0)
        arrival[reached] = k
        if np.all(arrival > 0):
            break
    assert np.all(arrival > 0)
    p = -np.expm1(-params.spread_m_s / H_M * dt_s)
    cells = length - 1
    # the arrival time is a sum of `cells` geometric waits: mean cells / p, var cells (1-p)/p^2
    mean, sd = cells / p, np.sqrt(cells * (1 - p)) / p
    assert abs(arrival.mean() - mean) < 4.0 * sd / np.sqrt(n)
    speed, q = corridor_front_speed(params, dt_s, H_M)
    assert q == pytest.approx(1.0)
    assert speed == pytest.approx(H_M * p / dt_s, rel=1e-12)


def test_corridor_burn_out_stops_the_front_at_the_truncated_geometric_rate() -> None:
    params = FireParams(spread_m_s=0.01, burn_s_per_fuel=3.0)  # each cell burns 3 steps
    dt_s, n, length = 1.0, 400, 30
    fuel = _corridors(n, length)
    ignite = np.zeros_like(fuel, dtype=bool)
    ignite[::2, 0] = True
    fire = fire_init(fuel, ignite, params)
    rng = np.random.default_rng(3)
    for _ in range(200):
        fire = fire_step(fire, params, dt_s, H_M, rng=rng)
    assert not fire.burning.any()  # every corridor's fire has died
    crossings = (fire.state[::2] == BURNT).sum(axis=1) - 1
    _, q = corridor_front_speed(params, dt_s, H_M)
    p = -np.expm1(-0.2)
    assert q == pytest.approx(1 - (1 - p) ** 3, rel=1e-12)
    # crossings before the first failure: geometric, mean q / (1 - q), var q / (1 - q)^2
    mean, sd = q / (1 - q), np.sqrt(q) / (1 - q)
    assert np.all(crossings < length - 1)
    assert abs(crossings.mean() - mean) < 4.0 * sd / np.sqrt(n)


def _diagonal_over_axis(dt_s: float, seeds: int = 4) -> float:
    """Mean burned radius along the diagonals over that along the axes, from one cell."""
    n = 161
    c = n // 2
    k = np.arange(c + 1)
    axis, diag = [], []
    params = FireParams(spread_m_s=0.01, burn_s_per_fuel=1e6)
    for seed in range(seeds):
        ignite = np.zeros((n, n), dtype=bool)
        ignite[c, c] = True
        fire = fire_init(np.ones((n, n)), ignite, params)
        rng = np.random.default_rng(seed)
        while (fire.state[c, :] == UNBURNT).sum() > 40:  # until the radius is ~60 cells
            fire = fire_step(fire, params, dt_s, H_M, rng=rng)
        b = fire.burned
        rays = [b[c, c:], b[c, c::-1], b[c:, c], b[c::-1, c]]
        axis.append(np.mean([k[ray].max() for ray in rays]))
        rays = [b[c + k, c + k], b[c - k, c - k], b[c + k, c - k], b[c - k, c + k]]
        diag.append(np.sqrt(2.0) * np.mean([k[ray].max() for ray in rays]))
    return float(np.mean(diag) / np.mean(axis))


@pytest.mark.parametrize("dt_s", [0.25, 2.0])  # lambda_0 dt = 0.05 and 0.4 (the largest allowed)
def test_spread_in_uniform_fuel_is_isotropic_within_five_percent(dt_s: float) -> None:
    assert _diagonal_over_axis(dt_s) == pytest.approx(1.0, abs=0.05)


def test_a_step_too_long_for_an_isotropic_front_is_refused() -> None:
    fire = fire_init(np.ones((3, 3)), np.eye(3, dtype=bool), FireParams())
    with pytest.raises(InputError, match=r"dt_s 2.5 .* at most 2 s"):
        fire_step(fire, FireParams(), 2.5, H_M, rng=np.random.default_rng(0))


def test_walls_stop_the_fire_and_a_door_lets_it_through() -> None:
    params = FireParams(spread_m_s=0.02, burn_s_per_fuel=60.0)
    fuel = np.ones((20, 41))
    fuel[:, 20] = 0.0  # a wall down the middle
    ignite = np.zeros_like(fuel, dtype=bool)
    ignite[10, 5] = True
    for door, expect_right in ((False, False), (True, True)):
        f = fuel.copy()
        if door:
            f[9:11, 20] = 1.0  # two cells of door (0.1 m at 0.05 m: cells, not metres here)
        fire = fire_init(f, ignite, params)
        rng = np.random.default_rng(1)
        for _ in range(600):
            fire = fire_step(fire, params, 1.0, H_M, rng=rng)
        assert fire.state[:, 20][f[:, 20] == 0].tolist() == [UNBURNT] * int((f[:, 20] == 0).sum())
        assert bool(fire.burned[:, 21:].any()) is expect_right
        assert fire.burned[:, :20].sum() == 20 * 20  # its own room burns whole


def test_fuel_runs_out_after_its_burning_time() -> None:
    params = FireParams(spread_m_s=0.01, burn_s_per_fuel=10.0)
    fuel = np.zeros((3, 3))
    fuel[1, 1] = 2.5  # alone: burns 25 s, then out
    ignite = fuel > 0
    fire = fire_init(fuel, ignite, params)
    rng = np.random.default_rng(0)
    states = []
    for _ in range(30):
        fire = fire_step(fire, params, 1.0, H_M, rng=rng)
        states.append(int(fire.state[1, 1]))
    assert states.index(BURNT) == 24  # burning during steps 1..25, out at the end of the 25th
    assert states[:24] == [BURNING] * 24
    assert fire.state[fuel == 0].max() == UNBURNT


def test_fire_is_reproducible_from_its_seed() -> None:
    params = FireParams()
    fuel = np.ones((30, 30))
    ignite = np.zeros_like(fuel, dtype=bool)
    ignite[15, 15] = True
    runs = []
    for _ in range(2):
        fire = fire_init(fuel, ignite, params)
        rng = np.random.default_rng(11)
        for _ in range(50):
            fire = fire_step(fire, params, 1.0, 0.05, rng=rng)
        runs.append(fire.state)
    np.testing.assert_array_equal(runs[0], runs[1])


def test_bad_fire_input_names_what_is_wrong() -> None:
    fuel = np.ones((3, 3))
    fuel[0, 0] = 0.0
    ignite = np.zeros((3, 3), dtype=bool)
    ignite[0, 0] = True
    with pytest.raises(InputError, match=r"cannot ignite cell \(row 0, col 0\)"):
        fire_init(fuel, ignite, FireParams())
    with pytest.raises(InputError, match="spread_m_s"):
        FireParams(spread_m_s=0.0)
    with pytest.raises(InputError, match="same"):
        fire_init(fuel, ignite[:2], FireParams())
    with pytest.raises(InputError, match="fuel"):
        fire_init(-fuel, np.zeros((3, 3), bool), FireParams())
