"""The plant over zenoh in place of the motor board: ``firefleet robot --sim ENDPOINT``.

The world process (``firefleet team SCENARIO --external --listen ENDPOINT``) simulates
the motors, the encoders and the robot's motion; this adapter is the robot's side of
it. It joins the plant's zenoh mesh at ``ENDPOINT``, holds a liveliness token
(``alive/robot/<i>``) and says hello until the first tick; then each tick the plant's
:class:`~firefleet.net.messages.Sensors` (encoder counts, measured wheel speeds, the
tick and its time) stand for the Arduino's encoder report, and the wheel references
the loop would send the Arduino go out as a :class:`~firefleet.net.messages.Command`
for that tick (with the kind's series, which the plant records). The plant's clock
paces the loop: a period starts when its sensors arrive.

The run id is the robot configuration's ``link.run_id`` (the plant's ``--run-id`` must
be the same); messages of another run are dropped and counted.
"""

from __future__ import annotations

import os
import threading
from typing import Any

from firefleet.net.messages import PLANT, Bye, Command, Hello, Sensors, Tick
from firefleet.net.transport import Counters, Keys

__all__ = ["SimMotors"]

_HELLO_EVERY_S = 0.1
"""Hello is repeated this often [s] until the plant's first sensors."""


class SimMotors:
    """The plant's motors and encoders for robot ``robot`` (module notes).

    Parameters
    ----------
    session : zenoh.Session
        A session connected to the plant's endpoint.
    run_id : int
    robot, n_robots : int
    dt_s : float
        The control period [s] (checked by the plant against its scenario's).
    """

    def __init__(self, session: Any, run_id: int, robot: int, n_robots: int, dt_s: float) -> None:
        import zenoh

        self.session = session
        self.keys = Keys(run_id)
        self.run_id, self.robot, self.n = run_id, robot, n_robots
        self.counters = Counters()
        self.cond = threading.Condition()
        self.latest: Sensors | None = None
        self.taken = -1  # the tick of the last sensors the loop took
        self.end: str | None = None  # "plant stopped" or "plant lost"
        self.hello = Hello(run_id, robot, 0, pid=os.getpid(), n_robots=n_robots, dt_s=dt_s)
        self.token = session.liveliness().declare_token(self.keys.alive(robot))
        self.subs = [
            session.declare_subscriber(self.keys.sensors(robot), self._on_sample),
            session.declare_subscriber(self.keys.clock, self._on_sample),
            session.liveliness().declare_subscriber(self.keys.alive_plant, self._on_plant),
        ]
        self.pub = session.declare_publisher(
            self.keys.command(robot), congestion_control=zenoh.CongestionControl.BLOCK
        )
        self.last_command: Command | None = None

    def _on_sample(self, sample: Any) -> None:
        with self.cond:
            msg = self.counters.receive(
                sample.payload.to_bytes(), run_id=self.run_id, n_robots=self.n
            )
            if isinstance(msg, Sensors) and msg.robot == self.robot:
                self.latest = msg
            elif isinstance(msg, Tick) and msg.robot == PLANT and msg.stop:
                self.end = "plant stopped"
            else:
                return
            self.cond.notify_all()

    def _on_plant(self, sample: Any) -> None:
        import zenoh

        if sample.kind == zenoh.SampleKind.DELETE:
            with self.cond:
                self.end = self.end or "plant lost"
                self.cond.notify_all()

    @property
    def crc_errors(self) -> int:
        """Messages dropped as invalid (the motor link's error counter's stand-in)."""
        return sum(self.counters.dropped.values())

    framing_errors = 0

    def next_sensors(self, stop: threading.Event) -> Sensors | None:
        """The next tick's sensors (blocking; saying hello until the first); None when
        the plant stops the run, the plant's process goes, or ``stop`` is set."""
        while True:
            with self.cond:
                if self.end is not None or stop.is_set():
                    return None
                if self.latest is not None and self.latest.tick > self.taken:
                    self.taken = self.latest.tick
                    return self.latest
                started = self.latest is not None
                if started:
                    self.cond.wait(0.05)
                    continue
                data = self.counters.send(self.hello)
            self.session.put(self.keys.hello, data)
            with self.cond:
                self.cond.wait(_HELLO_EVERY_S)

    def send(self, reference_rad_s: tuple[float, float], series: tuple[float, ...] = ()) -> None:
        """Wheel references [rad/s] for the tick last taken (with the kind's series)."""
        with self.cond:
            if self.latest is None:
                return
            command = Command(
                self.run_id, self.robot, self.taken, t_s=self.latest.t_s,
                reference_rad_s=reference_rad_s, series=series,
            )  # fmt: skip
            data = self.counters.send(command)
            self.last_command = command
        self.pub.put(data)

    def close(self) -> None:
        """Say goodbye (done when the plant stopped the run, else stopped) and leave
        the mesh."""
        with self.cond:
            reason = 0 if self.end == "plant stopped" else 2
            data = self.counters.send(Bye(self.run_id, self.robot, 0, reason=reason))
        self.session.put(self.keys.bye(self.robot), data)
        for sub in self.subs:
            sub.undeclare()
        self.pub.undeclare()
        self.token.undeclare()
