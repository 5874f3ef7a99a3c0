"""A simulated Arduino motor board on a pseudo-terminal pair.

The fake opens a pty, puts its slave end in raw mode and offers its path as a serial
port (:attr:`FakeBoard.port`); an adapter opens that path exactly as it opens
``/dev/ttyACM0`` on a robot. Behind the master end a thread runs the board at 100 Hz on
a monotonic clock: it decodes the frames the adapter sends (the same decoder and
counters), applies them with :class:`~firefleet.robot._firmware_logic.FirmwareLogic` (the
sketch's logic), steps two Table 2 motors (:func:`firefleet.models.motor_step`, exact
ZOH) and their encoders, and answers with ENCODERS every period and STATUS every 100 ms
or when a flag changes. Its clock is its own tick count (``micros = ticks * 10 ms``), so
what it records (when the watchdog tripped) does not depend on how busy the machine is;
only when it runs does.

``corrupt_every`` flips one byte of every k-th outgoing frame, to test what the Pi side
does with a damaged stream.
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
import tty
from dataclasses import dataclass, field

import numpy as np

from firefleet.models import MotorParams, discretise_motor, motor_step
from firefleet.robot._firmware_logic import PERIOD_US, FirmwareLogic
from firefleet.robot._frames import FrameDecoder
from firefleet.robot._messages import LENGTHS, Encoders, Pwm, Setpoint, Status, pack, unpack

__all__ = ["BoardLog", "FakeBoard"]


@dataclass
class BoardLog:
    """What the fake board did, in its own clock.

    Attributes
    ----------
    ticks : int
        Periods run.
    commands : int
        Valid SETPOINT or PWM frames applied.
    watchdog_trips_us : list of int
        Board times at which the watchdog tripped [us].
    last_command_us : int
        Board time of the last valid SETPOINT or PWM [us].
    wheel_speed_rad_s : list of tuple
        True wheel speeds (right, left) after each period [rad/s].
    """

    ticks: int = 0
    commands: int = 0
    watchdog_trips_us: list[int] = field(default_factory=list)
    last_command_us: int = 0
    wheel_speed_rad_s: list[tuple[float, float]] = field(default_factory=list)


class FakeBoard:
    """A simulated Arduino on a pty (module notes). Use as a context manager.

    Examples
    --------
    >>> import time
    >>> from firefleet.robot import ArduinoLink, Encoders, Pwm
    >>> from firefleet.robot import FakeBoard
    >>> with FakeBoard() as board, ArduinoLink(board.port) as link:
    ...     for _ in range(30):
    ...         link.send(Pwm(0.5, 0.5))
    ...         time.sleep(0.01)
    ...     got = link.poll()
    >>> any(isinstance(m, Encoders) and m.right_counts > 0 for m in got)
    True
    """

    def __init__(
        self,
        *,
        motor: MotorParams | None = None,
        counts_per_rev: int = 2048,
        corrupt_every: int = 0,
    ) -> None:
        self._motor = discretise_motor(MotorParams() if motor is None else motor, PERIOD_US * 1e-6)
        self._supply_v = (MotorParams() if motor is None else motor).supply_v
        self._cpr = counts_per_rev
        self._corrupt_every = corrupt_every
        self._decoder = FrameDecoder(LENGTHS)
        self._logic = FirmwareLogic(
            counts_per_rev=counts_per_rev, supply_v=self._supply_v, now_us=0
        )
        self.log = BoardLog()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        self.port = os.ttyname(self._slave)
        self._sent = 0

    @property
    def receive_errors(self) -> int:
        """CRC and framing errors of what the board received."""
        return self._decoder.crc_errors + self._decoder.framing_errors

    def __enter__(self) -> FakeBoard:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def start(self) -> None:
        """Run the board's thread."""
        self._thread = threading.Thread(target=self._run, name="fake-arduino", daemon=True)
        self._thread.start()

    def close(self) -> None:
        """Stop the board and close the pty."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        for fd in (self._master, self._slave):
            with contextlib.suppress(OSError):
                os.close(fd)

    def _write(self, frame: bytes) -> None:
        self._sent += 1
        if self._corrupt_every and self._sent % self._corrupt_every == 0:
            damaged = bytearray(frame)
            damaged[len(damaged) // 2] ^= 0x5A
            frame = bytes(damaged)
        with contextlib.suppress(OSError):  # nobody reading: a UART drops bytes the same way
            os.write(self._master, frame)

    def _run(self) -> None:
        current = np.zeros(2)
        speed = np.zeros(2)
        angle = np.zeros(2)
        flags_sent = -1
        next_t = time.monotonic()
        period_s = PERIOD_US * 1e-6
        while not self._stop.is_set():
            now_us = (self.log.ticks * PERIOD_US) & 0xFFFFFFFF
            try:
                data = os.read(self._master, 4096)
            except (BlockingIOError, OSError):
                data = b""
            for frame in self._decoder.feed(data):
                message = unpack(frame)
                if message is None:
                    continue
                if isinstance(message, Setpoint | Pwm):
                    self.log.commands += 1
                    self.log.last_command_us = now_us
                self._logic.command(message, now_us=now_us)
            counts = tuple(int(c) for c in np.floor(angle * self._cpr / (2.0 * np.pi)))
            tripped_before = self._logic.flags & 1
            volts = self._logic.tick(now_us, (counts[0], counts[1]))
            if self._logic.flags & 1 and not tripped_before:
                self.log.watchdog_trips_us.append(now_us)
            current, speed, dphi = motor_step(current, speed, np.array(volts), 0.0, self._motor)
            angle = angle + dphi
            self.log.wheel_speed_rad_s.append((float(speed[0]), float(speed[1])))
            self._write(pack(Encoders(now_us, counts[0], counts[1])))
            if self.log.ticks % 10 == 0 or self._logic.flags != flags_sent:
                flags_sent = self._logic.flags
                self._write(pack(Status(flags_sent, self._supply_v, self.receive_errors)))
            self.log.ticks += 1
            next_t += period_s
            delay = next_t - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            else:
                next_t = time.monotonic()  # overrun: keep the period, do not catch up
