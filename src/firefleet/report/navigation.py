"""Figures of a navigate run: the map, the paths, the sensor rays, and an animation."""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Circle

from firefleet._typing import FloatArray
from firefleet.sim.result import SimResult
from firefleet.world import OccupancyGrid

__all__ = ["animation_gif", "figures", "overview_png"]

_FRAMES = 40
"""Frames of the animation."""


def _png(fig: Figure, *, dpi: int = 110) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi)
    plt.close(fig)
    return buffer.getvalue()


def _colours(n: int) -> list[tuple[float, float, float, float]]:
    cmap = plt.get_cmap("tab10")
    return [cmap(i % 10) for i in range(n)]


def _map(ax: Axes, grid: OccupancyGrid, occupancy: FloatArray | None = None) -> None:
    """The map in grey: walls black, unknown mid grey (or a built map's probabilities)."""
    if occupancy is None:
        shade = np.where(grid.occupied, 0.0, np.where(grid.free, 1.0, 0.75))
    else:
        shade = 1.0 - np.asarray(occupancy, dtype=float)
    ax.imshow(shade, cmap="gray", vmin=0.0, vmax=1.0, extent=grid.extent_m, origin="upper")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")


def _discs(
    ax: Axes, pose: FloatArray, radius_m: float, colours: list[tuple[float, float, float, float]]
) -> None:
    for i, (x, y, th) in enumerate(pose):
        ax.add_patch(Circle((x, y), radius_m, fill=False, color=colours[i], lw=1.2))
        ax.plot([x, x + radius_m * np.cos(th)], [y, y + radius_m * np.sin(th)], color=colours[i])


def _rays(
    ax: Axes, result: SimResult, k: int, colours: list[tuple[float, float, float, float]]
) -> None:
    """Each robot's range readings at sample ``k``: a ray to each return (dots at the
    hit), faint rays to the range limit where nothing came back."""
    from firefleet.sim.kinds.navigate import reading_bearings, reading_limits

    pose = result.pose[k]
    limits = reading_limits(result.scenario)
    for name, bearings in reading_bearings(result.scenario).items():
        ranges = result.extra.get(name)
        if ranges is None:
            continue
        style = "-" if name.startswith("lidar") else "--"
        for i, (x, y, th) in enumerate(pose):
            r = np.asarray(ranges[k, i], dtype=float)
            hit = np.isfinite(r)
            reach = np.where(hit, r, limits[name])
            ang = th + bearings
            ex, ey = x + reach * np.cos(ang), y + reach * np.sin(ang)
            for j in range(bearings.size):
                ax.plot(
                    [x, ex[j]],
                    [y, ey[j]],
                    style,
                    color=colours[i],
                    lw=0.5,
                    alpha=0.6 if hit[j] else 0.12,
                )
            ax.plot(ex[hit], ey[hit], ".", color=colours[i], ms=2.5)


