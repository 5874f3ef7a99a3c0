"""The compiled sub-steps of ``diffuse_step`` equal the NumPy form, bit for bit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from firefleet.world import HEAT, SMOKE, FieldParams, diffuse_step
from firefleet.world._fields import stable_substeps
from firefleet.world._stencil import neighbour_sum


def _numpy(
    field: np.ndarray,
    open_m: np.ndarray,
    burning: np.ndarray,
    params: FieldParams,
    dt_s: float,
    res: float,
) -> np.ndarray:
    """diffuse_step as NumPy array operations (the form before the kernel)."""
    fire = burning & open_m
    n = stable_substeps(params, dt_s, res)
    h = dt_s / n
    r = params.diffusivity_m2_s * h / res**2
    openf = open_m.astype(float)
    neighbours = neighbour_sum(openf)
    u = np.where(open_m, field, params.ambient)
    if params.pinned:
        u = np.where(fire, params.source, u)
    add = 0.0 if params.pinned else params.source * h
    for _ in range(n):
        flux_in = neighbour_sum(u * openf)
        lap = flux_in - neighbours * u
        u = u + r * lap - params.decay_per_s * h * (u - params.ambient)
        u = np.where(fire, params.source, u) if params.pinned else u + np.where(fire, add, 0.0)
        u = np.where(open_m, u, params.ambient)
    return u


@pytest.mark.parametrize(
    ("params", "dt_s", "res"),
    [
        (HEAT, 0.1, 0.25),
        (SMOKE, 0.1, 0.25),
        (HEAT, 2.0, 0.1),  # several sub-steps
        (dataclasses.replace(SMOKE, pinned=True, source=3.0), 1.0, 0.2),
        (dataclasses.replace(HEAT, pinned=not HEAT.pinned), 0.5, 0.25),
    ],
)
def test_kernel_equals_numpy(params: FieldParams, dt_s: float, res: float) -> None:
    rng = np.random.default_rng(7)
    shape = (37, 53)
    open_m = rng.random(shape) > 0.2
    burning = rng.random(shape) > 0.9
    field = params.ambient + 300.0 * rng.random(shape) * (rng.random(shape) > 0.5)
    field[0, 0] = -0.0  # the sign of zero survives as the array form leaves it
    want = _numpy(field, open_m, burning, params, dt_s, res)
    got = diffuse_step(field, open_m, burning, params, dt_s, res)
    for _ in range(5):  # and over a few steps
        want = _numpy(want, open_m, burning, params, dt_s, res)
        got = diffuse_step(got, open_m, burning, params, dt_s, res)
    assert stable_substeps(params, dt_s, res) >= 1
    assert np.array_equal(got.view(np.int64), want.view(np.int64))
    assert not np.array_equal(got, field)
