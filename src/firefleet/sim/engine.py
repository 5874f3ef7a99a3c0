"""The simulator: a fixed-step loop over the whole team.

Each tick, for N robots at once (batch-first arrays, no per-robot Python objects)::

    command (voltage, or wheel-speed reference)        (N, 2)
      -> control.pid       voltages from the encoder's measured speeds   (N, 2)
      -> models.motor      exact zero-order hold: currents, speeds, angles turned
      -> models.kinematics poses                                        (N, 3)
      -> models.encoder    counts and measured speeds                   (N, 2)

(the wheel stack of :mod:`firefleet.sim.drive`, shared with the formation runner and the
SLAM drive of :mod:`firefleet.sim.world`).

Randomness (the encoders' unknown initial phase) comes from one
``numpy.random.Generator`` seeded with the scenario's ``seed``: same seed, same arrays,
bit for bit.

The motor runs have two backends with the same arithmetic in the same order. ``"auto"``
runs the compiled team kernel of :mod:`firefleet.sim._kernels` (the models' compiled
scalar steps, fused; on every core from 64 robots). ``"array"`` steps the whole team
with NumPy, step by step (:mod:`firefleet.sim.drive`, on the models' public step
functions): the reference the kernel is tested against (tests/sim/test_kernels.py).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from firefleet.errors import InputError
from firefleet.scenarios.schema import (
    Formation,
    PathFollowing,
    Scenario,
    VoltageStep,
    WheelSpeedStep,
)
from firefleet.sim._kernels import run_motor_team
from firefleet.sim.cooperative import simulate_path_following
from firefleet.sim.drive import (
    discretise_drive,
    drive_init,
    drive_step,
    encoder_phase,
    speed_control,
)
from firefleet.sim.formation import simulate_formation
from firefleet.sim.result import SimResult

__all__ = ["ProgressCallback", "simulate"]

ProgressCallback = Callable[[int, int], None]
"""Called as ``progress(steps_done, steps_total)`` about a hundred times a run."""


def simulate(
    scenario: Scenario,
    *,
    seed: int | None = None,
    record_every: int = 1,
    progress: ProgressCallback | None = None,
    backend: Literal["auto", "array"] = "auto",
) -> SimResult:
    """Run a scenario.

    Parameters
    ----------
    scenario : Scenario
        The experiment.
    seed : int, optional
        Overrides ``scenario.seed``.
    record_every : int
        Record every k-th step (and the last); 1 records them all.
    progress : callable, optional
        ``progress(done, total)``, for a progress bar.
    backend : {"auto", "array"}
        How to step a motor run's team: compiled, or NumPy step by step (same arithmetic
        either way, see the module notes).

    Returns
    -------
    SimResult
        The recorded run; its ``scenario`` carries the seed used.
    """
    if seed is not None:
        if seed < 0:
            raise InputError(f"seed must be >= 0, got {seed}")
        scenario = dataclasses.replace(scenario, seed=seed)
    if record_every < 1:
        raise InputError(f"record_every must be >= 1, got {record_every}")
    if backend not in ("auto", "array"):
        raise InputError(f"backend must be 'auto' or 'array', got {backend!r}")
    n_steps = scenario.n_steps
    rec_steps = np.arange(0, n_steps + 1, record_every)
    if rec_steps[-1] != n_steps:  # the last step is always recorded
        rec_steps = np.r_[rec_steps, n_steps]
    cmd = scenario.command
    if isinstance(cmd, VoltageStep | WheelSpeedStep):
        return _simulate_motors(scenario, rec_steps, progress, backend)
    if isinstance(cmd, PathFollowing):
        return simulate_path_following(scenario, rec_steps, progress)
    if isinstance(cmd, Formation):
        return simulate_formation(scenario, rec_steps, progress)
    raise InputError(f"no simulator for a {cmd.kind} scenario")


def _simulate_motors(
    scenario: Scenario,
    rec_steps: NDArray[np.int64],
    progress: ProgressCallback | None,
    backend: Literal["auto", "array"],
) -> SimResult:
    """A voltage-step or wheel-speed-step run: every wheel gets the same command."""
    assert isinstance(scenario.command, VoltageStep | WheelSpeedStep)
    rng = np.random.default_rng(scenario.seed)
    dt = scenario.dt_s
    n_steps = scenario.n_steps
    n = scenario.n_robots
    enc_params = scenario.encoder
    phase = encoder_phase(enc_params, n, rng)
    stack = discretise_drive(scenario.robot, scenario.motor, scenario.speed_pid, enc_params, dt)
    cmd = scenario.command
    assert isinstance(cmd, VoltageStep | WheelSpeedStep)  # the dispatch in simulate()
    open_loop = isinstance(cmd, VoltageStep)
    step_value = cmd.voltage_v if isinstance(cmd, VoltageStep) else cmd.speed_rad_s
    t_rec = np.asarray(rec_steps * dt, dtype=np.float64)
    if backend == "auto":
        out = run_motor_team(
            stack,
            scenario.initial_poses,
            phase,
            open_loop=open_loop,
            level=step_value,
            level_start_s=cmd.start_s,
            load_torque_n_m=scenario.load.torque_n_m,
            load_start_s=scenario.load.start_s,
            n_steps=n_steps,
            rec_steps=rec_steps,
            progress=progress,
        )
        return SimResult(
            scenario=scenario,
            t=t_rec,
            pose=out["pose"],
            wheel_speed_rad_s=out["speed"],
            wheel_speed_measured_rad_s=out["measured"],
            wheel_speed_ref_rad_s=out["ref"],
            current_a=out["current"],
            voltage_v=out["voltage"],
            load_torque_n_m=out["load"],
        )

    drive = drive_init(scenario.initial_poses, phase, stack)
    n_rec = rec_steps.size
    rec = {
        name: np.empty((n_rec, n, 2))
        for name in ("speed", "measured", "ref", "current", "voltage", "load")
    }
    pose_rec = np.empty((n_rec, n, 3))
    row = 0
    report_every = max(1, n_steps // 100)

    for k in range(n_steps + 1):
        t = k * dt
        load = np.full(
            (n, 2), scenario.load.torque_n_m if t >= scenario.load.start_s - 1e-9 else 0.0
        )
        level = step_value if t >= cmd.start_s - 1e-9 else 0.0
        if open_loop:
            ref = np.full((n, 2), np.nan)
            voltage = np.full((n, 2), level)
        else:
            ref = np.full((n, 2), level)
            drive, voltage = speed_control(drive, ref, stack)
        if row < n_rec and rec_steps[row] == k:
            pose_rec[row] = drive.pose
            rec["speed"][row] = drive.speed_rad_s
            rec["measured"][row] = drive.measured_rad_s
            rec["ref"][row] = ref
            rec["current"][row] = drive.current_a
            rec["voltage"][row] = voltage
            rec["load"][row] = load
            row += 1
        if k == n_steps:
            break
        drive = drive_step(drive, voltage, stack, load_torque_n_m=load)
        if progress is not None and (k + 1) % report_every == 0:
            progress(k + 1, n_steps)
    if progress is not None:
        progress(n_steps, n_steps)

    return SimResult(
        scenario=scenario,
        t=t_rec,
        pose=pose_rec,
        wheel_speed_rad_s=rec["speed"],
        wheel_speed_measured_rad_s=rec["measured"],
        wheel_speed_ref_rad_s=rec["ref"],
        current_a=rec["current"],
        voltage_v=rec["voltage"],
        load_torque_n_m=rec["load"],
    )
