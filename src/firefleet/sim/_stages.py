"""The loop's default stages before the decision: the world, the sensors and the pose
estimate (see :mod:`firefleet.sim.loop`, which exports them).

A stage is an object with ``init`` and ``step`` (or ``read``) methods on batch-first
arrays; these are the ones a kind without a world of its own runs: a static world (a
load step and motor faults), no sensors or a true-pose sensor, odometry or no estimate.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

import numpy as np

from firefleet._typing import FloatArray
from firefleet.scenarios.schema import MotorFault
from firefleet.sim.drive import DriveStack, DriveState, dead_reckoning

__all__ = [
    "Estimation",
    "Messages",
    "NoEstimation",
    "NoSensors",
    "Odometry",
    "OdometryState",
    "Sensors",
    "StaticWorld",
    "TruePose",
    "WorldState",
]

Messages = Mapping[str, FloatArray]
"""Readings or messages by name, each a batch-first array."""


@dataclass(frozen=True)
class WorldState:
    """What the world holds at a tick.

    Attributes
    ----------
    load_torque_n_m : ndarray, shape (N, 2)
        Load torque on each wheel motor [N m], held over the tick.
    voltage_scale : ndarray, shape (N,), or None
        The fraction of its commanded voltage each robot's motors get (a motor fault);
        None: all of it.
    """

    load_torque_n_m: FloatArray
    voltage_scale: FloatArray | None = None


@dataclass(frozen=True)
class StaticWorld:
    """A world that does not change, but for the scenario's load step on the motors.

    Attributes
    ----------
    torque_n_m : float
        Load torque on every wheel motor from ``start_s`` on [N m] (0 before).
    start_s : float
        Time of the load step [s].
    faults : tuple of MotorFault
        Motor faults: robot ``robot`` (from 1) gets ``voltage_scale`` of its voltage
        from ``start_s`` (included) to ``end_s`` (excluded).
    """

    torque_n_m: float = 0.0
    start_s: float = 0.0
    faults: tuple[MotorFault, ...] = ()

    def init(self, n_robots: int) -> WorldState:
        """The world before the first tick."""
        return WorldState(load_torque_n_m=np.zeros((n_robots, 2)))

    def step(self, state: WorldState, t_s: float) -> WorldState:
        """The world at ``t_s``."""
        tau = self.torque_n_m if t_s >= self.start_s - 1e-9 else 0.0
        scale = None
        for fault in self.faults:
            if fault.start_s - 1e-9 <= t_s < fault.end_s - 1e-9:
                if scale is None:
                    scale = np.ones(state.load_torque_n_m.shape[0])
                scale[fault.robot - 1] *= fault.voltage_scale
        return WorldState(
            load_torque_n_m=np.full(state.load_torque_n_m.shape, tau), voltage_scale=scale
        )


@dataclass(frozen=True)
class NoSensors:
    """No sensor besides the wheel encoders (which belong to the wheel stack)."""

    def read(self, world: WorldState, drive: DriveState) -> Messages:
        """Readings by name: none."""
        return {}


@dataclass(frozen=True)
class TruePose:
    """A ground-truth pose sensor (motion capture): reading ``"pose"`` (N, 3), the true poses."""

    def read(self, world: WorldState, drive: DriveState) -> Messages:
        """Readings by name: ``{"pose": true poses}``."""
        return {"pose": drive.pose}


class Sensors(Protocol):
    """The sensors of the loop: readings by name from the world and the true state."""

    def read(self, world: WorldState, drive: DriveState) -> Messages: ...


@dataclass(frozen=True)
class OdometryState:
    """Dead-reckoned poses (N, 3) and the encoder counts (N, 2) they integrate up to."""

    pose: FloatArray
    counts: FloatArray


@dataclass(frozen=True)
class Odometry:
    """Pose estimate by dead reckoning: the encoders' count differences, nominal geometry.

    ``arc_odometry``: its step is the arc of the count differences that the quiet
    stretches compute (:func:`firefleet.sim._quiet_stretch.stretch_ok`); a subclass
    declares it itself.
    """

    arc_odometry: ClassVar[bool] = True

    def init(self, pose: FloatArray, drive: DriveState) -> OdometryState:
        """The estimate at the start: the true start poses."""
        return OdometryState(pose=pose.copy(), counts=drive.encoder.history[-1])

    def step(
        self, state: OdometryState, drive: DriveState, stack: DriveStack, readings: Messages
    ) -> OdometryState:
        """The estimate moved by the counts since its last update (readings unused)."""
        counts = drive.encoder.history[-1]
        return OdometryState(
            pose=dead_reckoning(state.pose, state.counts, counts, stack), counts=counts
        )

    def pose(self, state: OdometryState) -> FloatArray | None:
        """The estimated poses (N, 3)."""
        return state.pose


@dataclass(frozen=True)
class NoEstimation:
    """No pose estimate (a kind that does not use one, such as the motor runs)."""

    def init(self, pose: FloatArray, drive: DriveState) -> None:
        """Nothing to hold."""

    def step(self, state: None, drive: DriveState, stack: DriveStack, readings: Messages) -> None:
        """Nothing to update."""

    def pose(self, state: None) -> FloatArray | None:
        """No estimated pose."""
        return None


class Estimation(Protocol):
    """A pose estimator of the loop; ``step`` gets the readings the sensors stage gave
    this tick, by name."""

    def init(self, pose: FloatArray, drive: DriveState) -> Any: ...

    def step(self, state: Any, drive: DriveState, stack: DriveStack, readings: Messages) -> Any: ...

    def pose(self, state: Any) -> FloatArray | None: ...
