"""``summary.json``: per point, each claim's pass rate and each metric's spread over seeds."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from firefleet.sweep._grid import Point
from firefleet.sweep._table import column_roles
from firefleet.sweep._tasks import claim_key

if TYPE_CHECKING:
    import pyarrow as pa

__all__ = ["summarize"]


def _spread(values: list[float | None]) -> dict[str, Any]:
    """Mean, 5th and 95th percentiles (linear) of the finite values, and how many were not."""
    numbers = np.array([v for v in values if v is not None], dtype=np.float64)
    finite = numbers[np.isfinite(numbers)]
    if finite.size == 0:
        return {"n": 0, "not_finite": int(numbers.size), "mean": None, "p5": None, "p95": None}
    return {
        "n": int(finite.size),
        "not_finite": int(numbers.size - finite.size),
        "mean": float(finite.mean()),
        "p5": float(np.percentile(finite, 5)),
        "p95": float(np.percentile(finite, 95)),
        "min": float(finite.min()),
        "max": float(finite.max()),
    }


def summarize(table: pa.Table, points: Sequence[Point]) -> dict[str, Any]:
    """The sweep's summary: one entry per point, in point order.

    Each entry: ``point``, ``values`` (the swept keys as typed), ``runs``, ``failed``,
    ``claims`` (:func:`~firefleet.sweep.claim_key` -> ``passed``, ``of`` (finished
    runs), ``pass_rate``, ``expected``)
    and ``metrics`` (name -> ``mean``, ``p5``, ``p95``, ``min``, ``max`` over the finite
    values, ``n`` of them and ``not_finite``, such as a settling time never reached).

    Examples
    --------
    >>> from firefleet import load_scenario
    >>> from firefleet.sweep import build_table, points_of, run_batch, summarize
    >>> points = points_of(load_scenario("motor-pid"), [])
    >>> table = build_table(points, run_batch(points[0].scenario, 0, [0, 1]), "motor-pid")
    >>> entry = summarize(table, points)["points"][0]
    >>> entry["runs"], entry["claims"]["rise_time_s < 0.2"]["pass_rate"]
    (2, 1.0)
    """
    roles = column_roles(table)
    data = table.to_pydict()
    entries = []
    for point in points:
        mine = [i for i, p in enumerate(data["point"]) if p == point.index]
        ok = [i for i in mine if data["error"][i] is None]
        claims = {}
        for claim in point.scenario.claims:
            column = data.get(f"claim:{claim_key(claim)}", [])
            passed = sum(bool(column[i]) for i in ok)
            claims[claim_key(claim)] = {
                "expected": claim.expected,
                "passed": passed,
                "of": len(ok),
                "pass_rate": passed / len(ok) if ok else math.nan,
            }
        metrics = {name: _spread([data[name][i] for i in ok]) for name in roles["metrics"]}
        entries.append(
            {
                "point": point.index,
                "values": dict(point.labels),
                "runs": len(mine),
                "failed": len(mine) - len(ok),
                "claims": claims,
                "metrics": metrics,
            }
        )
    return {
        "scenario": roles["scenario"],
        "params": roles["params"],
        "seeds": sorted(set(data["seed"])),
        "runs": table.num_rows,
        "failed": sum(e is not None for e in data["error"]),
        "points": entries,
    }
