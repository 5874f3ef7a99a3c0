"""Figures of a mission run: the building with its fire, smoke and people, the team's
tracks, and an animation with the robots' thermal views."""

from __future__ import annotations

import io
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap, PowerNorm
from matplotlib.figure import Figure

from firefleet.sim.result import SimResult
from firefleet.world import BURNING, OccupancyGrid

__all__ = ["animation_gif", "figures", "overview_png"]

_FRAMES = 45
"""Frames of the animation."""
_INSETS = 3
"""Thermal views shown in the animation (the first robots')."""
_FIRE_CMAP = ListedColormap([(0, 0, 0, 0), (1.0, 0.45, 0.0, 0.9), (0.35, 0.15, 0.1, 0.75)])
"""Unburnt (clear), burning (orange), burnt (dark brown)."""


def _png(fig: Figure, *, dpi: int = 110) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi)
    plt.close(fig)
    return buffer.getvalue()


def _colours(n: int) -> list[Any]:
    cmap = plt.get_cmap("tab10")
    return [cmap(i % 10) for i in range(n)]


def _scene(ax: Axes, grid: OccupancyGrid, field: OccupancyGrid, fire: Any, smoke: Any) -> None:
    """Map (walls black), smoke (grey veil), fire (orange burning, brown burnt)."""
    ax.imshow(
        np.where(grid.occupied, 0.0, 1.0),
        cmap="gray",
        vmin=0.0,
        vmax=1.0,
        extent=grid.extent_m,
        origin="upper",
    )
    veil = np.zeros((*field.shape, 4))
    veil[..., :3] = 0.45
    veil[..., 3] = np.clip(1.0 - np.exp(-np.asarray(smoke, dtype=float)), 0.0, 0.6)
    veil[field.occupied] = 0.0
    ax.imshow(veil, extent=field.extent_m, origin="upper")
    ax.imshow(
        np.asarray(fire),
        cmap=_FIRE_CMAP,
        vmin=-0.5,
        vmax=2.5,
        extent=field.extent_m,
        origin="upper",
        interpolation="nearest",
    )
    ax.set_aspect("equal")
    ax.set_xlim(grid.extent_m[:2])
    ax.set_ylim(grid.extent_m[2:])
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")


def _people(ax: Axes, world: Any, found_s: Any, t_s: float) -> None:
    for (x, y), when in zip(world.victim_xy_m, found_s, strict=True):
        found = np.isfinite(when) and when <= t_s + 1e-9
        ax.plot(x, y, "o", ms=8, mfc="limegreen" if found else "white", mec="k", mew=1.2)


def overview_png(result: SimResult, metrics: dict[str, Any]) -> bytes:
    """The building at the end (fire, smoke, people found or not), the team's tracks,
    and the burning area against time."""
    from firefleet.sim.kinds.mission import _grid, mission_world

    world = mission_world(result.scenario)
    grid = _grid(result.scenario)
    x = result.extra
    fire = np.asarray(x["fire_state"])
    wide = grid.width_m / grid.height_m
    fig = plt.figure(figsize=(11.0, 4.0 / wide * 2.0 + 1.2), layout="constrained")
    ax, ax_t = fig.subplots(1, 2, width_ratios=[2.2, 1.0])
    _scene(ax, grid, world.field, fire[-1], np.asarray(x["smoke_per_m"])[-1])
    colours = _colours(result.pose.shape[1])
    for i in range(result.pose.shape[1]):
        ax.plot(result.pose[:, i, 0], result.pose[:, i, 1], color=colours[i], lw=1.0)
        ax.plot(*result.pose[-1, i, :2], "o", color=colours[i], ms=4)
    for cell in world.fire_cells:
        ax.plot(*world.field.center_of(cell), "^", color="red", mec="k", ms=9)
    _people(ax, world, np.asarray(x["victims_found_s"]), float(result.t[-1]))
    n_people = world.victim_xy_m.shape[0]
    stereo = float(metrics.get("stereo_victims_found", np.nan))
    ax.set_title(
        f"{result.scenario.name}: burned {metrics['burned_area_m2']:.0f} m^2 "
        f"(without the team {metrics['baseline_burned_area_m2']:.0f}); people found "
        f"{metrics['victims_found']:.0f} of {n_people}"
        + (
            f"\n(tracks: the thermal team; a stereo-only team in the same world found "
            f"{stereo:.0f} of {n_people})"
            if np.isfinite(stereo)
            else ""
        ),
        fontsize=9,
    )
    t = np.asarray(x["field_t_s"])
    area = world.field.resolution_m**2
    ax_t.plot(t, (fire == BURNING).sum(axis=(1, 2)) * area, color="darkorange", label="burning")
    ax_t.plot(t, (fire != 0).sum(axis=(1, 2)) * area, color="saddlebrown", label="burned")
    ax_t.axhline(
        metrics["baseline_burned_area_m2"], color="k", ls="--", lw=1, label="burned, no team"
    )
    for when in np.asarray(x["victims_found_s"]):
        if np.isfinite(when):
            ax_t.axvline(when, color="limegreen", lw=1)
    ax_t.set_xlabel("t [s]")
    ax_t.set_ylabel("area [m^2]")
    ax_t.set_title("fire (green lines: a person found)", fontsize=9)
    ax_t.legend(fontsize=8)
    return _png(fig)


