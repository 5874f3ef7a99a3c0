"""The world loop's recorder: the samples of a staged run, written at the ticks to record
(:mod:`firefleet.sim.loop`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from firefleet._typing import FloatArray

if TYPE_CHECKING:
    from firefleet.sim.drive import DriveState
    from firefleet.sim.loop import Messages, WheelCommand, WorldState

__all__ = ["Recorder", "Recording"]


@dataclass(frozen=True)
class Recording:
    """The samples of a staged run (T recorded ticks, N robots).

    Attributes
    ----------
    t_s : ndarray, shape (T,)
        Time [s].
    pose : ndarray, shape (T, N, 3)
        True poses.
    wheel_speed_rad_s, wheel_speed_measured_rad_s, wheel_speed_ref_rad_s, current_a, \
voltage_v, load_torque_n_m : ndarray, shape (T, N, 2)
        The wheel stack's quantities (as :class:`~firefleet.sim.result.SimResult`).
    series : dict of str to ndarray
        The decision's series (and the estimator's, if it has ``series(state)``, and
        the link's counters) by name, time first.
    final : dict of str to ndarray
        What the estimator gives at the end (``final(state)``, if it has one: a map).
    link_series : tuple of str
        The names of the link's counters among ``series`` (T,): cumulative messages
        sent, lost, ... (:meth:`Link.counters`).
    """

    t_s: FloatArray
    pose: FloatArray
    wheel_speed_rad_s: FloatArray
    wheel_speed_measured_rad_s: FloatArray
    wheel_speed_ref_rad_s: FloatArray
    current_a: FloatArray
    voltage_v: FloatArray
    load_torque_n_m: FloatArray
    series: dict[str, FloatArray]
    final: dict[str, FloatArray] = field(default_factory=dict)
    link_series: tuple[str, ...] = ()


class Recorder:
    """The samples of a run, written at the ticks to record."""

    def __init__(self, rec_steps: NDArray[np.int64], n_robots: int) -> None:
        self.rec_steps = rec_steps
        self.recorded: list[int] = []
        self.row = 0
        size = rec_steps.size
        self.pose = np.empty((size, n_robots, 3))
        self.wheel = {
            name: np.empty((size, n_robots, 2))
            for name in ("speed", "measured", "ref", "current", "voltage", "load")
        }
        self.series: dict[str, FloatArray] = {}
        self.link_series: list[str] = []

    def record(
        self,
        k: int,
        drive: DriveState,
        command: WheelCommand,
        voltage: FloatArray,
        world: WorldState,
        counters: Mapping[str, float],
        *,
        force: bool = False,
    ) -> None:
        """Record tick ``k`` if it is the next to record (or ``force``: the last)."""
        row = self.row
        if row >= self.rec_steps.size or (self.rec_steps[row] != k and not force):
            return
        self.recorded.append(k)
        self.pose[row] = drive.pose
        self.wheel["speed"][row] = drive.speed_rad_s
        self.wheel["measured"][row] = drive.measured_rad_s
        self.wheel["ref"][row] = command.reference_rad_s
        self.wheel["current"][row] = drive.current_a
        self.wheel["voltage"][row] = voltage
        self.wheel["load"][row] = world.load_torque_n_m
        for name, count in counters.items():
            if name not in self.series:
                self.series[name] = np.empty(self.rec_steps.size)
                self.link_series.append(name)
            self.series[name][row] = count
        for name, value in command.series.items():
            if name not in self.series:
                self.series[name] = np.empty((self.rec_steps.size, *np.shape(value)))
            self.series[name][row] = value
        self.row += 1

    def recording(self, dt_s: float, final: Messages) -> Recording:
        """The samples recorded (fewer than planned if the task ended early)."""
        m = self.row
        return Recording(
            t_s=np.asarray(np.array(self.recorded, dtype=np.int64) * dt_s, dtype=np.float64),
            pose=self.pose[:m],
            wheel_speed_rad_s=self.wheel["speed"][:m],
            wheel_speed_measured_rad_s=self.wheel["measured"][:m],
            wheel_speed_ref_rad_s=self.wheel["ref"][:m],
            current_a=self.wheel["current"][:m],
            voltage_v=self.wheel["voltage"][:m],
            load_torque_n_m=self.wheel["load"][:m],
            series={name: value[:m] for name, value in self.series.items()},
            final=dict(final),
            link_series=tuple(self.link_series),
        )
