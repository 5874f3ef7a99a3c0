"""Metrics of a run: step-response figures and the scenario's named numbers."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet.errors import InputError, as_float_array
from firefleet.scenarios.schema import Claim
from firefleet.sim.registry import Metrics, task_kind
from firefleet.sim.result import SimResult

__all__ = [
    "Metrics",
    "compute_metrics",
    "metrics_document",
    "recovery_time",
    "settling_time",
    "step_response_info",
]


def _crossing(t: NDArray[np.float64], y: NDArray[np.float64], i: int, level: float) -> float:
    """Time at which y crosses ``level`` between samples i - 1 and i (linear)."""
    if i == 0 or y[i] == y[i - 1]:
        return float(t[i])
    return float(t[i - 1] + (level - y[i - 1]) * (t[i] - t[i - 1]) / (y[i] - y[i - 1]))


def settling_time(
    t_s: ArrayLike, y: ArrayLike, target: float, *, band: float = 0.02, t0_s: float = 0.0
) -> float:
    """Time from ``t0_s`` until ``y`` enters ``|y - target| <= band |target|`` for good.

    Parameters
    ----------
    t_s, y : array_like, shape (T,)
        Samples, from ``t0_s`` on.
    target : float
        The final value.
    band : float
        Relative half-width of the band (0.02 for the 2 % band).
    t0_s : float
        Start of the count [s].

    Returns
    -------
    float
        Seconds (0 if never outside, ``inf`` if still outside at the end), with the
        last exit interpolated linearly between samples.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.metrics import settling_time
    >>> t = np.linspace(0.0, 5.0, 50001)
    >>> # first order, tau = 1 s: the 2 % band at tau ln(50)
    >>> round(settling_time(t, 1.0 - np.exp(-t), 1.0), 4), round(float(np.log(50.0)), 4)
    (3.912, 3.912)
    """
    t = as_float_array(t_s, "t_s", (None,))
    yy = as_float_array(y, "y", (t.shape[0],))
    if t.size == 0:
        raise InputError("settling_time needs at least one sample")
    half = band * abs(target)
    outside = np.abs(yy - target) > half
    if not outside.any():
        return 0.0
    last = int(np.nonzero(outside)[0][-1])
    if last == t.size - 1:
        return math.inf
    # interpolate where |y - target| comes back to the band edge on the exit side
    edge = target + half if yy[last] > target else target - half
    return _crossing(t, yy, last + 1, edge) - t0_s


def recovery_time(
    t_s: ArrayLike, y: ArrayLike, target: float, t_event_s: float, *, band: float = 0.02
) -> float:
    """Time from an event (a load step) until ``y`` is back inside the band for good.

    Only samples at or after ``t_event_s`` count. Returns 0 if ``y`` never leaves the
    band, ``inf`` if it has not come back by the end.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.metrics import recovery_time
    >>> t = np.linspace(0.0, 5.0, 50001)
    >>> y = np.where(t < 1.0, 1.0, 1.0 - 0.5 * np.exp(-(t - 1.0)))  # a dip at 1 s, tau = 1 s
    >>> round(recovery_time(t, y, 1.0, 1.0), 4), round(float(np.log(25.0)), 4)
    (3.2189, 3.2189)
    """
    t = as_float_array(t_s, "t_s", (None,))
    yy = as_float_array(y, "y", (t.shape[0],))
    after = t >= t_event_s - 1e-12
    if not after.any():
        raise InputError(f"no sample at or after the event time {t_event_s} s")
    return settling_time(t[after], yy[after], target, band=band, t0_s=t_event_s)


def step_response_info(
    t_s: ArrayLike, y: ArrayLike, target: float, *, t0_s: float = 0.0, band: float = 0.02
) -> dict[str, float]:
    """Rise time (10-90 %), settling time (band), overshoot of a step response.

    Parameters
    ----------
    t_s, y : array_like, shape (T,)
        The response from the step on (``t_s[0] >= t0_s``), starting from 0.
    target : float
        The step's final value (> 0 or < 0).
    t0_s : float
        Time of the step [s].
    band : float
        Relative half-width of the settling band.

    Returns
    -------
    dict
        ``rise_time_s`` (``inf`` if 90 % is never reached), ``settling_time_s``,
        ``overshoot_pct`` (peak beyond the target, percent of the target, >= 0).
        Crossings are interpolated linearly between samples.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.metrics import step_response_info
    >>> t = np.linspace(0.0, 5.0, 50001)
    >>> info = step_response_info(t, 2.0 * (1.0 - np.exp(-t)), 2.0)
    >>> round(info["rise_time_s"], 4), round(float(np.log(9.0)), 4), info["overshoot_pct"]
    (2.1972, 2.1972, 0.0)
    """
    t = as_float_array(t_s, "t_s", (None,))
    yy = as_float_array(y, "y", (t.shape[0],))
    if target == 0:
        raise InputError("step_response_info needs a non-zero target")
    s = yy / target  # normalised: rises from 0 to 1
    rise = math.inf
    above10 = np.nonzero(s >= 0.1)[0]
    above90 = np.nonzero(s >= 0.9)[0]
    if above90.size:
        t10 = _crossing(t, s, int(above10[0]), 0.1)
        t90 = _crossing(t, s, int(above90[0]), 0.9)
        rise = t90 - t10
    return {
        "rise_time_s": rise,
        "settling_time_s": settling_time(t, yy, target, band=band, t0_s=t0_s),
        "overshoot_pct": max(0.0, float(s.max()) - 1.0) * 100.0,
    }


def compute_metrics(result: SimResult) -> Metrics:
    """The scenario's metrics from a run: those its task kind declares.

    The names are ``result.scenario.metric_names``
    (:attr:`firefleet.sim.registry.TaskKind.metric_names`).

    Examples
    --------
    >>> import firefleet
    >>> result = firefleet.simulate(firefleet.load_scenario("motor-open-loop"), record_every=100)
    >>> sorted(firefleet.compute_metrics(result)) == sorted(result.scenario.metric_names)
    True
    """
    return task_kind(result.scenario.command.kind).metrics(result)


def metrics_document(
    scenario_name: str, claims: tuple[Claim, ...], metrics: Metrics
) -> dict[str, Any]:
    """The ``metrics.json`` object: scenario name, checked claims, and the metrics.

    Each claim is ``{"name", "expected", "measured", "passed", "source"}``; ``name`` is
    the metric, with ``[robot k]`` for a claim on one robot of a per-robot metric.

    Examples
    --------
    >>> from firefleet.scenarios import Claim
    >>> from firefleet.sim.metrics import metrics_document
    >>> claim = Claim(metric="rise_time_s", op="<=", value=0.2)
    >>> doc = metrics_document("demo", (claim,), {"rise_time_s": 0.1})
    >>> doc["scenario"], doc["claims"][0]["passed"], doc["rise_time_s"]
    ('demo', True, 0.1)
    """
    checked = [
        {
            "name": claim.label,
            "expected": claim.expected,
            "measured": claim.select(metrics.get(claim.metric)),
            "passed": claim.holds(metrics.get(claim.metric)),
            "source": claim.source,
        }
        for claim in claims
    ]
    return {"scenario": scenario_name, "claims": checked, **metrics}