def animation_gif(result: SimResult, *, frames: int = _FRAMES) -> bytes:
    """The run animated: fire, smoke, people and robots, with the first robots' thermal
    views rendered from the recorded fields at their poses."""
    from PIL import Image

    from firefleet.sim.kinds._mission_world import SCENE
    from firefleet.sim.kinds.mission import _grid, mission_world
    from firefleet.sim.sensors import ThermalCameraParams, render_thermal_grid

    world = mission_world(result.scenario)
    grid = _grid(result.scenario)
    x = result.extra
    fire = np.asarray(x["fire_state"])
    temp = np.asarray(x["temperature_c"])
    smoke = np.asarray(x["smoke_per_m"])
    t_field = np.asarray(x["field_t_s"])
    found = np.asarray(x["victims_found_s"])
    n = result.pose.shape[1]
    colours = _colours(n)
    insets = min(n, _INSETS)
    camera = ThermalCameraParams(supersample=1, netd_k=0.0, column_fpn_k=0.0)
    wide = grid.width_m / grid.height_m
    images = []
    picks = np.unique(np.linspace(0, t_field.size - 1, min(frames, t_field.size)).astype(int))
    for j in picks:
        t_s = float(t_field[j])
        k = int(np.argmin(np.abs(result.t - t_s)))
        fig = plt.figure(figsize=(8.0, 8.0 / wide * 0.75 + 1.8), layout="constrained")
        subs: Any = fig.subfigures(2, 1, height_ratios=[3.0, 1.0])
        top, bottom = subs[0], subs[1]
        ax = top.subplots()
        _scene(ax, grid, world.field, fire[j], smoke[j])
        for i in range(n):
            ax.plot(
                result.pose[: k + 1, i, 0], result.pose[: k + 1, i, 1], color=colours[i], lw=0.8
            )
            ax.plot(*result.pose[k, i, :2], "o", color=colours[i], ms=5, mec="k", mew=0.5)
        _people(ax, world, found, t_s)
        ax.set_title(f"{result.scenario.name}  t = {t_s:.0f} s", fontsize=9)
        views = render_thermal_grid(
            result.pose[k, :insets],
            world.field,
            temp[j],
            fire[j] == BURNING,
            world.victim_xy_m,
            camera,
            rng=np.random.default_rng(0),
            scene=SCENE,
        )
        axes = np.atleast_1d(bottom.subplots(1, _INSETS))
        for i, axi in enumerate(axes):
            axi.axis("off")
            if i < insets:
                # one fixed scale, 15-600 C (a Lepton's high-gain range saturates at
                # 150 C: a robot at a burning room's door saw one flat colour), on a
                # power scale (gamma 0.4) so a person at 37 C still shows
                axi.imshow(views[i], cmap="inferno", norm=PowerNorm(0.4, 15.0, 600.0))
                axi.set_title(f"robot {i + 1} thermal, 15-600 C", fontsize=8, color=colours[i])
        images.append(
            Image.open(io.BytesIO(_png(fig, dpi=70))).convert(
                "P", palette=Image.Palette.ADAPTIVE, colors=96
            )
        )
    buffer = io.BytesIO()
    images[0].save(
        buffer, format="GIF", save_all=True, append_images=images[1:], duration=200, loop=0
    )
    return buffer.getvalue()


def figures(result: SimResult, metrics: dict[str, Any]) -> dict[str, bytes]:
    """``mission.png`` (:func:`overview_png`) and ``mission.gif`` (:func:`animation_gif`)."""
    return {
        "mission.png": overview_png(result, metrics),
        "mission.gif": animation_gif(result),
    }
