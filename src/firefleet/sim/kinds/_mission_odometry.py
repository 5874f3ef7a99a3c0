"""The mission's pose estimate: dead reckoning on the loop's own arrays."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from firefleet.sim._kernels._stretch import odometry_arc
from firefleet.sim.drive import DriveStack, DriveState
from firefleet.sim.loop import Messages, Odometry, OdometryState

__all__ = ["MissionOdometry"]


@dataclass(frozen=True)
class MissionOdometry(Odometry):
    """:class:`~firefleet.sim.loop.Odometry` at the mission's 100 Hz: the encoders'
    count differences moved along their arc with the nominal geometry, the arithmetic
    of :func:`~firefleet.sim.drive.dead_reckoning` in one compiled call
    (:func:`~firefleet.sim._kernels._stretch.odometry_arc`, the scalar arc step of the
    kernels) without :func:`~firefleet.models.diff_drive_step`'s checks of its inputs.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.pid import PidParams
    >>> from firefleet.models import EncoderParams, MotorParams, RobotGeometry
    >>> from firefleet.sim.drive import discretise_drive, drive_init, drive_step
    >>> from firefleet.sim.loop import Odometry
    >>> stack = discretise_drive(RobotGeometry(), MotorParams(), PidParams(), EncoderParams(), 0.01)
    >>> drive = drive_init(np.zeros((2, 3)), np.zeros((2, 2)), stack)
    >>> a = b = MissionOdometry().init(drive.pose, drive)
    >>> for _ in range(50):
    ...     drive = drive_step(drive, [[6.0, 4.0], [3.0, 5.0]], stack)
    ...     a = MissionOdometry().step(a, drive, stack, {})
    ...     b = Odometry().step(b, drive, stack, {})
    >>> bool(np.array_equal(a.pose, b.pose)), bool(a.pose[0, 0] > 0.0)
    (True, True)
    """

    arc_odometry: ClassVar[bool] = True  # the loop's quiet stretches compute this step

    def step(
        self, state: OdometryState, drive: DriveState, stack: DriveStack, readings: Messages
    ) -> OdometryState:
        """The estimate moved by the counts since its last update (readings unused)."""
        counts = drive.encoder.history[-1]
        g = stack.geometry
        nominal = np.array([g.wheel_radius_m, g.axle_length_m, stack.count_angle_rad])
        return OdometryState(
            pose=odometry_arc(state.pose, state.counts, counts, nominal), counts=counts
        )
