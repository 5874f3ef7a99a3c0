"""The simulator: a fixed-step loop over the whole team.

Each tick, for N robots at once (batch-first arrays, no per-robot Python objects)::

    command (voltage, or wheel-speed reference)        (N, 2)
      -> control.pid       voltages from the encoder's measured speeds   (N, 2)
      -> models.motor      exact zero-order hold: currents, speeds, angles turned
      -> models.kinematics poses                                        (N, 3)
      -> models.encoder    counts and measured speeds                   (N, 2)

Randomness (the encoders' unknown initial phase) comes from one
``numpy.random.Generator`` seeded with the scenario's ``seed``: same seed, same arrays,
bit for bit.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from firefleet.control.pid import pid_init, pid_step
from firefleet.errors import InputError
from firefleet.models.encoder import encoder_init, encoder_step
from firefleet.models.kinematics import diff_drive_step
from firefleet.models.motor import discretise_motor, motor_step
from firefleet.scenarios.schema import Scenario, VoltageStep
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
    rng = np.random.default_rng(scenario.seed)
    dt = scenario.dt_s
    n_steps = scenario.n_steps
    n = scenario.n_robots
    motor = discretise_motor(scenario.motor, dt)
    enc_params = scenario.encoder
    pid_params = scenario.speed_pid
    cmd = scenario.command
    open_loop = isinstance(cmd, VoltageStep)
    step_value = cmd.voltage_v if isinstance(cmd, VoltageStep) else cmd.speed_rad_s

    pose = scenario.initial_poses
    current = np.zeros((n, 2))
    speed = np.zeros((n, 2))
    count_rad = 2.0 * np.pi / enc_params.counts_per_rev if enc_params.counts_per_rev else 0.0
    encoder = encoder_init(rng.uniform(0.0, count_rad, size=(n, 2)), enc_params)
    measured = np.zeros((n, 2))
    pid = pid_init(measured)

    rec_steps = np.unique(np.r_[np.arange(0, n_steps + 1, record_every), n_steps])
    n_rec = rec_steps.size
    t_rec = rec_steps * dt
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
            pid, voltage = pid_step(pid, ref, measured, pid_params, dt)
        if row < n_rec and rec_steps[row] == k:
            pose_rec[row] = pose
            rec["speed"][row] = speed
            rec["measured"][row] = measured
            rec["ref"][row] = ref
            rec["current"][row] = current
            rec["voltage"][row] = voltage
            rec["load"][row] = load
            row += 1
        if k == n_steps:
            break
        current, speed, dphi = motor_step(current, speed, voltage, load, motor)
        pose = diff_drive_step(pose, dphi, scenario.robot)
        encoder, _, measured = encoder_step(encoder, dphi, enc_params, dt)
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
