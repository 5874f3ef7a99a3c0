"""Figures of a formation run: trajectories, shape against time, and an animation.

matplotlib is imported when a figure is made (Agg backend), as everywhere in
``firefleet.report``.
"""

from __future__ import annotations

import io
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from firefleet._typing import FloatArray
from firefleet.scenarios.schema import Formation
from firefleet.sim.formation import RADIUS_BAND, spacing_error_deg
from firefleet.sim.result import SimResult

__all__ = ["formation_animation", "formation_figures"]


_GIF_FRAMES = 40
"""Frames of the animation (spread evenly over the run)."""
_GIF_FPS = 12


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _png(fig: Any) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110, bbox_inches="tight")
    _pyplot().close(fig)
    return buffer.getvalue()


def _command(result: SimResult) -> Formation:
    cmd = result.scenario.command
    if not isinstance(cmd, Formation):
        raise ValueError(f"not a formation run: {cmd.kind}")
    return cmd


def _arrays(result: SimResult) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    points = np.asarray(result.extra["formation_xy_m"], dtype=np.float64)
    leader = np.asarray(result.extra["leader_xy_m"], dtype=np.float64)
    active = np.asarray(result.extra["robot_active"]) > 0.5
    return points, leader, active


_LEGEND_MAX = 10
"""Teams larger than this get one legend entry for all their robots."""


def _robot_label(k: int, n: int) -> str | None:
    """Legend label of robot k (from 0) of n: each its own, or one for a large team."""
    if n <= _LEGEND_MAX:
        return f"robot {k + 1}"
    return f"robots 1-{n}" if k == 0 else None


def _polygon(ax: Any, points: FloatArray, leader: FloatArray, color: str, **kw: Any) -> Any:
    """Join the points in their angular order about the leader (the formation's polygon)."""
    d = points - leader
    order = np.argsort(np.arctan2(d[:, 1], d[:, 0]))
    ring = points[np.r_[order, order[:1]]]
    return ax.plot(ring[:, 0], ring[:, 1], color=color, **kw)[0]


def _scene(ax: Any, result: SimResult, cmd: Formation) -> None:
    """Obstacles, the leader's path, axis labels."""
    plt = _pyplot()
    for o in cmd.obstacles:
        ax.add_patch(plt.Circle((o.x_m, o.y_m), o.radius_m, color="0.35", alpha=0.8, zorder=1))
    leader = np.asarray(result.extra["leader_xy_m"])
    if np.ptp(leader, axis=0).max() > 0:
        ax.plot(leader[:, 0], leader[:, 1], "k--", lw=1, label="virtual leader's path")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(alpha=0.3)


