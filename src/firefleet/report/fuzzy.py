"""Figures of a fuzzy controller: control surfaces and membership functions.

The deliverable shows its controller as MATLAB ``gensurf`` surfaces (Figures 16, 17,
21-23) and ``plotmf`` membership plots (Figures 14, 15, 20). These functions draw the
same for any :class:`~firefleet.control.fuzzy.SugenoSystem` and return PNG bytes.
matplotlib is imported inside each function (only when a figure is made), and used
through ``Figure`` objects with the Agg canvas, not pyplot's global state.
"""

from __future__ import annotations

import io
import re
from collections.abc import Mapping
from typing import Any

import numpy as np

from firefleet.control.fuzzy import FuzzyInput, SugenoSystem, evaluate, membership
from firefleet.errors import InputError

__all__ = ["figures", "membership_png", "surface_grid", "surface_png"]

GRID_POINTS = 41
"""Grid points per axis of a control surface (MATLAB's gensurf uses 15)."""
MF_POINTS = 801
"""Points along an input's range in a membership plot."""


def _index(names: list[str], key: str | int, what: str) -> int:
    if isinstance(key, int) and not isinstance(key, bool):
        if 0 <= key < len(names):
            return key
        raise InputError(f"{what} index {key} out of range 0..{len(names) - 1}")
    if key in names:
        return names.index(key)
    raise InputError(f"unknown {what} {key!r}; the system's {what}s are {names}")


def surface_grid(
    system: SugenoSystem,
    output: str | int,
    x_input: str | int,
    y_input: str | int,
    *,
    fixed: Mapping[str, float] | None = None,
    points: int = GRID_POINTS,
) -> tuple[np.ndarray[Any, np.dtype[np.float64]], ...]:
    """The control surface of one output over two inputs, as MATLAB's ``gensurf``.

    Parameters
    ----------
    system : SugenoSystem
        The controller.
    output, x_input, y_input : str or int
        Names (or 0-based indices) of the output and of the two inputs swept over
        their ranges; ``x_input`` and ``y_input`` must differ.
    fixed : mapping of str to float, optional
        Values of the other inputs, by name; an input not given is held at the
        middle of its range (gensurf's reference input).
    points : int
        Grid points per axis.

    Returns
    -------
    (X, Y, Z) : ndarrays of shape (points, points)
        The grid of the two inputs and the output on it.

    Raises
    ------
    InputError
        Unknown names, the same input twice, a fixed value for an unknown input or
        one of the swept inputs, or a non-finite fixed value.
    """
    in_names = [v.name for v in system.inputs]
    j = _index([o.name for o in system.outputs], output, "output")
    ix = _index(in_names, x_input, "input")
    iy = _index(in_names, y_input, "input")
    if ix == iy:
        raise InputError(f"surface: x and y inputs must differ, got {in_names[ix]!r} twice")
    if points < 2:
        raise InputError(f"surface: points must be >= 2, got {points}")
    base = np.array([0.5 * (v.range[0] + v.range[1]) for v in system.inputs])
    for name, value in (fixed or {}).items():
        k = _index(in_names, name, "input")
        if k in (ix, iy):
            raise InputError(f"--fix {name}: it is an axis of this surface, not a fixed input")
        if not np.isfinite(value):
            raise InputError(f"--fix {name}={value}: must be a finite number")
        base[k] = float(value)
    xs = np.linspace(*system.inputs[ix].range, points)
    ys = np.linspace(*system.inputs[iy].range, points)
    X, Y = np.meshgrid(xs, ys)
    batch = np.tile(base, (X.size, 1))
    batch[:, ix] = X.ravel()
    batch[:, iy] = Y.ravel()
    Z = evaluate(system, batch)[:, j].reshape(X.shape)
    return X, Y, Z


def _png(fig: Any) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()


