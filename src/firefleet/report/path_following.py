"""Figures of a path-following run (Figures 14-17 and 20-37 of the deliverable)."""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from mpl_toolkits.mplot3d import Axes3D
from numpy.typing import NDArray

from firefleet.control.fuzzy import SugenoSystem, evaluate, membership
from firefleet.control.path_following import PathFollowingController
from firefleet.scenarios.schema import PathFollowing
from firefleet.sim.result import SimResult

__all__ = ["controller_png", "figures"]

_MARKERS = 10
"""Markers at this many equal time steps on a team's trajectories (Figures 32, 36)."""


def _png(fig: matplotlib.figure.Figure, *, dpi: int = 110) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi)
    plt.close(fig)
    return buffer.getvalue()


def _colours(n: int) -> list[tuple[float, float, float, float]]:
    cmap = matplotlib.colormaps["tab10"]
    return [cmap(i % 10) for i in range(n)]


def _trajectory(result: SimResult) -> bytes:
    """Paths against the true trajectories, markers at equal times (Figures 26, 30-32, 36)."""
    cmd = result.scenario.command
    assert isinstance(cmd, PathFollowing)
    xy = result.pose[:, :, :2]
    n = xy.shape[1]
    fig, ax = plt.subplots(figsize=(8.5, 6.0))
    marks = np.linspace(0, result.t.size - 1, _MARKERS + 1).astype(int)
    for i, (path, colour) in enumerate(zip(cmd.paths, _colours(n), strict=True)):
        xs = np.linspace(path.x_start_m, path.x_end_m, 400)
        ax.plot(xs, path.y(xs), "--", color=colour, lw=1.0, alpha=0.8)
        ax.plot(xy[:, i, 0], xy[:, i, 1], "-", color=colour, lw=1.8, label=f"robot {i + 1}")
        ax.plot(xy[marks, i, 0], xy[marks, i, 1], "o", color=colour, ms=5, mfc="white")
        ax.plot(*xy[0, i], "s", color=colour, ms=7)
        ax.plot(path.x_end_m, path.y(path.x_end_m), "*", color=colour, ms=11)
    ax.plot([], [], "k--", lw=1, label="path (dashed)")
    ax.plot([], [], "ks", ms=6, label="start")
    ax.plot([], [], "ko", mfc="white", ms=5, label=f"every {result.t[-1] / _MARKERS:g} s")
    ax.plot([], [], "k*", ms=9, label="path end")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    ax.set_title(f"{result.scenario.name}: trajectories (solid) against paths (dashed)")
    fig.tight_layout()
    return _png(fig)


def _series(result: SimResult) -> bytes:
    """v, omega and y_err against time (Figures 27-29, 33-35, 37)."""
    t = result.t
    v = result.extra["v_ref_m_s"]
    omega = result.extra["omega_ref_rad_s"]
    y_err = result.extra["y_err_m"]
    wheel = result.wheel_speed_rad_s
    geom = result.scenario.robot
    v_true = geom.wheel_radius_m * wheel.mean(axis=2)
    n = v.shape[1]
    fig, axes = plt.subplots(3, 1, figsize=(8.5, 8.0), sharex=True)
    for i, colour in enumerate(_colours(n)):
        axes[0].plot(t, v_true[:, i], color=colour, lw=1.4, label=f"robot {i + 1}")
        axes[0].plot(t, v[:, i], color=colour, lw=0.7, ls=":", alpha=0.9)
        axes[1].plot(t, np.degrees(omega[:, i]), color=colour, lw=1.0)
        axes[2].plot(t, y_err[:, i], color=colour, lw=1.2)
    axes[0].plot([], [], "k:", lw=0.8, label="fuzzy set point")
    axes[0].set_ylabel("linear velocity v [m/s]")
    axes[0].legend(fontsize=8, ncol=4, loc="upper right")
    axes[1].set_ylabel("angular velocity\nset point [deg/s]")
    axes[2].set_ylabel("y_err [m] (eq. 10)")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].set_title(f"{result.scenario.name}: velocities and y_err")
    fig.tight_layout()
    return _png(fig)


def _surface(
    ax: Axes3D,
    grid_x: NDArray[np.float64],
    grid_y: NDArray[np.float64],
    z: NDArray[np.float64],
    labels: tuple[str, str, str],
    title: str,
) -> None:
    ax.plot_surface(grid_x, grid_y, z, cmap="viridis", linewidth=0, antialiased=True)
    ax.set_xlabel(labels[0], fontsize=11, labelpad=6)
    ax.set_ylabel(labels[1], fontsize=11, labelpad=6)
    ax.set_zlabel(labels[2], fontsize=11, labelpad=6)
    ax.set_title(title, fontsize=12)
    ax.tick_params(labelsize=10)