def _trajectories(result: SimResult, cmd: Formation) -> bytes:
    """Every robot's path from its start (o) to its end (square), with the final circle."""
    plt = _pyplot()
    points, leader, active = _arrays(result)
    pose = result.pose
    n = pose.shape[1]
    colors = plt.get_cmap("tab10")(np.arange(n) % 10)
    span = np.ptp(np.concatenate([pose[:, :, :2].reshape(-1, 2), leader], axis=0), axis=0)
    span = span + 2.0 * cmd.alpha_m * 0.2 + 1.0
    height = float(np.clip(6.0 * span[1] / span[0], 3.0, 7.0))
    fig, ax = plt.subplots(figsize=(9.0, height + 1.2))
    _scene(ax, result, cmd)
    many = n > _LEGEND_MAX  # a team: one legend entry, thinner lines, smaller marks
    for k in range(n):
        ax.plot(
            pose[:, k, 0],
            pose[:, k, 1],
            color=colors[k],
            lw=0.5 if many else 1.3,
            label=_robot_label(k, n),
        )
        ax.plot(pose[0, k, 0], pose[0, k, 1], "o", color=colors[k], mfc="none", ms=3 if many else 7)
        failed = not active[-1, k]
        ax.plot(
            pose[-1, k, 0],
            pose[-1, k, 1],
            "X" if failed else "s",
            color=colors[k],
            ms=10 if failed else (3 if many else 7),
        )
        if failed:
            ax.annotate(
                f"robot {k + 1} failed at {cmd.failure.time_s if cmd.failure else 0:g} s",
                (pose[-1, k, 0], pose[-1, k, 1]),
                xytext=(8, -12),
                textcoords="offset points",
                fontsize=8,
                color=colors[k],
            )
    c = leader[-1]
    ax.add_patch(
        plt.Circle(
            (float(c[0]), float(c[1])),
            cmd.alpha_m,
            fill=False,
            color="tab:red",
            ls=":",
            lw=1.2,
            label=f"circle alpha = {cmd.alpha_m:g} m (end)",
        )
    )
    ax.plot(c[0], c[1], "k+", ms=12, mew=2, label="virtual leader (end)")
    alive = active[-1]
    if alive.sum() >= 3:
        _polygon(ax, points[-1, alive], c, "0.4", lw=0.8, ls="-", label="final polygon")
    law = "eqs. 6-8 (deliverable)" if cmd.law == "deliverable" else "regular-polygon law"
    ax.set_title(
        f"{result.scenario.name}: {n} {cmd.robot_model} robots, {law}\n"
        "start o, end square"
        + (
            f"; robot centres (formation points {cmd.look_ahead_m:g} m ahead)"
            if cmd.robot_model == "diff-drive"
            else ""
        ),
        fontsize=10,
    )
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    fig.tight_layout()
    return _png(fig)


def _shape(result: SimResult, cmd: Formation) -> bytes:
    """Radius error of each robot and the spacing error against time."""
    plt = _pyplot()
    points, leader, active = _arrays(result)
    t = result.t
    r = np.sqrt(((points - leader[:, None, :]) ** 2).sum(axis=2))
    spacing = np.full(t.size, np.nan)
    for pattern in np.unique(active, axis=0):
        rows = (active == pattern).all(axis=1)
        spacing[rows] = spacing_error_deg(points[rows][:, pattern], leader[rows])
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    ax = axes[0]
    band = RADIUS_BAND * cmd.alpha_m
    ax.axhspan(0, band, color="tab:green", alpha=0.15, label=f"5 % of alpha ({band:g} m)")
    colors = plt.get_cmap("tab10")(np.arange(r.shape[1]) % 10)
    for k in range(r.shape[1]):
        err = np.where(active[:, k], np.abs(r[:, k] - cmd.alpha_m), np.nan)
        ax.semilogy(
            t,
            np.maximum(err, 1e-6),
            color=colors[k],
            lw=0.5 if r.shape[1] > _LEGEND_MAX else 1.1,
            label=_robot_label(k, r.shape[1]),
        )
    ax.set_ylabel("| distance to leader - alpha | [m]")
    ax.set_ylim(1e-6, None)
    ax.legend(fontsize=7, ncol=3, loc="upper right")
    axes[1].semilogy(t, np.maximum(spacing, 1e-4), color="tab:purple", lw=1.2)
    axes[1].axhline(2.0, color="tab:red", ls=":", lw=1, label="2 deg")
    axes[1].set_ylim(1e-4, None)
    axes[1].set_ylabel("spacing error [deg]")
    axes[1].set_xlabel("time [s]")
    axes[1].legend(fontsize=8, loc="upper right")
    for a in axes:
        a.axvspan(cmd.formed_by_s, t[-1], color="0.5", alpha=0.08)
        a.grid(alpha=0.3, which="both")
        if cmd.failure is not None:
            a.axvline(cmd.failure.time_s, color="tab:orange", ls="--", lw=1)
        if cmd.leader.speed_m_s > 0 and len(cmd.leader.waypoints_m) > 1:
            a.axvline(cmd.leader.start_s, color="k", ls=":", lw=0.8)
    axes[0].set_title(
        f"{result.scenario.name}: shape of the formation (metrics over the shaded window; "
        "values floored for the log scale)",
        fontsize=9,
    )
    fig.tight_layout()
    return _png(fig)


