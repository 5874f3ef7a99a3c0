"""Figures of a sweep: each metric against each swept key (seeds as spread, claims'
bounds drawn), and each claim's pass rate.

matplotlib is imported here only, when a sweep's figures are made.
"""

from __future__ import annotations

import io
import math
import re
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from firefleet.scenarios.schema import Claim
from firefleet.sweep import column_roles

if TYPE_CHECKING:
    import pyarrow as pa

__all__ = ["sweep_figures"]

_ROBOT = re.compile(r"^(?P<base>.+)\[robot (?P<k>\d+)\]$")
_MAX_SERIES = 8


def _png(fig: Any) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    plt.close(fig)
    return buffer.getvalue()


def _groups(metrics: Sequence[str]) -> dict[str, list[tuple[int | None, str]]]:
    """Metric columns by base name: ``[(robot or None, column), ...]``."""
    groups: dict[str, list[tuple[int | None, str]]] = {}
    for name in metrics:
        found = _ROBOT.match(name)
        base, robot = (found["base"], int(found["k"])) if found else (name, None)
        groups.setdefault(base, []).append((robot, name))
    return groups


def _bounds(ax: Any, claims: Sequence[Claim], base: str, colors: dict[int | None, Any]) -> None:
    """Draw each claim on ``base``: a dashed line at its bound, a band for ``~``."""
    for claim in claims:
        if claim.metric != base:
            continue
        color = colors.get(claim.robot, "tab:red") if claim.robot is not None else "tab:red"
        label = f"claim {claim.expected}" + (f" (robot {claim.robot})" if claim.robot else "")
        if claim.op == "~":
            half = claim.rel_tol * abs(claim.value)
            ax.axhspan(claim.value - half, claim.value + half, color=color, alpha=0.15)
            ax.axhline(claim.value, color=color, ls="--", lw=1, label=label)
        else:
            ax.axhline(claim.value, color=color, ls="--", lw=1, label=label)


def _x_of(data: dict[str, list[Any]], key: str) -> tuple[np.ndarray, list[str] | None]:
    """Positions along the key: its numbers, or 0, 1, ... for values typed as text."""
    values = data[key]
    if all(isinstance(v, int | float) for v in values):
        return np.asarray(values, dtype=np.float64), None
    labels = list(dict.fromkeys(values))
    return np.array([labels.index(v) for v in values], dtype=np.float64), labels


def _series(data: dict[str, list[Any]], params: list[str], key: str) -> list[tuple[str, list[int]]]:
    """Rows split by the other swept keys' values (pooled if that makes too many lines)."""
    others = [p for p in params if p != key]
    n = len(data["seed"])
    if not others:
        return [("", list(range(n)))]
    combos: dict[str, list[int]] = {}
    for i in range(n):
        name = ", ".join(
            f"{p}={data[p][i]:g}" if isinstance(data[p][i], float) else f"{p}={data[p][i]}"
            for p in others
        )
        combos.setdefault(name, []).append(i)
    if len(combos) > _MAX_SERIES:
        return [(f"pooled over {', '.join(others)}", list(range(n)))]
    return list(combos.items())


def _spread_plot(
    ax: Any, x: np.ndarray, y: np.ndarray, rows: list[int], color: Any, label: str
) -> None:
    """Every seed as a dot, the mean as a line, the 5-95 % band shaded."""
    xs, ys = x[rows], y[rows]
    keep = np.isfinite(ys)
    if not keep.any():
        return
    xs, ys = xs[keep], ys[keep]
    levels = np.unique(xs)
    width = (np.diff(levels).min() if levels.size > 1 else 1.0) * 0.06
    jitter = (np.arange(xs.size) % 7 - 3) / 3.0 * width
    ax.plot(xs + jitter, ys, "o", ms=2.5, alpha=0.35, color=color)
    means = np.array([ys[xs == v].mean() for v in levels])
    low = np.array([np.percentile(ys[xs == v], 5) for v in levels])
    high = np.array([np.percentile(ys[xs == v], 95) for v in levels])
    ax.plot(levels, means, "-o", ms=4, color=color, label=label or "mean over seeds")
    ax.fill_between(levels, low, high, color=color, alpha=0.18, lw=0)


