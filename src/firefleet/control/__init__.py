"""Controllers: the low-level wheel-speed PID."""

from firefleet.control.pid import PidParams, PidState, pid_init, pid_step

__all__ = ["PidParams", "PidState", "pid_init", "pid_step"]
