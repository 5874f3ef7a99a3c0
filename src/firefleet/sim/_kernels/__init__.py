"""Compiled (numba) team kernels, built only from the compiled scalar steps of the models.

Two fused loops run a whole team for a range of steps, each robot's state held in
registers while it runs the range (robots are independent: a team equals its robots run
one by one, and a parallel run equals a serial one bit for bit);
with ``coupled``, :func:`path_following_chunk` runs the team from one release tick to the
next instead, for the closed-loop coordination that couples the robots through their
broadcasts:

:func:`path_following_chunk`
    The cooperative path-following hierarchy (deliverable section 2.6, Figure 10): the
    trajectory's desired point, the controller's inputs (eqs. 9-11) on the odometry
    pose, the two fuzzy systems (:func:`firefleet.control.fuzzy_kernel.eval_one`), the
    wheel-speed PIDs, the motors, the true pose, the encoders and dead reckoning.
:func:`motor_team_chunk`
    The wheel stack alone under a voltage or wheel-speed step and a load step (the
    ``voltage-step`` and ``wheel-speed-step`` runs): :func:`firefleet.sim.drive.speed_control`
    and :func:`firefleet.sim.drive.drive_step` (without slip), fused.

The physics is not written here: each step calls the one compiled definition beside its
NumPy form (:func:`~firefleet.control.pid.pid_step_one`,
:func:`~firefleet.models.motor.motor_step_one`,
:func:`~firefleet.models.encoder.encoder_step_one`,
:func:`~firefleet.models.kinematics.diff_drive_step_one`,
:func:`~firefleet.models.kinematics.wrap_angle_one`); tests show each equals its NumPy
reference and each kernel equals the NumPy composition.

Numba's on-disk cache keys a compiled function on its own file only: after editing one
of those scalar steps, remove the caches (``make clean``) so these kernels compile again.
"""

from firefleet.sim._kernels._motor import (
    MOTOR_RECORD,
    motor_team_chunk,
    motor_team_chunk_parallel,
    run_motor_team,
)
from firefleet.sim._kernels._parallel import PARALLEL_MIN_ROBOTS, PARALLEL_MIN_ROBOTS_ONE_PIECE
from firefleet.sim._kernels._path_following import (
    path_following_chunk,
    path_following_chunk_parallel,
)

__all__ = [
    "MOTOR_RECORD",
    "PARALLEL_MIN_ROBOTS",
    "PARALLEL_MIN_ROBOTS_ONE_PIECE",
    "motor_team_chunk",
    "motor_team_chunk_parallel",
    "path_following_chunk",
    "path_following_chunk_parallel",
    "run_motor_team",
]