def _metric_grid(table: pa.Table, claims: Sequence[Claim], key: str | None, title: str) -> bytes:
    """One panel per metric against ``key`` (or against the seed when nothing is swept)."""
    roles = column_roles(table)
    data = table.to_pydict()
    ok = [i for i, e in enumerate(data["error"]) if e is None]
    data = {name: [column[i] for i in ok] for name, column in data.items()}
    groups = _groups(roles["metrics"])
    ncols = min(3, len(groups))
    nrows = math.ceil(len(groups) / ncols)
    fig, axes = plt.subplots(
        nrows, ncols, figsize=(5.2 * ncols, 3.3 * nrows), squeeze=False, layout="constrained"
    )
    if key is None:
        x, labels = np.asarray(data["seed"], dtype=np.float64), None
        series = [("", list(range(len(x))))]
    else:
        x, labels = _x_of(data, key)
        series = _series(data, roles["params"], key)
    palette = plt.get_cmap("tab10")
    for ax, (base, columns) in zip(axes.flat, groups.items(), strict=False):
        colors: dict[int | None, Any] = {}
        for s, (name, rows) in enumerate(series):
            for c, (robot, column) in enumerate(columns):
                color = palette((s * len(columns) + c) % 10)
                colors.setdefault(robot, color)
                y = np.array([np.nan if v is None else v for v in data[column]], dtype=float)
                label = ", ".join(t for t in (name, f"robot {robot}" if robot else "") if t)
                if key is None:  # nothing swept: the seeds along x, the spread as a band
                    ys = y[rows]
                    keep = np.isfinite(ys)
                    ax.plot(x[rows][keep], ys[keep], "o", ms=3, color=color, label=label or None)
                    if keep.any():
                        mean = float(ys[keep].mean())
                        low, high = np.percentile(ys[keep], [5, 95])
                        ax.axhline(mean, color=color, lw=1)
                        ax.axhspan(low, high, color=color, alpha=0.12, lw=0)
                else:
                    _spread_plot(ax, x, y, rows, color, label)
        _bounds(ax, claims, base, colors)
        undefined = sum(
            1 for _, column in columns for v in data[column] if v is None or not math.isfinite(v)
        )
        ax.set_title(
            base + (f"  ({undefined} not finite, not drawn)" if undefined else ""), fontsize=9
        )
        ax.set_xlabel("seed" if key is None else key, fontsize=8)
        ax.tick_params(labelsize=8)
        if labels is not None:
            ax.set_xticks(range(len(labels)), labels, rotation=20, fontsize=7)
        ax.grid(alpha=0.3)
        handles, _ = ax.get_legend_handles_labels()
        if handles and len(handles) <= 8:
            ax.legend(fontsize=6, loc="best")
    for ax in axes.flat[len(groups) :]:
        ax.set_visible(False)
    fig.suptitle(title, fontsize=11)
    return _png(fig)


