"""The team link on the robot: its progress out, its teammates' in, the lost-link e-stop.

Each control period the robot publishes its row of the task kind's broadcast (for path
following its progress ``zeta`` [segments] and rate [segments/s], the coordination of
:mod:`firefleet.sim.kinds.path_following`) as a :class:`~firefleet.net.messages.TeamProgress`
carrying its own row only, on ``firefleet/<run-id>/team/robot/<i>``
(:meth:`firefleet.net.transport.Keys.team`), and hears its teammates' on
``team/robot/*``. What it holds becomes the controller's inbox, as the plant's relay
would give it (:func:`firefleet.net.robot.team_inbox`): the values with their ages,
+inf for a teammate never heard or gone.

Lost-link e-stop: a teammate that has not said goodbye (its last message flags it not
alive: it arrived or was stopped) and from which nothing came for ``timeout_s`` (or
never, ``timeout_s`` after this robot's first period) trips the e-stop: the loop
commands zero wheel speeds from that period on. It is *latched*: it holds until every
teammate is heard again (each within ``timeout_s``) and has stayed so for ``rearm_s``;
then the robot drives again (the coordination lets the others catch up). Each trip is
recorded with the monotonic time it happened and who was silent (a teammate falling
silent while it holds joins it).

Examples
--------
>>> from firefleet.robot._teamlink import Watchdog
>>> dog = Watchdog(teammates=(1, 2), timeout_s=1.0, rearm_s=0.5, start_s=0.0)
>>> dog.heard(1, 0.1); dog.heard(2, 0.1)
>>> dog.check(1.0), dog.check(1.2)      # 1.1 s since robot 2 and 3 (1-based) spoke
(False, True)
>>> dog.heard(1, 1.3); dog.heard(2, 1.3)
>>> dog.check(1.4), dog.check(1.95)     # back; released rearm_s later
(True, False)
>>> len(dog.trips), dog.trips[0]["silent"]
(1, [2, 3])
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from firefleet.net.messages import TeamProgress
from firefleet.net.transport import Counters, Keys, robot_of_key

__all__ = ["TeamLink", "Watchdog"]


@dataclass
class Watchdog:
    """The lost-link e-stop's state (module notes); times on the monotonic clock [s].

    Parameters
    ----------
    teammates : tuple of int
        The other robots (0-based).
    timeout_s, rearm_s : float
        Silence that trips it; how long the link must be back to release it [s].
    start_s : float
        When the robot started (a teammate never heard counts as silent from then).
    """

    teammates: tuple[int, ...]
    timeout_s: float
    rearm_s: float
    start_s: float
    last: dict[int, float] = field(default_factory=dict)
    done: set[int] = field(default_factory=set)
    latched: bool = False
    back_since: float | None = None
    trips: list[dict[str, Any]] = field(default_factory=list)
    releases: int = 0
    stopped_s: float = 0.0
    _last_check: float | None = None

    def heard(self, robot: int, now_s: float, *, alive: bool = True) -> None:
        """A message from ``robot`` at ``now_s`` (``alive`` False: its goodbye)."""
        self.last[robot] = now_s
        if not alive:
            self.done.add(robot)

    def silent(self, now_s: float) -> list[int]:
        """Teammates (0-based) silent for more than ``timeout_s`` at ``now_s``."""
        return [
            j
            for j in self.teammates
            if j not in self.done and now_s - self.last.get(j, self.start_s) > self.timeout_s
        ]

    def check(self, now_s: float) -> bool:
        """Whether the robot is e-stopped at ``now_s`` (and update the latch)."""
        if self._last_check is not None and self.latched:
            self.stopped_s += now_s - self._last_check
        self._last_check = now_s
        lost = self.silent(now_s)
        if lost:
            self.back_since = None
            if not self.latched:
                self.latched = True
                quiet = [now_s - self.last.get(j, self.start_s) for j in lost]
                self.trips.append(
                    {"t_monotonic_s": now_s, "silent": [j + 1 for j in lost], "silent_s": quiet}
                )
            else:  # a teammate falling silent during the trip joins it (one event)
                trip = self.trips[-1]
                for j in lost:
                    if j + 1 not in trip["silent"]:
                        trip["silent"].append(j + 1)
                        trip["silent_s"].append(now_s - self.last.get(j, self.start_s))
        elif self.latched:
            if self.back_since is None:
                self.back_since = now_s
            if now_s - self.back_since >= self.rearm_s:
                self.latched = False
                self.back_since = None
                self.releases += 1
        return self.latched


class TeamLink:
    """The robot's end of the team link over a zenoh session (module notes).

    Parameters
    ----------
    session : zenoh.Session
        An open session (the plant's mesh with ``--sim``, the link's own otherwise).
    run_id : int
    robot, n_robots : int
    width : int
        Values per robot of the kind's broadcast.
    dt_s : float
        The control period [s].
    timeout_s, rearm_s : float
        The lost-link e-stop (:class:`Watchdog`).
    tick_ages : bool
        Ages from the ticks the messages carry (``--sim``: every robot runs the plant's
        ticks) rather than from the time they arrived.
    """

    def __init__(
        self,
        session: Any,
        run_id: int,
        robot: int,
        n_robots: int,
        width: int,
        dt_s: float,
        *,
        timeout_s: float,
        rearm_s: float,
        tick_ages: bool,
    ) -> None:
        self.keys = Keys(run_id)
        self.run_id, self.robot, self.n, self.width, self.dt_s = (
            run_id,
            robot,
            n_robots,
            width,
            dt_s,
        )
        self.tick_ages = tick_ages
        self.counters = Counters()
        self.cond = threading.Condition()
        nan_row = (math.nan,) * width
        self.rows: list[tuple[float, ...]] = [nan_row] * n_robots
        self.ticks = [-1] * n_robots
        self.arrived_s = [math.nan] * n_robots
        self.alive = [True] * n_robots
        self.dog = Watchdog(
            tuple(j for j in range(n_robots) if j != robot),
            timeout_s,
            rearm_s,
            start_s=math.inf,
        )
        self.started = False
        self.sub = session.declare_subscriber(self.keys.team("*"), self._on_sample)
        self.pub = session.declare_publisher(self.keys.team(robot))

    def _on_sample(self, sample: Any) -> None:
        now = time.monotonic()
        if robot_of_key(str(sample.key_expr)) == self.robot:
            return  # its own, echoed by the mesh
        with self.cond:
            msg = self.counters.receive(
                sample.payload.to_bytes(), run_id=self.run_id, n_robots=self.n
            )
            if not isinstance(msg, TeamProgress) or msg.robot == self.robot:
                return
            j = msg.robot
            if msg.width != self.width or len(msg.alive) != self.n:
                self.counters.dropped["layout"] += 1
                return
            self.rows[j] = tuple(msg.values[j * self.width : (j + 1) * self.width])
            self.ticks[j] = msg.tick
            self.arrived_s[j] = now
            self.alive[j] = msg.alive[j]
            self.dog.heard(j, now, alive=msg.alive[j])
            self.cond.notify_all()

    def publish(self, tick: int, row: tuple[float, ...], *, alive: bool = True) -> None:
        """This robot's broadcast of ``tick`` (``alive`` False: its goodbye)."""
        i = self.robot
        if len(row) != self.width:  # nothing decided yet
            row = (math.nan,) * self.width
        values = [math.nan] * (self.n * self.width)
        values[i * self.width : (i + 1) * self.width] = row
        ages = [math.inf] * self.n
        ages[i] = 0.0
        flags = [True] * self.n
        flags[i] = alive
        message = TeamProgress(
            self.run_id, i, tick, width=self.width, values=tuple(values),
            age_s=tuple(ages), alive=tuple(flags),
        )  # fmt: skip
        with self.cond:
            self.rows[i] = row
            self.ticks[i] = tick
            self.arrived_s[i] = time.monotonic()
            data = self.counters.send(message)
        self.pub.put(data)

    def wait_for(self, tick: int, timeout_s: float) -> None:
        """Wait up to ``timeout_s`` for every live teammate's broadcast of ``tick``."""
        end = time.monotonic() + timeout_s
        with self.cond:
            while True:
                behind = [
                    j
                    for j in self.dog.teammates
                    if self.alive[j] and j not in self.dog.done and self.ticks[j] < tick
                ]
                left = end - time.monotonic()
                if not behind or left <= 0:
                    return
                self.cond.wait(left)

    def progress(self, tick: int) -> TeamProgress | None:
        """What the team said, as the controller's inbox wants it at ``tick`` (None
        before anything was heard)."""
        now = time.monotonic()
        with self.cond:
            if all(t < 0 for t in self.ticks):
                return None
            ages = []
            for j in range(self.n):
                if self.ticks[j] < 0 or not self.alive[j]:
                    ages.append(math.inf)
                elif self.tick_ages:
                    ages.append(max(tick - self.ticks[j], 1) * self.dt_s)
                else:
                    ages.append(self.dt_s + max(now - self.arrived_s[j], 0.0))
            values = tuple(v for row in self.rows for v in row)
            return TeamProgress(
                self.run_id, self.robot, tick, width=self.width, values=values,
                age_s=tuple(ages), alive=tuple(self.alive),
            )  # fmt: skip

    def estopped(self) -> bool:
        """The lost-link e-stop at this instant (the first call starts its clock)."""
        now = time.monotonic()
        with self.cond:
            if not self.started:
                self.dog.start_s = now
                self.started = True
            return self.dog.check(now)

    def summary(self) -> dict[str, Any]:
        """The link's numbers: e-stop trips and releases, time stopped, counters."""
        with self.cond:
            return {
                "timeout_s": self.dog.timeout_s,
                "rearm_s": self.dog.rearm_s,
                "estops": len(self.dog.trips),
                "estop_trips": list(self.dog.trips),
                "releases": self.dog.releases,
                "estopped_s": self.dog.stopped_s,
                "latched_at_end": self.dog.latched,
                "teammates_done": sorted(j + 1 for j in self.dog.done),
                **self.counters.document(),
            }

    def close(self) -> None:
        """Stop hearing and publishing."""
        self.sub.undeclare()
        self.pub.undeclare()
