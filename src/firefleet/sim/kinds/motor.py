"""The motor runs: every wheel of the team gets the same step (deliverable section 2.4).

``voltage-step`` (open loop, Figure 24): every motor gets ``voltage_v`` from
``start_s`` on, the PIDs bypassed. ``wheel-speed-step`` (closed loop, Figure 25): every
wheel's speed reference steps to ``speed_rad_s`` at ``start_s``; the PIDs turn the
encoders' measured speeds into voltages. Both run on the world loop
(:mod:`firefleet.sim.loop`), the wheel stack of :mod:`firefleet.sim.drive`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.scenarios.schema import Scenario, VoltageStep, WheelSpeedStep
from firefleet.sim._kernels import run_motor_team
from firefleet.sim.drive import discretise_drive
from firefleet.sim.loop import DecideInputs, Decider, ProgressCallback, WheelCommand
from firefleet.sim.metrics import _crossing, recovery_time, step_response_info
from firefleet.sim.registry import Metrics, TaskKind
from firefleet.sim.result import SimResult

__all__ = ["KINDS", "StepParams", "voltage_step_metrics", "wheel_speed_step_metrics"]


_C = TypeVar("_C", VoltageStep, WheelSpeedStep)


def _command(scenario: Scenario, kind: type[_C]) -> _C:
    cmd = scenario.command
    if not isinstance(cmd, kind):
        raise InputError(f"command.kind: expected a {kind.__name__} command, got {cmd.kind!r}")
    return cmd


@dataclass(frozen=True)
class StepParams:
    """A step applied to every wheel of a team.

    Attributes
    ----------
    value : float
        The step's level: volts (``voltage-step``) or rad/s (``wheel-speed-step``).
    start_s : float
        When it steps [s] (0 before).
    n_robots : int
        Team size N.
    """

    value: float
    start_s: float
    n_robots: int

    def level(self, t_s: float) -> float:
        """The level at ``t_s``."""
        return self.value if t_s >= self.start_s - 1e-9 else 0.0


def _voltage_init(scenario: Scenario) -> tuple[None, StepParams]:
    cmd = _command(scenario, VoltageStep)
    return None, StepParams(cmd.voltage_v, cmd.start_s, scenario.n_robots)


def voltage_decide(
    state: None, inputs: DecideInputs, params: StepParams, dt_s: float
) -> tuple[None, WheelCommand]:
    """Open loop: every motor's voltage is the step's level (no speed reference)."""
    n = params.n_robots
    return state, WheelCommand(
        reference_rad_s=np.full((n, 2), np.nan),
        voltage_v=np.full((n, 2), params.level(inputs.t_s)),
    )


def _speed_init(scenario: Scenario) -> tuple[None, StepParams]:
    cmd = _command(scenario, WheelSpeedStep)
    return None, StepParams(cmd.speed_rad_s, cmd.start_s, scenario.n_robots)


def speed_decide(
    state: None, inputs: DecideInputs, params: StepParams, dt_s: float
) -> tuple[None, WheelCommand]:
    """Closed loop: every wheel's speed reference is the step's level."""
    return state, WheelCommand(
        reference_rad_s=np.full((params.n_robots, 2), params.level(inputs.t_s))
    )


def voltage_step_metrics(result: SimResult) -> Metrics:
    """Metrics of a ``voltage-step`` run (over every wheel of the team).

    ``steady_speed_rad_s`` and ``steady_current_a`` (mean over the last second, averaged
    over the wheels), ``peak_current_a``, ``time_constant_s`` (the slowest wheel's time
    from the step to 63.2 % of the steady speed, interpolated between samples).
    """
    cmd = _command(result.scenario, VoltageStep)
    t = result.t
    w = result.wheel_speed_rad_s.reshape(t.size, -1)  # (T, 2N)
    current = result.current_a.reshape(t.size, -1)
    out: Metrics = {"peak_current_a": float(np.abs(current).max())}
    last = t >= t[-1] - 1.0 + 1e-9
    steady = float(w[last].mean())
    out["steady_speed_rad_s"] = steady
    out["steady_current_a"] = float(current[last].mean())
    after = t >= cmd.start_s - 1e-12
    taus = [
        _crossing(
            t[after], w[after, j], int(np.argmax(w[after, j] >= 0.632 * steady)), 0.632 * steady
        )
        - cmd.start_s
        for j in range(w.shape[1])
    ]
    out["time_constant_s"] = float(max(taus))
    return out


def wheel_speed_step_metrics(result: SimResult) -> Metrics:
    """Metrics of a ``wheel-speed-step`` run (worst case over every wheel of the team).

    ``rise_time_s``, ``settling_time_s`` and ``overshoot_pct`` of the true wheel speed
    before the load step; ``steady_state_error_rad_s`` (distance of the mean speed over
    the second before the load step, or the run's end, from the reference);
    ``disturbance_recovery_s`` (from the load step until back inside the 2 % band for
    good; 0 without a load step); ``peak_current_a``; ``max_voltage_v``.
    """
    scn = result.scenario
    cmd = _command(scn, WheelSpeedStep)
    t = result.t
    w = result.wheel_speed_rad_s.reshape(t.size, -1)  # (T, 2N)
    current = result.current_a.reshape(t.size, -1)
    out: Metrics = {"peak_current_a": float(np.abs(current).max())}
    load = scn.load
    has_load = load.torque_n_m != 0 and load.start_s < t[-1]
    end = load.start_s if has_load else t[-1] + 1e-9
    pre = (t >= cmd.start_s - 1e-12) & (t < end)
    infos = [
        step_response_info(t[pre], w[pre, j], cmd.speed_rad_s, t0_s=cmd.start_s)
        for j in range(w.shape[1])
    ]
    for key in ("rise_time_s", "settling_time_s", "overshoot_pct"):
        out[key] = float(max(info[key] for info in infos))
    window = pre & (t >= end - 1.0)
    out["steady_state_error_rad_s"] = float(np.abs(w[window].mean(axis=0) - cmd.speed_rad_s).max())
    out["disturbance_recovery_s"] = (
        float(
            max(recovery_time(t, w[:, j], cmd.speed_rad_s, load.start_s) for j in range(w.shape[1]))
        )
        if has_load
        else 0.0
    )
    out["max_voltage_v"] = float(np.abs(result.voltage_v).max())
    return out


def _voltage_figures(result: SimResult, metrics: Metrics) -> dict[str, bytes]:
    from firefleet.report.plots import voltage_step_figures

    return voltage_step_figures(result, metrics)


def _speed_figures(result: SimResult, metrics: Metrics) -> dict[str, bytes]:
    from firefleet.report.plots import wheel_speed_step_figures

    return wheel_speed_step_figures(result, metrics)


def _motor_fused(
    scenario: Scenario,
    phase: FloatArray,
    rec_steps: NDArray[np.int64],
    progress: ProgressCallback | None,
    *,
    open_loop: bool,
) -> SimResult:
    """The default stages' motor run, compiled (:func:`firefleet.sim._kernels.run_motor_team`):
    the same wheel stack as the staged loop, bit for bit (tests/sim/test_loop.py)."""
    _, step = _voltage_init(scenario) if open_loop else _speed_init(scenario)
    stack = discretise_drive(
        scenario.robot, scenario.motor, scenario.speed_pid, scenario.encoder, scenario.dt_s
    )
    out = run_motor_team(
        stack,
        scenario.initial_poses,
        phase,
        open_loop=open_loop,
        level=step.value,
        level_start_s=step.start_s,
        load_torque_n_m=scenario.load.torque_n_m,
        load_start_s=scenario.load.start_s,
        n_steps=scenario.n_steps,
        rec_steps=rec_steps,
        progress=progress,
    )
    return SimResult(
        scenario=scenario,
        t=np.asarray(rec_steps * scenario.dt_s, dtype=np.float64),
        pose=out["pose"],
        wheel_speed_rad_s=out["speed"],
        wheel_speed_measured_rad_s=out["measured"],
        wheel_speed_ref_rad_s=out["ref"],
        current_a=out["current"],
        voltage_v=out["voltage"],
        load_torque_n_m=out["load"],
    )


KINDS = (
    TaskKind(
        name="voltage-step",
        metric_names=(
            "steady_speed_rad_s",
            "steady_current_a",
            "peak_current_a",
            "time_constant_s",
        ),
        metrics=voltage_step_metrics,
        figures=_voltage_figures,
        decider=Decider(init=_voltage_init, decide=voltage_decide),
        fused=functools.partial(_motor_fused, open_loop=True),
    ),
    TaskKind(
        name="wheel-speed-step",
        metric_names=(
            "rise_time_s",
            "settling_time_s",
            "overshoot_pct",
            "steady_state_error_rad_s",
            "disturbance_recovery_s",
            "peak_current_a",
            "max_voltage_v",
        ),
        metrics=wheel_speed_step_metrics,
        figures=_speed_figures,
        decider=Decider(init=_speed_init, decide=speed_decide),
        fused=functools.partial(_motor_fused, open_loop=False),
    ),
)
"""The two motor kinds."""
