"""The Arduino's controller logic in Python: what ``ff_motor.c`` does, for the fake board.

Commands, the 200 ms watchdog, the latched e-stop and the wheel-speed PID at 100 Hz, as
``firmware/arduino/PROTOCOL.md`` says and the sketch does; the PID is the simulator's own
(:func:`firefleet.control.pid.pid_step`), and the speed is the count difference over two
periods, as :mod:`firefleet.models.encoder` measures it. ``tests/robot`` holds this
class and the compiled C to the same voltages on the same commands.
"""

from __future__ import annotations

import math

import numpy as np

from firefleet.control.pid import PidParams, PidState, pid_init, pid_step
from firefleet.robot._messages import (
    ESTOP_ACTIVE,
    WATCHDOG_TRIPPED,
    EStop,
    EStopClear,
    Message,
    Pwm,
    Setpoint,
)

__all__ = ["FirmwareLogic"]

WATCHDOG_US = 200_000
PERIOD_US = 10_000
WINDOW = 2


class FirmwareLogic:
    """One board's controller state (``ff_motor`` of the sketch).

    Examples
    --------
    >>> from firefleet.robot import Pwm
    >>> from firefleet.robot._firmware_logic import FirmwareLogic
    >>> board = FirmwareLogic(counts_per_rev=2048, supply_v=12.0, now_us=0)
    >>> board.command(Pwm(0.5, -0.25), now_us=0)
    >>> board.tick(10_000, (0, 0))
    (6.0, -3.0)
    >>> board.tick(220_000, (0, 0))  # no command for 220 ms: the watchdog
    (0.0, 0.0)
    """

    def __init__(
        self,
        *,
        counts_per_rev: float,
        supply_v: float,
        now_us: int,
        pid: PidParams | None = None,
    ) -> None:
        self.pid = PidParams() if pid is None else pid
        self.counts_per_rad = counts_per_rev / (2.0 * math.pi)
        self.supply_v = supply_v
        self.last_command_us = now_us
        self.flags = WATCHDOG_TRIPPED
        self.mode = 0  # 0 stopped, 1 speed, 2 duty
        self.estop = False
        self.reference = np.zeros(2)
        self.duty = np.zeros(2)
        self.state: PidState = pid_init(np.zeros(2))
        self.history: list[tuple[int, int]] = []

    def command(self, message: Message, *, now_us: int) -> None:
        """Apply a decoded command from the Pi."""
        if isinstance(message, EStop):
            self.estop = True
            self.flags |= ESTOP_ACTIVE
            self.mode = 0
            return
        if isinstance(message, EStopClear):
            self.estop = False
            self.flags &= ~ESTOP_ACTIVE
            return
        if not isinstance(message, Setpoint | Pwm):
            return
        self.last_command_us = now_us
        self.flags &= ~WATCHDOG_TRIPPED
        if self.estop:
            return
        if isinstance(message, Setpoint):
            if self.mode != 1:
                self.state = pid_init(np.zeros(2))
            self.mode = 1
            self.reference = np.array([message.right_rad_s, message.left_rad_s])
        else:
            self.mode = 2
            self.duty = np.array([message.right, message.left])

    def tick(self, now_us: int, counts: tuple[int, int]) -> tuple[float, float]:
        """The 100 Hz period: the voltages [V] to hold until the next."""
        if not self.history:
            self.history = [counts] * (WINDOW + 1)
        else:
            self.history = [*self.history[1:], counts]
        if (now_us - self.last_command_us) & 0xFFFFFFFF > WATCHDOG_US:
            self.flags |= WATCHDOG_TRIPPED
            self.mode = 0
        dt_s = PERIOD_US * 1e-6
        old, new = np.array(self.history[0], float), np.array(self.history[-1], float)
        speed = (new - old) / (self.counts_per_rad * WINDOW * dt_s)
        if self.mode == 1:
            self.state, volts = pid_step(self.state, self.reference, speed, self.pid, dt_s)
        else:
            volts = self.duty * self.supply_v if self.mode == 2 else np.zeros(2)
            self.state = PidState(self.state.integral, self.state.derivative, speed)
        return float(volts[0]), float(volts[1])