def overview_png(result: SimResult) -> bytes:
    """The map with each robot's true path (solid), its pose estimate's (dashed), start
    (circle) and goal (star); below, the robots and their sensor rays at the start, the
    middle and the end of the run; and the map the team built, for SLAM."""
    from firefleet.sim.kinds.navigate import _command, _grid

    cmd = _command(result.scenario)
    grid = _grid(result.scenario)
    n = result.pose.shape[1]
    colours = _colours(n)
    occupancy = result.extra.get("occupancy")
    wide = grid.width_m / grid.height_m
    fig = plt.figure(figsize=(11, 4.2 + 11 / (3 * wide) + 0.6), layout="constrained")
    subs = fig.subfigures(2, 1, height_ratios=[1.6, 1])
    assert isinstance(subs, np.ndarray)  # two subfigures
    top, bottom = subs
    axes_top = top.subplots(1, 2 if occupancy is not None else 1, squeeze=False)[0]
    ax = axes_top[0]
    _map(ax, grid)
    est = result.extra.get("estimated_pose")
    odo = result.extra.get("odometry_pose")
    for i in range(n):
        xy = result.pose[:, i, :2]
        ax.plot(xy[:, 0], xy[:, 1], color=colours[i], lw=1.6, label=f"robot {i + 1}")
        if est is not None and cmd.localisation != "odometry":
            ax.plot(est[:, i, 0], est[:, i, 1], "--", color=colours[i], lw=0.9)
        elif odo is not None:
            ax.plot(odo[:, i, 0], odo[:, i, 1], ":", color=colours[i], lw=0.9)
        ax.plot(*xy[0], "o", color=colours[i], ms=6)
        ax.plot(*cmd.goals_m[i], "*", color=colours[i], ms=13, mec="k", mew=0.6)
        ax.add_patch(
            Circle(cmd.goals_m[i], cmd.goal_tolerance_m, fill=False, color=colours[i], ls=":")
        )
    _discs(ax, result.pose[-1], cmd.robot_radius_m, colours)
    ax.set_xlim(grid.extent_m[:2])
    ax.set_ylim(grid.extent_m[2:])
    estimate = "estimate (dashed)" if cmd.localisation != "odometry" else "odometry (dotted)"
    ax.set_title(
        f"{result.scenario.name}: true paths (solid), {estimate}, start o, goal *; "
        f"localisation {cmd.localisation}",
        fontsize=9,
    )
    ax.legend(fontsize=7, loc="upper right")
    if occupancy is not None:
        _map(axes_top[1], grid, occupancy)
        axes_top[1].set_title("the map the team built (occupancy probability)", fontsize=9)
    snaps = bottom.subplots(1, 3)
    for ax_s, k in zip(snaps, _instants(result.t.size, 3), strict=True):
        _map(ax_s, grid)
        _rays(ax_s, result, k, colours)
        _discs(ax_s, result.pose[k], cmd.robot_radius_m, colours)
        ax_s.set_title(f"t = {result.t[k]:.1f} s: robots and their range readings", fontsize=8)
        _zoom(ax_s, grid, result.pose[..., :2])
    return _png(fig)


def _zoom(ax: Axes, grid: OccupancyGrid, xy_m: FloatArray, margin_m: float = 1.5) -> None:
    """Limit the axes to where the robots went (plus ``margin_m``), within the map."""
    x0, x1, y0, y1 = grid.extent_m
    pts = np.asarray(xy_m).reshape(-1, 2)
    ax.set_xlim(max(x0, pts[:, 0].min() - margin_m), min(x1, pts[:, 0].max() + margin_m))
    ax.set_ylim(max(y0, pts[:, 1].min() - margin_m), min(y1, pts[:, 1].max() + margin_m))


def _instants(size: int, count: int) -> list[int]:
    return [int(k) for k in np.linspace(0, size - 1, count).round()]


def animation_gif(result: SimResult, *, frames: int = _FRAMES) -> bytes:
    """An animated GIF of the run: the robots on the map with their trails and rays."""
    from PIL import Image

    from firefleet.sim.kinds.navigate import _command, _grid

    cmd = _command(result.scenario)
    grid = _grid(result.scenario)
    n = result.pose.shape[1]
    colours = _colours(n)
    wide = grid.width_m / grid.height_m
    images = []
    for k in _instants(result.t.size, min(frames, result.t.size)):
        fig = plt.figure(figsize=(6.0, 6.0 / wide + 0.5), layout="constrained")
        ax = fig.subplots()
        _map(ax, grid)
        ax.set_xlim(grid.extent_m[:2])
        ax.set_ylim(grid.extent_m[2:])
        for i in range(n):
            ax.plot(result.pose[: k + 1, i, 0], result.pose[: k + 1, i, 1], color=colours[i])
            ax.plot(*cmd.goals_m[i], "*", color=colours[i], ms=10, mec="k", mew=0.5)
        _rays(ax, result, k, colours)
        _discs(ax, result.pose[k], cmd.robot_radius_m, colours)
        ax.set_title(f"{result.scenario.name}  t = {result.t[k]:.1f} s", fontsize=9)
        images.append(
            Image.open(io.BytesIO(_png(fig, dpi=80))).convert(
                "P", palette=Image.Palette.ADAPTIVE, colors=64
            )
        )
    buffer = io.BytesIO()
    images[0].save(
        buffer, format="GIF", save_all=True, append_images=images[1:], duration=150, loop=0
    )
    return buffer.getvalue()


def figures(result: SimResult) -> dict[str, bytes]:
    """``navigate.png`` (:func:`overview_png`) and ``navigate.gif`` (:func:`animation_gif`)."""
    return {"navigate.png": overview_png(result), "navigate.gif": animation_gif(result)}