def _pass_rates(summary: dict[str, Any], key: str | None) -> bytes:
    """Each claim's pass rate: bars for one point, lines against ``key`` otherwise."""
    entries = summary["points"]
    labels = list(entries[0]["claims"]) if entries else []
    if key is None or len(entries) == 1:
        rates = [100 * np.nanmean([e["claims"][c]["pass_rate"] for e in entries]) for c in labels]
        fig, ax = plt.subplots(figsize=(7.5, 0.45 * len(labels) + 1.4))
        y = np.arange(len(labels))
        ax.barh(y, rates, color=["tab:green" if r == 100 else "tab:orange" for r in rates])
        for yy, r in zip(y, rates, strict=True):
            ax.text(min(r, 88) + 1, float(yy), f"{r:.0f} %", va="center", fontsize=8)
        ax.set_yticks(y, labels, fontsize=8)
        ax.invert_yaxis()
        ax.set_xlim(0, 100)
        ax.set_xlabel("runs in which the claim holds [%]")
        n = sum(e["runs"] - e["failed"] for e in entries)
        ax.set_title(f"{summary['scenario']}: pass rate of each claim over {n} runs", fontsize=10)
    else:
        values = [e["values"][key] for e in entries]
        numeric = all(_is_number(v) for v in values)
        xs_all = [float(v) for v in values] if numeric else None
        order = list(dict.fromkeys(values))
        fig, ax = plt.subplots(figsize=(7.5, 4.2))
        for c, label in enumerate(labels):
            by_x: dict[Any, list[float]] = {}
            for e, v in zip(entries, values, strict=True):
                by_x.setdefault(v, []).append(e["claims"][label]["pass_rate"])
            xs = [float(v) if numeric else order.index(v) for v in by_x]
            ys = [100 * float(np.nanmean(r)) for r in by_x.values()]
            # overlapping lines stay visible: each claim its marker, the first ones larger
            ax.plot(
                xs,
                ys,
                "-" + "osD^vPX"[c % 7],
                ms=max(3.0, 9.0 - 1.2 * c),
                lw=max(1.0, 3.5 - 0.5 * c),
                mfc="none" if c % 2 else None,
                label=label,
                color=plt.get_cmap("tab10")(c % 10),
                alpha=0.85,
            )
        if not numeric:
            ax.set_xticks(range(len(order)), order, rotation=20, fontsize=8)
        elif xs_all:
            ax.set_xlim(
                min(xs_all) - 0.05 * (max(xs_all) - min(xs_all) or 1),
                max(xs_all) + 0.05 * (max(xs_all) - min(xs_all) or 1),
            )
        ax.set_ylim(-3, 103)
        ax.set_xlabel(key)
        ax.set_ylabel("runs in which the claim holds [%]")
        others = [p for p in summary["params"] if p != key]
        pooled = f" (pooled over {', '.join(others)})" if others else ""
        ax.set_title(f"{summary['scenario']}: pass rate of each claim{pooled}", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    return _png(fig)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _slug(key: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", key)


def sweep_figures(
    table: pa.Table, summary: dict[str, Any], claims: Sequence[Claim]
) -> dict[str, bytes]:
    """The sweep's PNG figures by file name.

    ``metrics_vs_KEY.png`` for each swept key (``metrics_by_seed.png`` when only seeds
    are swept): a panel per metric, each seed a dot, the mean over seeds a line, the
    5-95 % band shaded, each claim's bound dashed. ``pass_rates.png`` (and
    ``pass_rates_vs_KEY.png`` per swept key): each claim's pass rate.

    Parameters
    ----------
    table : pyarrow.Table
        A sweep's table (:func:`firefleet.sweep.build_table`).
    summary : dict
        Its summary (:func:`firefleet.sweep.summarize`).
    claims : sequence of Claim
        The scenario's claims, whose bounds are drawn.

    Examples
    --------
    >>> from firefleet import load_scenario
    >>> from firefleet.sweep import build_table, points_of, run_batch, summarize
    >>> from firefleet.report.sweep import sweep_figures
    >>> scenario = load_scenario("motor-pid")
    >>> points = points_of(scenario, [])
    >>> table = build_table(points, run_batch(scenario, 0, [0, 1, 2]), scenario.name)
    >>> sorted(sweep_figures(table, summarize(table, points), scenario.claims))
    ['metrics_by_seed.png', 'pass_rates.png']
    """
    params: list[str] = column_roles(table)["params"]
    name = summary["scenario"]
    figures: dict[str, bytes] = {}
    if not params:
        figures["metrics_by_seed.png"] = _metric_grid(
            table, claims, None, f"{name}: every metric over {table.num_rows} runs (one per seed)"
        )
    for key in params:
        figures[f"metrics_vs_{_slug(key)}.png"] = _metric_grid(
            table, claims, key, f"{name}: every metric against {key} (dots: seeds; band: 5-95 %)"
        )
        if len(summary["points"]) > 1:
            figures[f"pass_rates_vs_{_slug(key)}.png"] = _pass_rates(summary, key)
    figures["pass_rates.png"] = _pass_rates(summary, None)
    return figures
