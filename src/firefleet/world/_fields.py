"""Heat and smoke on the building's grid: diffusion, decay and sources through open cells.

Both fields obey one equation on the open (non-wall) cells,

    du/dt = kappa laplacian(u) - k (u - u_ambient) + s(x),

with no flux through walls (they insulate heat and stop smoke: the five-point Laplacian
counts only open neighbours) and the grid's edge closed too. It is written once
(:func:`diffuse_step`) and used by both:

* temperature [deg C]: burning cells are held at the flame temperature (a Dirichlet
  source), heat spreads with an effective diffusivity of the hot gas layer and cools
  towards the ambient temperature (Newton's law; walls, ceiling and ventilation);
* smoke density (optical density per metre, 1/m, so that the extinction over a path is
  ``exp(-integral of density)``, Beer-Lambert): produced by burning cells at a constant
  rate, spreading through open cells and doors, decaying (ventilation) towards 0.

The step is explicit (forward Euler), split into as many equal sub-steps as keep it
stable and accurate (``kappa dt / h^2 <= 0.2``, below the five-point scheme's limit
of 1/4, and ``k dt <= 0.02``).
Defaults: an effective diffusivity of 0.05 m^2/s (turbulent mixing of a room's hot layer,
orders above still air's 2e-5 m^2/s), cooling at 0.02 1/s (a 50 s time constant),
flame 800 deg C (the upper layer at flashover is 500-600 deg C, flames 800-1000),
smoke produced at 0.5 (1/m)/s per burning cell and cleared at 0.01 1/s.

References
----------
D. Drysdale, An Introduction to Fire Dynamics, 3rd ed., Wiley 2011 (flame and layer
temperatures, ch. 9-10; smoke optical density, ch. 11).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError, check_fields

__all__ = ["HEAT", "SMOKE", "FieldParams", "diffuse_step", "stable_substeps"]

_STABILITY = 0.2
"""Largest ``kappa dt / h^2`` of a sub-step (the explicit five-point scheme needs <= 1/4)."""
_DECAY_PER_SUBSTEP = 0.02
"""Largest ``k dt`` of a sub-step (Euler's ``1 - k dt`` is then within 2e-4 of ``exp(-k dt)``)."""


@dataclass(frozen=True)
class FieldParams:
    """The constants of one field.

    Attributes
    ----------
    diffusivity_m2_s : float
        Effective diffusivity kappa [m^2/s].
    decay_per_s : float
        Relaxation rate k towards ``ambient`` [1/s].
    ambient : float
        Value the field relaxes to, and holds in walls (deg C for heat, 0 for smoke).
    source : float
        At burning cells: the value they are held at (``pinned=True``: heat) or the
        production rate per second (``pinned=False``: smoke).
    pinned : bool
        Whether burning cells hold ``source`` (Dirichlet) or add it per second.
    """

    diffusivity_m2_s: float
    decay_per_s: float
    ambient: float
    source: float
    pinned: bool

    def __post_init__(self) -> None:
        check_fields(self, "field", non_negative=("diffusivity_m2_s", "decay_per_s"))
        if not (np.isfinite(self.ambient) and np.isfinite(self.source)):
            raise InputError("field: ambient and source must be finite numbers")


HEAT = FieldParams(diffusivity_m2_s=0.05, decay_per_s=0.02, ambient=20.0, source=800.0, pinned=True)
"""Temperature [deg C]: flame 800 deg C, ambient 20 deg C (module notes)."""

SMOKE = FieldParams(diffusivity_m2_s=0.05, decay_per_s=0.01, ambient=0.0, source=0.5, pinned=False)
"""Smoke optical density [1/m] (module notes)."""


def stable_substeps(params: FieldParams, dt_s: float, resolution_m: float) -> int:
    """How many equal explicit sub-steps keep a step of ``dt_s`` stable.

    Examples
    --------
    >>> from firefleet.world import HEAT, stable_substeps
    >>> stable_substeps(HEAT, dt_s=1.0, resolution_m=0.25)  # 0.05 * 1 / 0.0625 = 0.8 -> 4
    4
    """
    r = params.diffusivity_m2_s * dt_s / resolution_m**2
    decay = params.decay_per_s * dt_s
    return max(1, int(np.ceil(max(r / _STABILITY, decay / _DECAY_PER_SUBSTEP) - 1e-12)))


def diffuse_step(
    field: FloatArray,
    open_cells: ArrayLike,
    burning: ArrayLike,
    params: FieldParams,
    dt_s: float,
    resolution_m: float,
) -> FloatArray:
    """The field one step of ``dt_s`` later (module notes: the equation).

    Parameters
    ----------
    field : ndarray, shape (H, W)
        The field now (heat [deg C] or smoke [1/m]); walls hold ``params.ambient``.
    open_cells : array_like of bool, shape (H, W)
        Cells the field lives in (not walls).
    burning : array_like of bool, shape (H, W)
        Burning cells (the sources).
    params : FieldParams
    dt_s : float
        Step [s].
    resolution_m : float
        Cell side [m].

    Returns
    -------
    ndarray, shape (H, W)

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import FieldParams, diffuse_step
    >>> decay = FieldParams(diffusivity_m2_s=0.0, decay_per_s=0.1, ambient=0.0, source=0.0,
    ...                     pinned=False)
    >>> u = diffuse_step(np.ones((2, 2)), np.ones((2, 2), bool), np.zeros((2, 2), bool),
    ...                  decay, dt_s=1.0, resolution_m=1.0)
    >>> round(float(u[0, 0]), 6)  # 5 Euler sub-steps of exp(-0.1): (1 - 0.02)^5
    0.903921
    """
    u = np.asarray(field, dtype=float)
    open_m = np.asarray(open_cells, dtype=bool)
    fire = np.asarray(burning, dtype=bool)
    if u.ndim != 2 or open_m.shape != u.shape or fire.shape != u.shape:
        raise InputError(
            f"field {u.shape}, open cells {open_m.shape} and burning {fire.shape} must be "
            "the same (H, W)"
        )
    n = stable_substeps(params, dt_s, resolution_m)
    h = dt_s / n
    out: FloatArray = _diffuse(
        np.ascontiguousarray(u, dtype=np.float64),
        np.ascontiguousarray(open_m),
        np.ascontiguousarray(fire),
        n,
        params.diffusivity_m2_s * h / resolution_m**2,
        params.decay_per_s * h,
        float(params.ambient),
        bool(params.pinned),
        float(params.source),
        0.0 if params.pinned else params.source * h,
    )
    return out


@numba.njit(cache=True)
def _diffuse(
    field: FloatArray,
    open_m: np.ndarray,
    burning: np.ndarray,
    n: int,
    r: float,
    decay_h: float,
    ambient: float,
    pinned: bool,
    source: float,
    add: float,
) -> FloatArray:  # pragma: no cover - compiled
    """:func:`diffuse_step` after its checks, compiled: ``n`` explicit sub-steps of ``h``
    with ``r = D h / dx^2`` and ``decay_h = k h``. Per cell, the operations of the array
    form in its order: the field (walls at ambient, pinned sources at ``source``); each
    sub-step the open neighbours' values summed up, down, left, right (zeros off the
    grid, a wall's value times 0.0), ``u + r lap - decay_h (u - ambient)``, the source,
    walls back to ambient; bit for bit (tests/world/test_fields_kernel.py)."""
    h, w = field.shape
    u = np.empty((h, w))
    neighbours = np.empty((h, w))
    for i in range(h):
        for j in range(w):
            x = field[i, j] if open_m[i, j] else ambient
            if pinned and burning[i, j] and open_m[i, j]:
                x = source
            u[i, j] = x
            up = (1.0 if open_m[i - 1, j] else 0.0) if i > 0 else 0.0
            down = (1.0 if open_m[i + 1, j] else 0.0) if i < h - 1 else 0.0
            left = (1.0 if open_m[i, j - 1] else 0.0) if j > 0 else 0.0
            right = (1.0 if open_m[i, j + 1] else 0.0) if j < w - 1 else 0.0
            neighbours[i, j] = up + down + left + right
    new = np.empty((h, w))
    for _ in range(n):
        for i in range(h):
            for j in range(w):
                up = u[i - 1, j] * (1.0 if open_m[i - 1, j] else 0.0) if i > 0 else 0.0
                down = u[i + 1, j] * (1.0 if open_m[i + 1, j] else 0.0) if i < h - 1 else 0.0
                left = u[i, j - 1] * (1.0 if open_m[i, j - 1] else 0.0) if j > 0 else 0.0
                right = u[i, j + 1] * (1.0 if open_m[i, j + 1] else 0.0) if j < w - 1 else 0.0
                flux_in = up + down + left + right
                x = u[i, j]
                lap = flux_in - neighbours[i, j] * x
                y = x + r * lap - decay_h * (x - ambient)
                fire = burning[i, j] and open_m[i, j]
                if pinned:
                    if fire:
                        y = source
                else:
                    y = y + (add if fire else 0.0)
                new[i, j] = y if open_m[i, j] else ambient
        u, new = new, u
    return u
