"""Fire on the building's grid: a stochastic cellular automaton (Alexandridis et al. 2008).

Each cell is unburnt (0), burning (1) or burnt out (2). A burning cell ignites each of
its eight neighbours independently; a cell with burning neighbours ``j`` ignites during
a step of ``dt`` seconds with probability

    p = 1 - prod_j (1 - p_j),    p_j = 1 - exp(-lambda_j dt),
    lambda_j = lambda_0 (1 + p_fuel) / d_j,

the ignition law of Alexandridis et al., ``p_burn = p_h (1 + p_veg)(1 + p_den) p_w p_s``,
written as a hazard rate so that the step ``dt`` is free: the fuel factor ``(1 + p_fuel)``
takes the place of the vegetation and density factors, the wind and slope factors are 1
indoors (no wind, a flat floor), and ``d_j`` is the neighbour's distance in cells (1 for
the four edge neighbours, sqrt(2) for the diagonal ones: the fire crosses a diagonal at
the speed it crosses an edge, which makes the spread nearly isotropic, where the same
probability for all eight makes it square). Drawing one uniform number per cell against
``p`` is the same distribution as one draw per burning neighbour, and needs one array.

``lambda_0`` follows from the front speed in a corridor one cell wide, where the front
waits for one neighbour at a time: an exponential waiting time of mean ``1 / lambda_0``
per cell of side ``h``, so ``lambda_0 = spread_m_s / h`` (in steps of ``dt``: a geometric
number of steps of mean ``1 / p``, truncated at the burn duration; see
:func:`corridor_front_speed`).

A cell burns for ``burn_s_per_fuel * fuel`` seconds, then is burnt out. Cells with no
fuel (walls) never burn; doors are free cells and burn as the floor does.

Defaults: ``spread_m_s = 0.01`` (1 cm/s: an unfought fire in uniform furnishings grows to
a room's size, about 5 m, in 8 to 10 minutes, the "medium" t-squared growth of NFPA 72
whose fire reaches 1 MW in 300 s, when the heat release scales with the burning area
of about 250 kW/m^2 for furniture) and ``burn_s_per_fuel = 300`` (a furnished cell burns
for five minutes at a relative fuel load of 1: the burning time of upholstered furniture
and wood cribs in Babrauskas' data, a few minutes to ten).

References
----------
A. Alexandridis, D. Vakalis, C. I. Siettos, G. V. Bafas, "A cellular automata model for
forest fire spread prediction: the case of the wildfire that swept through Spetses
Island in 1990", Applied Mathematics and Computation 204(1), 2008, 191-201.
NFPA 72, National Fire Alarm and Signaling Code, Annex B (t-squared fires).
V. Babrauskas, "Heat release rates", SFPE Handbook of Fire Protection Engineering.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import BoolArray, FloatArray
from firefleet.errors import InputError, check_fields
from firefleet.world._fire_kernel import advance, candidates

__all__ = [
    "BURNING",
    "BURNT",
    "UNBURNT",
    "FireParams",
    "FireState",
    "corridor_front_speed",
    "fire_init",
    "fire_step",
]

MAX_RATE_STEP = 0.4
"""Largest ``lambda_0 dt`` a step may take: the front is round within 5 % up to it
(diagonal over axial radius 1.04 measured at 0.4, 1.14 at 1.0)."""

UNBURNT = 0
BURNING = 1
BURNT = 2


@dataclass(frozen=True)
class FireParams:
    """The fire automaton's constants.

    Attributes
    ----------
    spread_m_s : float
        Front speed in a one-cell corridor of relative fuel load 1 without burn-out
        [m/s] (sets the ignition rate ``lambda_0 = spread_m_s / cell side``).
    burn_s_per_fuel : float
        Burning time of a cell per unit of relative fuel load [s].
    fuel_factor : float
        ``p_fuel`` of the ignition rate's ``(1 + p_fuel)`` factor for cells whose fuel
        load is 1; it scales as ``p_fuel * (fuel - 1)`` clipped to [-0.9, 1] for other
        loads (Alexandridis' density factor: -0.4 sparse, 0 normal, 0.3 dense). 0: the
        load changes how long a cell burns, not how fast it catches.
    """

    spread_m_s: float = 0.01
    burn_s_per_fuel: float = 300.0
    fuel_factor: float = 0.3

    def __post_init__(self) -> None:
        check_fields(self, "fire", positive=("spread_m_s", "burn_s_per_fuel"))
        check_fields(self, "fire", non_negative=("fuel_factor",))


@dataclass(frozen=True)
class FireState:
    """The fire at one instant.

    Attributes
    ----------
    state : ndarray of int8, shape (H, W)
        ``UNBURNT``, ``BURNING`` or ``BURNT`` per cell (row 0 at the map's top).
    burn_left_s : ndarray, shape (H, W)
        Time each burning cell has left [s] (its whole burning time before it ignites).
    fuel : ndarray, shape (H, W)
        Relative fuel load (0 for walls: they never burn).
    """

    state: np.ndarray
    burn_left_s: FloatArray
    fuel: FloatArray

    @property
    def burning(self) -> BoolArray:
        """Cells burning now, (H, W)."""
        return np.asarray(self.state == BURNING)

    @property
    def burned(self) -> BoolArray:
        """Cells burning or burnt out, (H, W)."""
        return np.asarray(self.state != UNBURNT)


def fire_init(fuel: ArrayLike, ignite: ArrayLike, params: FireParams) -> FireState:
    """The fire before its first step: ``ignite``'s cells burning, the rest unburnt.

    Parameters
    ----------
    fuel : array_like, shape (H, W)
        Relative fuel load per cell, >= 0 (0: walls and other incombustible cells).
    ignite : array_like of bool, shape (H, W)
        Cells set burning now; each must hold fuel.
    params : FireParams

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import FireParams, fire_init
    >>> fuel = np.ones((3, 3)); ignite = np.zeros((3, 3), dtype=bool); ignite[1, 1] = True
    >>> fire = fire_init(fuel, ignite, FireParams())
    >>> int(fire.burning.sum()), float(fire.burn_left_s[1, 1])
    (1, 300.0)
    """
    fuel_a = np.asarray(fuel, dtype=float)
    ignite_a = np.asarray(ignite, dtype=bool)
    if fuel_a.ndim != 2 or ignite_a.shape != fuel_a.shape:
        raise InputError(
            f"fire: fuel {fuel_a.shape} and ignite {ignite_a.shape} must be the same (H, W)"
        )
    if not np.all(np.isfinite(fuel_a)) or np.any(fuel_a < 0.0):
        raise InputError("fire: fuel loads must be finite and >= 0")
    if np.any(ignite_a & (fuel_a <= 0.0)):
        r, c = np.argwhere(ignite_a & (fuel_a <= 0.0))[0]
        raise InputError(f"fire: cannot ignite cell (row {r}, col {c}): it holds no fuel (a wall)")
    state = np.where(ignite_a, BURNING, UNBURNT).astype(np.int8)
    burn_left = np.where(ignite_a, params.burn_s_per_fuel * fuel_a, 0.0)
    return FireState(state=state, burn_left_s=burn_left, fuel=fuel_a)


_DIAGONAL = 1.0 / np.sqrt(2.0)


def fire_step(
    fire: FireState,
    params: FireParams,
    dt_s: float,
    resolution_m: float,
    *,
    rng: np.random.Generator,
) -> FireState:
    """The fire one step of ``dt_s`` later (module notes: the ignition law).

    Parameters
    ----------
    fire : FireState
    params : FireParams
    dt_s : float
        Step [s].
    resolution_m : float
        Cell side [m].
    rng : numpy.random.Generator
        One uniform draw per cell per step.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import FireParams, fire_init, fire_step
    >>> fuel = np.ones((1, 5)); ignite = np.zeros((1, 5), dtype=bool); ignite[0, 0] = True
    >>> params = FireParams(spread_m_s=0.01, burn_s_per_fuel=1e3)
    >>> fire = fire_init(fuel, ignite, params)
    >>> rng = np.random.default_rng(0)
    >>> for _ in range(60):  # 60 s: the front crosses a 5 cm cell in 5 s on average
    ...     fire = fire_step(fire, params, 1.0, 0.05, rng=rng)
    >>> fire.state.tolist()
    [[1, 1, 1, 1, 1]]
    """
    if not (dt_s > 0.0 and resolution_m > 0.0):
        raise InputError(f"fire step: dt_s {dt_s} and resolution_m {resolution_m} must be > 0")
    rate0_hz = params.spread_m_s / resolution_m
    if rate0_hz * dt_s > MAX_RATE_STEP + 1e-12:
        raise InputError(
            f"fire step: dt_s {dt_s:g} is too long for cells of {resolution_m:g} m at "
            f"spread_m_s {params.spread_m_s:g}: at most {MAX_RATE_STEP / rate0_hz:g} s "
            "(a longer step makes the front square, not round)"
        )
    state0 = np.ascontiguousarray(fire.state)
    fuel = np.ascontiguousarray(fire.fuel, dtype=np.float64)
    # only an unburnt cell with fuel and a burning neighbour can ignite (elsewhere the
    # probability is 0): the law on those cells alone, element by element the same
    # (the neighbour sums and the state update: compiled passes, ``_fire_kernel``)
    cand, near = candidates(state0, fuel, _DIAGONAL)
    u = rng.random(fire.state.shape)
    # log of the probability that no burning neighbour ignites the cell this step
    log_no = -rate0_hz * dt_s * near
    factor = 1.0 + np.clip(params.fuel_factor * (fuel.ravel()[cand] - 1.0), -0.9, 1.0)
    p_ignite = -np.expm1(log_no * factor)
    ignites = cand[u.ravel()[cand] < p_ignite]
    state, burn_left = advance(
        state0,
        np.ascontiguousarray(fire.burn_left_s, dtype=np.float64),
        fuel,
        ignites,
        float(dt_s),
        float(params.burn_s_per_fuel),
    )
    return FireState(state=state, burn_left_s=burn_left, fuel=fire.fuel)


def corridor_front_speed(
    params: FireParams, dt_s: float, resolution_m: float
) -> tuple[float, float]:
    """The front's mean speed in a one-cell corridor of fuel load 1, and the probability
    that it crosses a cell before the cell behind it burns out.

    In a corridor the front cell ignites its one unburnt neighbour with probability
    ``p = 1 - exp(-lambda_0 dt)`` per step for the ``D = ceil(burn / dt)`` steps it burns
    (it ignited at the end of a step and burns from the next), so the wait is geometric,
    truncated at ``D``: crossing probability ``q = 1 - (1 - p)^D`` and mean wait
    ``E[T | T <= D] = (sum_{k=1..D} k p (1-p)^(k-1)) / q`` steps.

    Returns
    -------
    speed_m_s : float
        ``h / (E[T | T <= D] dt)`` [m/s].
    crossing_probability : float
        ``q``.

    Examples
    --------
    >>> from firefleet.world import FireParams, corridor_front_speed
    >>> speed, q = corridor_front_speed(FireParams(spread_m_s=0.01), dt_s=0.1, resolution_m=0.05)
    >>> round(speed, 6), round(q, 9)  # h (1 - exp(-lambda_0 dt)) / dt; burn-out never stops it
    (0.009901, 1.0)
    """
    p = -np.expm1(-params.spread_m_s / resolution_m * dt_s)
    d = int(np.ceil(params.burn_s_per_fuel / dt_s - 1e-9))
    k = np.arange(1, d + 1)
    pk = p * (1.0 - p) ** (k - 1)
    q = float(pk.sum())
    mean_steps = float((k * pk).sum() / q)
    return resolution_m / (mean_steps * dt_s), q
