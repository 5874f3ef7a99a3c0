"""The dynamic window's pruned obstacle search gives the brute-force search's commands
and clearances exactly (tests/control/_dwa_reference.py: every arc against every
obstacle), on random teams among random walls, range returns and teammates."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from firefleet.control.navigation._dwa import DwaParams, _dwa_batch

from ._dwa_reference import _dwa_batch as _dwa_batch_reference


def _args(params: DwaParams, dt_s: float) -> tuple[Any, ...]:
    return (
        dt_s,
        params.wheel_speed_max_m_s,
        params.wheel_accel_m_s2,
        params.axle_length_m,
        params.robot_radius_m,
        params.horizon_s,
        params.n_v,
        params.n_omega,
        params.n_steps,
        params.clearance_cap_m,
        params.clearance_weight,
    )


@pytest.mark.parametrize("seed", range(8))
def test_pruned_search_equals_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n, m = 6, int(rng.integers(1, 300))
    pose = np.c_[rng.uniform(0.0, 4.0, (n, 2)), rng.uniform(-np.pi, np.pi, n)]
    last = np.c_[rng.uniform(0.0, 0.7, n), rng.uniform(-2.0, 2.0, n)]
    ref = np.c_[rng.uniform(0.0, 0.7, n), rng.uniform(-3.0, 3.0, n)]
    obs = rng.uniform(-1.0, 5.0, (n, m, 2))
    obs[rng.random((n, m)) < 0.2] = 1e9  # padding
    rad = np.where(rng.random((n, m)) < 0.3, 0.15, rng.uniform(0.0, 0.18, (n, m)))
    params = DwaParams(n_v=5, n_omega=9, n_steps=8) if seed % 2 else DwaParams()
    got = _dwa_batch(pose, last, ref, obs, rad, *_args(params, 0.1))
    want = _dwa_batch_reference(pose, last, ref, obs, rad, *_args(params, 0.1))
    np.testing.assert_array_equal(got, want)
    assert np.isfinite(got[:, 2]).all()