def formation_animation(result: SimResult, *, frames: int = _GIF_FRAMES) -> bytes:
    """An animated GIF of the run: robots (body discs), leader, circle, obstacles.

    Parameters
    ----------
    result : SimResult
        A formation run.
    frames : int
        Number of frames, spread evenly over the recorded samples.

    Returns
    -------
    bytes
        The GIF file (matplotlib's PillowWriter).
    """
    plt = _pyplot()
    from matplotlib.animation import FuncAnimation, PillowWriter

    cmd = _command(result)
    _, leader, active = _arrays(result)
    pose = result.pose
    n = pose.shape[1]
    idx = np.unique(np.linspace(0, result.t.size - 1, max(2, frames)).round().astype(int))
    stride = max(1, result.t.size // 400)  # trails of at most ~400 points
    lo = np.minimum(pose[:, :, :2].min(axis=(0, 1)), leader.min(axis=0) - cmd.alpha_m) - 0.5
    hi = np.maximum(pose[:, :, :2].max(axis=(0, 1)), leader.max(axis=0) + cmd.alpha_m) + 0.5
    height = float(np.clip(6.0 * (hi[1] - lo[1]) / (hi[0] - lo[0]), 2.5, 6.0))
    fig, ax = plt.subplots(figsize=(8.0, height + 1.0))
    _scene(ax, result, cmd)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    colors = plt.get_cmap("tab10")(np.arange(n) % 10)
    bodies = [
        ax.add_patch(plt.Circle((0.0, 0.0), cmd.robot_radius_m, color=colors[k], zorder=3))
        for k in range(n)
    ]
    trails = [ax.plot([], [], color=colors[k], lw=0.8, alpha=0.6)[0] for k in range(n)]
    ring = ax.add_patch(plt.Circle((0.0, 0.0), cmd.alpha_m, fill=False, color="tab:red", ls=":"))
    (centre,) = ax.plot([], [], "k+", ms=10, mew=2)
    # laid out with the longest title it will show, so that no frame clips it
    title = ax.set_title(f"{result.scenario.name}   t = {result.t[-1]:5.1f} s", fontsize=12)
    fig.tight_layout()

    def draw(i: int) -> list[Any]:
        j = int(idx[i])
        for k in range(n):
            bodies[k].center = (float(pose[j, k, 0]), float(pose[j, k, 1]))
            bodies[k].set_alpha(1.0 if active[j, k] else 0.35)
            trails[k].set_data(pose[: j + 1 : stride, k, 0], pose[: j + 1 : stride, k, 1])
        ring.center = (float(leader[j, 0]), float(leader[j, 1]))
        centre.set_data([leader[j, 0]], [leader[j, 1]])
        title.set_text(f"{result.scenario.name}   t = {result.t[j]:5.1f} s")
        return [*bodies, *trails, ring, centre, title]

    anim = FuncAnimation(fig, draw, frames=idx.size, blit=False)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "formation.gif"
        # 800 px wide at 100 dpi: the report shows it at its own size, text legible
        anim.save(str(path), writer=PillowWriter(fps=_GIF_FPS), dpi=100)
        data = path.read_bytes()
    plt.close(fig)
    return data


def formation_figures(
    result: SimResult, metrics: Mapping[str, object] | None = None
) -> dict[str, bytes]:
    """The figures of a formation run, by file name (``metrics`` is not drawn).

    ``trajectories.png`` and ``shape.png`` for every run; ``formation.gif`` (an
    animation, about 2 s to make) when the leader moves.
    """
    cmd = _command(result)
    out = {
        "trajectories.png": _trajectories(result, cmd),
        "shape.png": _shape(result, cmd),
    }
    moving = cmd.leader.speed_m_s > 0 and len(cmd.leader.waypoints_m) > 1
    if moving:
        out["formation.gif"] = formation_animation(result)
    return out
