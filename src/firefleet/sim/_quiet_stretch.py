"""The staged loop's quiet stretches (:mod:`firefleet.sim.loop`'s notes): whether a run's
stages allow them, how many ticks the next one lasts, and running it.

A stretch starts after a tick whose decision returned its state unchanged and holds
while every stage is quiet: the world's step only moves its time, the sensors draw
nothing and read what they read, the link is ideal with nothing sent, and the decision
would answer the same (its ``quiet_ticks``). Its ticks then only turn the wheels:
:func:`firefleet.sim._kernels._stretch.stretch_drive` runs them in one compiled call,
and the stages are told once what those ticks would have done (the world's time and
the team's last pose, the sensors' tick count and each tick's true poses).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from firefleet.sim._kernels._stretch import (
    StretchConstants,
    drive_tick,
    stretch_constants,
    stretch_drive,
)
from firefleet.sim._link_stage import IdealLink
from firefleet.sim.drive import DriveStack, DriveState

if TYPE_CHECKING:
    from firefleet.sim.loop import (
        DecideInputs,
        HeldCommand,
        Messages,
        QuietTicks,
        Stages,
        WheelCommand,
        WorldState,
    )

__all__ = [
    "drive_tick",
    "held_command",
    "quiet_ticks",
    "run_stretch",
    "stretch_constants",
    "stretch_drive",
    "stretch_ok",
]


def stretch_ok(stages: Stages, drive: DriveState, rng: np.random.Generator | None) -> bool:
    """Whether the stages allow quiet stretches: a world and sensors that tell their
    quiet ticks (``quiet_ticks(world, k, dt_s, limit)``: from tick ``k`` on, the ticks
    where the world's step only moves its time, and the sensors' reading draws nothing
    and gives what it gave, with ``sensors.skip(world, poses)`` doing what their reads
    would have done with the true poses (m, N, 3)), the ideal link, the odometry (its
    class declaring ``arc_odometry``, no series), no slip and no odometry in the drive."""
    return (
        callable(getattr(stages.world, "quiet_ticks", None))
        and callable(getattr(stages.sensors, "quiet_ticks", None))
        and callable(getattr(stages.sensors, "skip", None))
        and type(stages.link) is IdealLink
        and bool(vars(type(stages.estimation)).get("arc_odometry", False))
        and getattr(stages.estimation, "series", None) is None
        and rng is None
        and drive.odometry is None
    )


def held_command(
    state: Any,
    before: Any,
    command: WheelCommand,
    inputs: DecideInputs,
    readings: Messages,
    k: int,
    dt_s: float,
    held: HeldCommand | None,
    quiet_readings: Callable[[Messages], Messages] | None,
) -> tuple[WheelCommand | None, DecideInputs]:
    """The command a stretch from tick ``k`` would hold, and the inputs its quiet test
    reads: after a tick (its ``inputs`` and ``readings``) that left the state as it was
    (``state is before``), its ``command`` and inputs; after one that changed it, what
    the decider's ``held`` gives with the sensors' ``quiet_readings`` (None without
    them); None too for a command with voltages or messages."""
    hold: WheelCommand | None = command
    if state is not before:  # what the next ticks read and would give
        hold = None
        if held is not None and quiet_readings is not None:
            from firefleet.sim.loop import DecideInputs

            inputs = DecideInputs(k * dt_s, k, inputs.pose_estimate, quiet_readings(readings), {})
            hold = held(state, inputs)
    if hold is None or hold.voltage_v is not None or hold.outbox:
        return None, inputs
    return hold, inputs


def quiet_ticks(
    stages: Stages,
    world: WorldState,
    quiet: QuietTicks | None,
    state: Any,
    inputs: DecideInputs,
    params: Any,
    k: int,
    dt_s: float,
    limit: int,
) -> int:
    """The quiet ticks from ``k`` on (at most ``limit``): quiet for every stage and the
    decision (``quiet``, :data:`~firefleet.sim.loop.QuietTicks`; None: none)."""
    if limit <= 0 or quiet is None:
        return 0
    m = int(stages.world.quiet_ticks(world, k, dt_s, limit))  # type: ignore[attr-defined]
    if m > 0:
        m = min(m, int(stages.sensors.quiet_ticks(world, k, dt_s, m)))  # type: ignore[attr-defined]
    if m > 0:
        m = min(m, int(quiet(state, inputs, params, k, dt_s, m)))
    return max(0, min(m, limit))


def run_stretch(
    m: int,
    k: int,
    drive: DriveState,
    stack: DriveStack,
    stages: Stages,
    world: WorldState,
    command: WheelCommand,
    estimate: Any,
    consts: StretchConstants | None,
) -> tuple[DriveState, Any, WorldState]:
    """The ticks ``k .. k + m - 1`` of a quiet stretch under the held ``command``: the
    drive and the odometry after them, and the world told of them (its step at the last
    tick, the held actions at the last pose); the sensors skip them."""
    from firefleet.sim.loop import OdometryState

    drive, odom_pose, odom_counts, poses = stretch_drive(
        m,
        drive,
        stack,
        command.reference_rad_s,
        world.voltage_scale,
        world.load_torque_n_m,
        estimate.pose,
        estimate.counts,
        consts,
    )
    world = stages.world.step(world, (k + m - 1) * stack.dt_s)
    stages.sensors.skip(world, poses)  # type: ignore[attr-defined]
    if command.actions:
        world = stages.world.act(world, command.actions, poses[-1])  # type: ignore[attr-defined]
    return drive, OdometryState(pose=odom_pose, counts=odom_counts), world