def surface_png(
    system: SugenoSystem,
    output: str | int,
    x_input: str | int,
    y_input: str | int,
    *,
    fixed: Mapping[str, float] | None = None,
    title: str | None = None,
) -> bytes:
    """PNG of a 3-D control surface (MATLAB ``gensurf`` style); see :func:`surface_grid`.

    The axes are labelled with the variables' names (units, if the names carry them,
    ``"D_rp [m]"``); the title says where the other inputs are held.
    """
    from matplotlib import cm
    from matplotlib.figure import Figure

    X, Y, Z = surface_grid(system, output, x_input, y_input, fixed=fixed)
    in_names = [v.name for v in system.inputs]
    out_name = system.outputs[_index([o.name for o in system.outputs], output, "output")].name
    ix, iy = _index(in_names, x_input, "input"), _index(in_names, y_input, "input")
    others = [
        f"{v.name} = {(fixed or {}).get(v.name, 0.5 * (v.range[0] + v.range[1])):.4g}"
        for k, v in enumerate(system.inputs)
        if k not in (ix, iy)
    ]
    fig = Figure(figsize=(7.0, 5.4))
    ax = fig.add_subplot(projection="3d")
    ax.plot_surface(X, Y, Z, cmap=cm.viridis, linewidth=0.2, edgecolor="0.3", antialiased=True)
    ax.set_xlabel(in_names[ix])
    ax.set_ylabel(in_names[iy])
    ax.set_zlabel(out_name)
    ax.view_init(elev=28, azim=-130)
    heading = title or f"{system.name}: {out_name} over {in_names[ix]} and {in_names[iy]}"
    fig.suptitle(heading, fontsize=10)
    if others:
        ax.set_title("held at " + ", ".join(others), fontsize=8)
    fig.subplots_adjust(left=0.0, right=0.95, bottom=0.05, top=0.9)
    return _png(fig)


def membership_png(system: SugenoSystem, input: str | int) -> bytes:
    """PNG of an input's membership functions over its range (MATLAB ``plotmf``)."""
    from matplotlib.figure import Figure

    var: FuzzyInput = system.inputs[_index([v.name for v in system.inputs], input, "input")]
    lo, hi = var.range
    pad = 0.0 if hi > lo else 1.0
    x = np.linspace(lo - pad, hi + pad, MF_POINTS)
    fig = Figure(figsize=(7.0, 3.4))
    ax = fig.add_subplot()
    for k, mf in enumerate(var.mfs):
        y = membership(mf.kind, mf.params, x)
        (line,) = ax.plot(x, y, lw=1.8, label=f"{mf.name} ({mf.kind})")
        peak = int(np.flatnonzero(y >= y.max() - 1e-9).mean())  # middle of a plateau
        ax.annotate(
            mf.name,
            (x[peak], y[peak]),
            xytext=(0, 4 + 9 * (k % 2)),
            textcoords="offset points",
            ha="left" if peak < 0.1 * x.size else "right" if peak > 0.9 * x.size else "center",
            fontsize=8,
            color=line.get_color(),
        )
    ax.set_xlim(x[0], x[-1])
    ax.set_ylim(-0.03, 1.22)
    ax.set_xlabel(var.name)
    ax.set_ylabel("degree of membership")
    ax.set_title(f"{system.name}: membership functions of {var.name}", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    return _png(fig)


def _slug(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_") or "var"


def figures(system: SugenoSystem, *, fixed: Mapping[str, float] | None = None) -> dict[str, bytes]:
    """Every figure of a controller, by file name.

    ``mf_<input>.png`` for each input, and ``surface_<output>_<x>_<y>.png`` for each
    output over each pair of inputs (the other inputs at ``fixed`` or mid-range; a
    fixed value for one of a surface's own axes is ignored for that surface).
    """
    in_names = [v.name for v in system.inputs]
    for name in fixed or {}:
        _index(in_names, name, "input")  # unknown names fail before any drawing
    pngs = {
        f"mf_{_slug(v.name)}.png": membership_png(system, k) for k, v in enumerate(system.inputs)
    }
    for j, out in enumerate(system.outputs):
        for a in range(len(in_names)):
            for b in range(a + 1, len(in_names)):
                held = {
                    k: v for k, v in (fixed or {}).items() if k not in (in_names[a], in_names[b])
                }
                key = f"surface_{_slug(out.name)}_{_slug(in_names[a])}_{_slug(in_names[b])}.png"
                pngs[key] = surface_png(system, j, a, b, fixed=held)
    return pngs
