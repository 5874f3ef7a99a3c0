"""Figures of a run: those its task kind draws (:mod:`firefleet.sim.registry`), and the
motor runs' figures.

matplotlib is imported only inside ``firefleet.report`` (this module and the topic
modules beside it), and only when a figure is made.
"""

from __future__ import annotations

import io
from collections.abc import Callable
from typing import cast

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from firefleet.scenarios.schema import VoltageStep, WheelSpeedStep
from firefleet.sim.registry import Metrics, task_kind
from firefleet.sim.result import SimResult

__all__ = ["figures", "voltage_step_figures", "wheel_speed_step_figures"]


def _png(fig: matplotlib.figure.Figure) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    return buffer.getvalue()


def _band(ax: matplotlib.axes.Axes, target: float) -> None:
    """Shade the 2 % settling band around ``target``."""
    half = 0.02 * abs(target)
    ax.axhspan(target - half, target + half, color="tab:green", alpha=0.15, label="2 % band")


def _speed_reference(ax: matplotlib.axes.Axes, result: SimResult) -> None:
    """The closed loop's reference, the encoder's speed and the 2 % band (Figure 25)."""
    cmd = cast(WheelSpeedStep, result.scenario.command)
    t = result.t
    ax.plot(t, result.wheel_speed_ref_rad_s[:, 0, 0], "k--", lw=1.2, label="reference")
    ax.plot(
        t,
        result.wheel_speed_measured_rad_s[:, 0, 0],
        color="0.7",
        lw=0.5,
        label=f"encoder ({result.scenario.encoder.counts_per_rev} counts/rev)",
    )
    _band(ax, cmd.speed_rad_s)


def _voltage_input(ax: matplotlib.axes.Axes, result: SimResult) -> None:
    """The analytic steady speed of the open loop (Figure 24), and a note on its input.

    The input is a voltage: it is drawn on the voltage axis below, not on this rad/s
    axis. The deliverable calls it the motor's "1 rad/sec reference": the note says so.
    """
    scn = result.scenario
    cmd = cast(VoltageStep, scn.command)
    ax.text(
        0.98,
        0.45,
        f'input: a {cmd.voltage_v:g} V step (bottom panel),\nthe deliverable\'s "reference"',
        transform=ax.transAxes,
        ha="right",
        va="center",
        fontsize=8,
        color="0.3",
    )
    steady = cmd.voltage_v * scn.motor.speed_gain_rad_s_per_v
    ax.axhline(
        steady,
        color="tab:red",
        ls=":",
        lw=1.2,
        label=f"Kt V / (R B + Ke Kt) = {steady:.4f} rad/s",
    )


def _motor_response(
    result: SimResult, draw_input: Callable[[matplotlib.axes.Axes, SimResult], None]
) -> bytes:
    """Speed, current and voltage against time (the layout of Figures 24 and 25)."""
    scn = result.scenario
    t = result.t
    w = result.wheel_speed_rad_s[:, 0, 0]  # robot 0, right wheel: all wheels are alike
    fig, axes = plt.subplots(3, 1, figsize=(8, 7.5), sharex=True, height_ratios=[3, 2, 1.4])
    ax = axes[0]
    draw_input(ax, result)
    ax.plot(t, w, color="tab:blue", lw=1.8, label="actual speed")
    if scn.load.torque_n_m != 0 and scn.load.start_s < t[-1]:
        for a in axes:
            a.axvline(scn.load.start_s, color="tab:orange", ls=":", lw=1)
        ax.annotate(
            f"load step {scn.load.torque_n_m:g} N m",
            (scn.load.start_s, 0.05),
            xycoords=("data", "axes fraction"),
            xytext=(4, 0),
            textcoords="offset points",
            color="tab:orange",
            fontsize=8,
        )
    ax.set_ylabel("wheel speed [rad/s]")
    ax.legend(loc="lower right", fontsize=8)
    ax.grid(alpha=0.3)
    ax.set_title(f"{scn.name}: {scn.title}", fontsize=10)
    axes[1].plot(t, result.current_a[:, 0, 0], color="tab:purple", lw=1.4)
    axes[1].set_ylabel("current [A]")
    axes[1].grid(alpha=0.3)
    axes[2].step(t, result.voltage_v[:, 0, 0], where="post", color="tab:brown", lw=1.0)
    vmax = max(float(np.abs(result.voltage_v[:, 0, 0]).max()), 1e-9)
    axes[2].set_ylim(-0.08 * vmax, 1.15 * vmax)
    axes[2].set_ylabel("voltage [V]")
    axes[2].set_xlabel("time [s]")
    axes[2].grid(alpha=0.3)
    fig.align_ylabels(axes)
    fig.tight_layout()
    return _png(fig)


def _transients(result: SimResult, metrics: Metrics) -> bytes:
    """Zoom on the speed step and the load step, with the 2 % band and the measured times."""
    scn = result.scenario
    cmd = cast(WheelSpeedStep, scn.command)
    t = result.t
    windows: list[tuple[str, float, object]] = [
        ("speed step", cmd.start_s, metrics.get("settling_time_s"))
    ]
    if scn.load.torque_n_m != 0 and scn.load.start_s < t[-1]:
        windows.append(
            (
                f"load step ({scn.load.torque_n_m:g} N m)",
                scn.load.start_s,
                metrics.get("disturbance_recovery_s"),
            )
        )
    fig, axes = plt.subplots(1, len(windows), figsize=(4.2 * len(windows), 3.6), squeeze=False)
    for ax, (label, t0, settle) in zip(axes[0], windows, strict=True):
        sel = (t >= t0 - 0.05) & (t <= t0 + 0.8)
        _band(ax, cmd.speed_rad_s)
        ax.step(
            t[sel],
            result.wheel_speed_measured_rad_s[sel, 0, 0],
            where="post",
            color="0.55",
            lw=0.8,
            label="encoder",
        )
        ax.plot(t[sel], result.wheel_speed_ref_rad_s[sel, 0, 0], "k--", lw=1, label="reference")
        ax.plot(
            t[sel],
            result.wheel_speed_rad_s[sel, 0, 0],
            ".-",
            color="tab:blue",
            lw=1.6,
            ms=3,
            label="actual",
        )
        if isinstance(settle, float) and np.isfinite(settle):
            ax.axvline(t0 + settle, color="tab:red", ls=":", lw=1.2)
            ax.annotate(
                f"in band for good\nafter {settle:.3f} s",
                (t0 + settle, 0.35),
                xycoords=("data", "axes fraction"),
                xytext=(4, 0),
                textcoords="offset points",
                color="tab:red",
                fontsize=8,
            )
        ax.set_title(label, fontsize=10)
        ax.set_xlabel("time [s]")
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("wheel speed [rad/s]")
    axes[0, 0].legend(loc="lower right", fontsize=7)
    fig.tight_layout()
    return _png(fig)


def voltage_step_figures(result: SimResult, metrics: Metrics) -> dict[str, bytes]:
    """The figures of a ``voltage-step`` run (Figure 24), PNG bytes by file name."""
    return {"response.png": _motor_response(result, _voltage_input)}


def wheel_speed_step_figures(result: SimResult, metrics: Metrics) -> dict[str, bytes]:
    """The figures of a ``wheel-speed-step`` run (Figure 25), PNG bytes by file name."""
    return {
        "response.png": _motor_response(result, _speed_reference),
        "transients.png": _transients(result, metrics),
    }


def figures(result: SimResult, metrics: Metrics) -> dict[str, bytes]:
    """The figures of a run, as PNG bytes by file name: those its task kind draws."""
    return task_kind(result.scenario.command.kind).figures(result, metrics)
