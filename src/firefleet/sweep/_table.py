"""The sweep's table: one row per run, as a pyarrow Table, and its files.

Columns, in order: ``point``, one per swept key (a number where every value is one,
else the value as typed), ``seed``, every scalar metric (a per-robot metric as
``name[robot k]``), ``claim:KEY`` (pass/fail, :func:`firefleet.sweep.claim_key`; null
for a failed run), ``run_time_s``, ``error`` (null for a run that finished) and
``point_digest`` (a hash of the point's scenario: what resume matches). Rows are sorted
by point, then seed. The schema's metadata names which columns are parameters, metrics
and claims.
"""

from __future__ import annotations

import io
import json
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from firefleet.sweep._grid import Point
from firefleet.sweep._tasks import Row, claim_key

if TYPE_CHECKING:
    import pyarrow as pa

__all__ = ["build_table", "column_roles", "csv_bytes", "parquet_bytes", "read_parquet"]

_META = b"firefleet.sweep"


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def build_table(points: Sequence[Point], rows: Sequence[Row], scenario: str) -> pa.Table:
    """The table of ``rows`` (from :func:`firefleet.sweep.run_batch`), sorted.

    Parameters
    ----------
    points : sequence of Point
        The sweep's points (their swept values and digests).
    rows : sequence of dict
        One per run, in any order.
    scenario : str
        The swept scenario's name, kept in the schema's metadata.
    """
    import pyarrow as pa

    rows = sorted(rows, key=lambda r: (r["point"], r["seed"]))
    keys = list(points[0].values) if points else []
    metrics: list[str] = []
    claims: list[str] = []
    for point in points:  # the claims in the scenario's order, then the metrics as met
        for claim in point.scenario.claims:
            if f"claim:{claim_key(claim)}" not in claims:
                claims.append(f"claim:{claim_key(claim)}")
    for row in rows:
        for name in row:
            if name.startswith("metric:") and name[7:] not in metrics:
                metrics.append(name[7:])
    by_index = {p.index: p for p in points}
    columns: dict[str, pa.Array] = {"point": pa.array([r["point"] for r in rows], pa.int64())}
    for key in keys:
        values = [by_index[r["point"]].values[key] for r in rows]
        if all(_is_number(v) for v in values):
            columns[key] = pa.array([float(v) for v in values], pa.float64())
        else:
            columns[key] = pa.array([by_index[r["point"]].labels[key] for r in rows], pa.string())
    columns["seed"] = pa.array([r["seed"] for r in rows], pa.int64())
    for name in metrics:
        columns[name] = pa.array([r.get(f"metric:{name}") for r in rows], pa.float64())
    for name in claims:
        columns[name] = pa.array([r.get(name) for r in rows], pa.bool_())
    columns["run_time_s"] = pa.array([r["run_time_s"] for r in rows], pa.float64())
    columns["error"] = pa.array([r["error"] for r in rows], pa.string())
    columns["point_digest"] = pa.array([by_index[r["point"]].digest for r in rows], pa.string())
    roles = {"scenario": scenario, "params": keys, "metrics": metrics, "claims": claims}
    schema = pa.schema(
        [pa.field(n, a.type) for n, a in columns.items()],
        metadata={_META: json.dumps(roles).encode()},
    )
    return pa.Table.from_arrays(list(columns.values()), schema=schema)


def column_roles(table: pa.Table) -> dict[str, Any]:
    """``{"scenario", "params", "metrics", "claims"}``: the table's columns by role."""
    meta = table.schema.metadata or {}
    if _META not in meta:
        raise ValueError("not a firefleet sweep table (no firefleet.sweep metadata)")
    roles: dict[str, Any] = json.loads(meta[_META])
    return roles


def rows_of(table: pa.Table) -> list[Row]:
    """A sweep table back to rows (for resume): the inverse of :func:`build_table`."""
    roles = column_roles(table)
    data = table.to_pydict()
    rows = []
    for i in range(table.num_rows):
        row: Row = {"point": data["point"][i], "seed": data["seed"][i]}
        for name in roles["metrics"]:
            value = data[name][i]
            if value is not None:
                row[f"metric:{name}"] = value
        for name in roles["claims"]:
            if data[name][i] is not None:
                row[name] = data[name][i]
        row["run_time_s"] = data["run_time_s"][i]
        row["error"] = data["error"][i]
        row["point_digest"] = data["point_digest"][i]
        rows.append(row)
    return rows


def parquet_bytes(table: pa.Table) -> bytes:
    """``results.parquet``: the table, schema metadata included."""
    import pyarrow.parquet as pq

    sink = io.BytesIO()
    pq.write_table(table, sink)
    return sink.getvalue()


def read_parquet(data: bytes) -> pa.Table:
    """A table from ``results.parquet`` bytes."""
    import pyarrow.parquet as pq

    return pq.read_table(io.BytesIO(data))


def csv_bytes(table: pa.Table) -> bytes:
    """``results.csv``: the same table, NaN and inf written as ``nan``, ``inf``."""
    import pyarrow.csv as pcsv

    sink = io.BytesIO()
    pcsv.write_csv(table, sink)
    return sink.getvalue()


def finite(values: Sequence[float | None]) -> list[float]:
    """The finite numbers among ``values``."""
    return [v for v in values if v is not None and math.isfinite(v)]