def _memberships(ax: matplotlib.axes.Axes, system: SugenoSystem, index: int, title: str) -> None:
    var = system.inputs[index]
    lo, hi = var.range
    xs = np.linspace(lo, hi, 601)
    for mf in var.mfs:
        ax.plot(xs, membership(mf.kind, mf.params, xs), label=mf.name)
    ax.set_title(title, fontsize=12)
    ax.set_ylabel("membership", fontsize=11)
    ax.set_ylim(-0.02, 1.05)
    ax.legend(fontsize=9, loc="center right")
    ax.grid(alpha=0.3)
    ax.tick_params(labelsize=10)


def _axes3d(fig: matplotlib.figure.Figure, index: int) -> Axes3D:
    ax = fig.add_subplot(3, 3, index, projection="3d")
    assert isinstance(ax, Axes3D)
    return ax


def controller_png(controller: PathFollowingController) -> bytes:
    """The controller: membership functions and control surfaces (Figures 14-17, 20-23)."""
    main, lam = controller.main, controller.correction
    fig = plt.figure(figsize=(13, 12))
    _memberships(fig.add_subplot(3, 3, 1), main, 0, "Fig. 14: D_rp [m]")
    _memberships(fig.add_subplot(3, 3, 2), main, 2, "Fig. 15: alpha [deg]")
    _memberships(fig.add_subplot(3, 3, 3), lam, 0, "Fig. 20: y_err [m]")
    d, a = np.meshgrid(np.linspace(0, 3, 41), np.linspace(-180, 180, 41))
    flat = np.stack([d.ravel(), np.full(d.size, 1.0), a.ravel()], axis=1)
    out = evaluate(main, flat)
    _surface(
        _axes3d(fig, 4),
        d,
        a,
        out[:, 0].reshape(d.shape),
        ("D_rp [m]", "alpha [deg]", "v [m/s]"),
        "Fig. 16: v(D_rp, alpha), x_err = 1 m",
    )
    _surface(
        _axes3d(fig, 5),
        d,
        a,
        out[:, 1].reshape(d.shape),
        ("D_rp [m]", "alpha [deg]", "omega [deg/s]"),
        "Fig. 17: omega(D_rp, alpha), x_err = 1 m",
    )
    ys = np.linspace(-3, 3, 301)
    ax = fig.add_subplot(3, 3, 6)
    ax.plot(ys, evaluate(lam, ys[:, None])[:, 0], color="tab:purple")
    ax.set_title("Fig. 21: lambda(y_err) [deg]", fontsize=12)
    ax.set_xlabel("y_err [m]", fontsize=11)
    ax.set_ylabel("lambda [deg]", fontsize=11)
    ax.grid(alpha=0.3)
    ax.tick_params(labelsize=10)
    xe, d2 = np.meshgrid(np.linspace(-0.3, 0.3, 41), np.linspace(0, 3, 41))
    out = evaluate(main, np.stack([d2.ravel(), xe.ravel(), np.zeros(d2.size)], axis=1))
    _surface(
        _axes3d(fig, 7),
        xe,
        d2,
        out[:, 0].reshape(d2.shape),
        ("x_err [m]", "D_rp [m]", "v [m/s]"),
        "Fig. 22: v(x_err, D_rp), alpha = 0",
    )
    xe3, a3 = np.meshgrid(np.linspace(-0.3, 0.3, 41), np.linspace(-180, 180, 41))
    out = evaluate(main, np.stack([np.full(a3.size, 0.5), xe3.ravel(), a3.ravel()], axis=1))
    _surface(
        _axes3d(fig, 8),
        xe3,
        a3,
        out[:, 1].reshape(a3.shape),
        ("x_err [m]", "alpha [deg]", "omega [deg/s]"),
        "Fig. 23: omega(x_err, alpha), D_rp = 0.5 m",
    )
    _memberships(fig.add_subplot(3, 3, 9), main, 1, "x_err [m] (range -3..3 m, zoomed)")
    fig.axes[-1].set_xlim(-0.2, 0.4)
    fig.suptitle("The fuzzy path-following controller (control/data/*.fis)", fontsize=14)
    fig.tight_layout(w_pad=4.0)
    # 1,040 px wide: the report shows it at about its own size, 10-12 pt text stays legible
    return _png(fig, dpi=80)


def figures(result: SimResult) -> dict[str, bytes]:
    """The figures of a path-following run, as PNG bytes by file name."""
    cmd = result.scenario.command
    assert isinstance(cmd, PathFollowing)
    return {
        "trajectory.png": _trajectory(result),
        "velocities.png": _series(result),
        "controller.png": controller_png(PathFollowingController.from_command(cmd)),
    }
