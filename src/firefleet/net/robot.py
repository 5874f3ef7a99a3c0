"""One robot's controller stack as its own process: ``python -m firefleet.net.robot``.

The process holds what the robot itself computes (Figure 10's upper half): its pose
estimate (odometry: dead reckoning of the encoder counts the plant's sensors send), the
task kind's decision (coordination, the fuzzy controller, the wheel-speed references),
and nothing of the world. Each tick, on the plant's :class:`~firefleet.net.messages.Sensors`
for it, it updates its odometry, runs the kind's ``decide`` and answers with a
:class:`~firefleet.net.messages.Command` (its references and the series the kind
records) and a :class:`~firefleet.net.messages.State` (its pose, wheel speeds and
progress) for the team.

The kind's decision is the in-process one, unchanged: it is called on the whole team's
arrays, this robot's row holding its own estimate and the other rows the last
positions the team heard (their ``State`` messages), with the inbox the in-process
ideal link would deliver (the team's broadcast of the last tick, which the plant relays
in :class:`~firefleet.net.messages.TeamProgress`: :func:`team_inbox`), and this robot's
row of the result is what it sends. A kind whose decision reads no other robot's pose
(:data:`INDEPENDENT_KINDS`: path following, whose robots share only their progress
broadcast, and the motor steps) thus gives exactly the in-process numbers, and its
robots do not listen to one another's states; a kind that reads its neighbours' poses
would see them as the network delivers them.

It also watches the team's liveliness tokens: a robot whose process dies is noticed
here when its token goes (``lost``: the monotonic time, comparable across the
processes of one machine). The scenario comes pickled on stdin (from the plant that
started the process); at the end the process writes its network counters and what it
noticed as one JSON line on stdout.
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import queue
import sys
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from firefleet._typing import FloatArray
from firefleet.net.messages import (
    PLANT,
    Bye,
    Command,
    Hello,
    Sensors,
    State,
    TeamProgress,
    Tick,
)
from firefleet.net.transport import Counters, Keys, open_session, robot_of_key
from firefleet.scenarios.schema import PathFollowing, Scenario
from firefleet.sim.drive import dead_reckoning, discretise_drive
from firefleet.sim.loop import DecideInputs, Decider
from firefleet.sim.registry import task_kind

__all__ = ["INDEPENDENT_KINDS", "PathProgress", "RobotController", "flat_series", "main"]

INDEPENDENT_KINDS = frozenset({"path-following", "wheel-speed-step", "voltage-step"})
"""Kinds whose decision reads no other robot's pose (what they share goes through the
broadcast): their processes do not listen to the team's states (each would decode N - 1
messages a tick for nothing)."""

_HELLO_EVERY_S = 0.1
"""Hello is repeated this often [s] until the plant's first message arrives."""
_TEAM_WAIT_S = 0.5
"""How long a tick's sensors wait for the last tick's team broadcast [s] before the
robot decides with what it holds (counted: ``stale_ticks``)."""
_IDLE_LIMIT_S = 30.0
"""A robot that hears nothing from the plant for this long [s] leaves (timed out)."""


def flat_series(series: dict[str, Any], names: Sequence[str], robot: int) -> tuple[float, ...]:
    """One robot's values of a decision's series, flattened in the order of ``names``.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.net.robot import flat_series
    >>> series = {"a": np.array([1.0, 2.0]), "b": np.array([[3.0, 4.0], [5.0, 6.0]])}
    >>> flat_series(series, ("a", "b"), 1)
    (2.0, 5.0, 6.0)
    """
    parts = [np.ravel(np.asarray(series[name], dtype=np.float64)[robot]) for name in names]
    return tuple(float(v) for v in np.concatenate(parts)) if parts else ()


Shapes = tuple[tuple[str, tuple[int, ...]], ...]


@dataclass(frozen=True)
class DecisionLayout:
    """Where a robot's values sit in its :class:`~firefleet.net.messages.Command`.

    Attributes
    ----------
    series : tuple of (name, shape)
        The kind's recorded series, each with its shape per robot, in order.
    outbox : tuple of (name, shape)
        What the kind broadcasts to the team (``WheelCommand.outbox``), likewise; these
        follow the series in a command and fill a :class:`TeamProgress` row.
    """

    series: Shapes
    outbox: Shapes

    @property
    def series_size(self) -> int:
        """Values of the series per robot."""
        return sum(int(np.prod(shape)) for _, shape in self.series)

    @property
    def width(self) -> int:
        """Values of the broadcast per robot."""
        return sum(int(np.prod(shape)) for _, shape in self.outbox)

    def split(self, flat: FloatArray, part: str) -> dict[str, FloatArray]:
        """(N, size) values back into arrays (N, *shape) by name (``part``: ``"series"``
        or ``"outbox"``)."""
        out, at = {}, 0
        for name, shape in self.series if part == "series" else self.outbox:
            size = int(np.prod(shape))
            out[name] = flat[:, at : at + size].reshape((flat.shape[0], *shape))
            at += size
        return out


def decision_layout(scenario: Scenario, decider: Decider) -> DecisionLayout:
    """The layout of a kind's decision, from its decision at tick 0 on the start poses
    (what the plant and every robot compute alike).

    Examples
    --------
    >>> from firefleet import load_scenario
    >>> from firefleet.net.robot import decision_layout
    >>> from firefleet.sim.registry import task_kind
    >>> layout = decision_layout(load_scenario("motor-pid"), task_kind("wheel-speed-step").decider)
    >>> layout.series_size, layout.width
    (0, 0)
    """
    state, params = decider.init(scenario)
    pose = scenario.initial_poses.copy() if decider.uses_estimate else None
    _, command = decider.decide(state, DecideInputs(0.0, 0, pose, {}, {}), params, scenario.dt_s)
    return DecisionLayout(
        series=tuple((name, np.shape(command.series[name])[1:]) for name in decider.series),
        outbox=tuple((name, np.shape(value)[1:]) for name, value in command.outbox.items()),
    )


def team_inbox(team: TeamProgress, layout: DecisionLayout, dt_s: float) -> dict[str, FloatArray]:
    """The kind's inbox from the team's broadcast as relayed: with every robot alive and
    heard last tick, what the in-process ideal link delivers (each name (N, ...));
    otherwise, for each scalar name, what every robot holds from every sender
    (N, N), with ``<name>_age_s`` (N, N) [s] (+inf for a robot whose process is gone:
    the coordination leaves it out).

    Examples
    --------
    >>> import math
    >>> from firefleet.net.messages import PLANT, TeamProgress
    >>> from firefleet.net.robot import DecisionLayout, team_inbox
    >>> layout = DecisionLayout(series=(), outbox=(("zeta", ()),))
    >>> team = TeamProgress(1, PLANT, 4, width=1, values=(3.0, 2.5), age_s=(0.01, 0.01),
    ...                     alive=(True, True))
    >>> team_inbox(team, layout, 0.01)["zeta"].tolist()
    [3.0, 2.5]
    >>> gone = TeamProgress(1, PLANT, 4, width=1, values=(3.0, 2.5), age_s=(0.01, 0.03),
    ...                     alive=(True, False))
    >>> inbox = team_inbox(gone, layout, 0.01)
    >>> inbox["zeta"].shape, inbox["zeta_age_s"][0].tolist()
    ((2, 2), [0.01, inf])
    """
    n = len(team.alive)
    values = np.asarray(team.values, dtype=np.float64).reshape(n, team.width)
    named = layout.split(values, "outbox")
    age = np.where(np.asarray(team.alive), np.asarray(team.age_s, dtype=np.float64), np.inf)
    if np.all(age == dt_s):
        return named
    inbox: dict[str, FloatArray] = {}
    for name, value in named.items():
        if value.ndim == 1:
            inbox[name] = np.broadcast_to(value, (n, n)).copy()
            inbox[f"{name}_age_s"] = np.broadcast_to(age, (n, n)).copy()
    return inbox


class PathProgress:
    """A robot's progress along its path, tracked from its pose estimate.

    The path is tabulated once (``samples`` points, their arc lengths); each update
    looks for the nearest tabulated point within ``window`` points of the last one (a
    robot moves a few millimetres a tick), so it costs some microseconds, not the
    whole-path search of :meth:`firefleet.planning.paths.PolynomialPath.distance`.

    Parameters
    ----------
    path : PolynomialPath
        The robot's path.
    pieces : int
        Pieces the path is cut into (the trajectory's segments).

    Examples
    --------
    >>> from firefleet.net.robot import PathProgress
    >>> from firefleet.planning.paths import PolynomialPath
    >>> path = PolynomialPath((0.0, 0.0), 0.0, 10.0)  # y = 0 from x = 0 to 10 m
    >>> track = PathProgress(path, pieces=100)
    >>> track.update(2.5, 0.3)
    (25, 0.0)
    >>> segment, fraction = track.update(2.55, -0.1)
    >>> segment, round(fraction, 2)
    (25, 0.5)
    >>> PathProgress(path, pieces=100).update(12.0, 0.0)  # past the end
    (100, 0.0)
    """

    def __init__(self, path: Any, pieces: int, samples: int = 8193, window: int = 128) -> None:
        lo, hi = path.x_start_m, path.x_end_m
        self.x = np.linspace(lo, hi, samples)
        self.y = path.y(self.x)
        self.s = np.asarray(path.arc_length(self.x), dtype=np.float64)
        self.length_m = float(path.length_m)
        self.pieces = pieces
        self.window = window
        self.index: int | None = None  # the first update searches the whole path

    def update(self, x_m: float, y_m: float) -> tuple[int, float]:
        """The segment index and the fraction along it [0, 1) of the point nearest
        ``(x_m, y_m)``; at the path's end, (pieces, 0.0)."""
        near = self.index
        lo = 0 if near is None else max(near - self.window, 0)
        hi = self.x.size if near is None else min(near + self.window + 1, self.x.size)
        d2 = (self.x[lo:hi] - x_m) ** 2 + (self.y[lo:hi] - y_m) ** 2
        self.index = lo + int(np.argmin(d2))
        zeta = float(self.s[self.index]) / self.length_m * self.pieces
        segment = min(int(zeta), self.pieces)
        return segment, (min(zeta - segment, 1.0) if segment < self.pieces else 0.0)


class RobotController:
    """Robot ``robot``'s controller stack: odometry and the kind's decision, per tick.

    Parameters
    ----------
    scenario : Scenario
    robot : int
        Which robot (0-based).
    """

    def __init__(self, scenario: Scenario, robot: int) -> None:
        kind = task_kind(scenario.command.kind)
        if kind.decider is None:
            from firefleet.errors import InputError

            raise InputError(
                f"command.kind: {kind.name!r} runs its own loop; a team run needs a kind "
                "with a decision on the world loop"
            )
        self.decider: Decider = kind.decider
        self.robot = robot
        self.stack = discretise_drive(
            scenario.robot, scenario.motor, scenario.speed_pid, scenario.encoder, scenario.dt_s
        )
        self.dt_s = scenario.dt_s
        self.team_pose: FloatArray = scenario.initial_poses.copy()
        self.counts: FloatArray | None = None
        # a warm-up decision (caches, compiled kernels) before the plant's first tick,
        # so that tick 0 costs what every other tick does; then the memory afresh
        self.layout = decision_layout(scenario, self.decider)
        self.state, self.params = self.decider.init(scenario)
        self.inbox: dict[str, FloatArray] = {}
        self.team_tick = -1  # the tick of the last team broadcast heard
        cmd = scenario.command
        self.track = (
            PathProgress(cmd.paths[robot], cmd.pieces) if isinstance(cmd, PathFollowing) else None
        )

    def step(self, sensors: Sensors) -> tuple[Command, State]:
        """The command and state of tick ``sensors.tick`` from its sensor readings."""
        i = self.robot
        counts = np.array([sensors.counts])
        if self.counts is not None:  # the encoders have counted since the last tick
            self.team_pose[i] = dead_reckoning(
                self.team_pose[i : i + 1], self.counts, counts, self.stack
            )[0]
        self.counts = counts
        estimate = self.team_pose.copy() if self.decider.uses_estimate else None
        inputs = DecideInputs(sensors.t_s, sensors.tick, estimate, {}, self.inbox)
        self.state, decision = self.decider.decide(self.state, inputs, self.params, self.dt_s)
        reference = decision.reference_rad_s[i]
        series = flat_series(dict(decision.series), self.decider.series, i) + flat_series(
            dict(decision.outbox), [name for name, _ in self.layout.outbox], i
        )
        head = (sensors.run_id, i, sensors.tick)
        command = Command(
            *head,
            t_s=sensors.t_s,
            reference_rad_s=(float(reference[0]), float(reference[1])),
            series=series,
        )
        pose = self.team_pose[i]
        segment, fraction = (0, 0.0) if self.track is None else self.track.update(pose[0], pose[1])
        flags = np.asarray(getattr(self.state, "arrived", self.state))
        arrived = flags[i] if flags.ndim == 1 else False
        state = State(
            *head,
            t_s=sensors.t_s,
            pose=(float(pose[0]), float(pose[1]), float(pose[2])),
            wheel_speed_rad_s=(float(sensors.measured_rad_s[0]), float(sensors.measured_rad_s[1])),
            segment=segment,
            fraction=fraction,
            arrived=bool(arrived),
        )
        return command, state

    def hear_team(self, team: TeamProgress) -> None:
        """The team's broadcast of tick ``team.tick``: the next decision's inbox."""
        if team.width == self.layout.width and len(team.alive) == self.team_pose.shape[0]:
            self.inbox = team_inbox(team, self.layout, self.dt_s)
            self.team_tick = team.tick

    def hear(self, state: State) -> None:
        """Another robot's state, as heard: its row of the team's positions."""
        if state.robot != self.robot and state.robot < self.team_pose.shape[0]:
            self.team_pose[state.robot] = state.pose


def run_robot(scenario: Scenario, robot: int, run_id: int, connect: str) -> dict[str, Any]:
    """Run robot ``robot``'s process until the plant stops the run; its counters."""
    import zenoh

    n = scenario.n_robots
    keys = Keys(run_id)
    controller = RobotController(scenario, robot)
    counters = Counters()
    inbox: queue.SimpleQueue[Any] = queue.SimpleQueue()
    lock = threading.Lock()

    def on_sample(sample: Any) -> None:
        with lock:
            message = counters.receive(sample.payload.to_bytes(), run_id=run_id, n_robots=n)
        if message is not None:
            inbox.put(message)

    session = open_session(listen=["tcp/127.0.0.1:0"], connect=[connect])
    outcome = {"reason": 2}
    lost: dict[str, float] = {}  # robot (1-based) -> monotonic time its token went [s]
    stopping = threading.Event()

    def on_token(sample: Any) -> None:
        other = robot_of_key(str(sample.key_expr))
        if other is None or sample.kind != zenoh.SampleKind.DELETE or stopping.is_set():
            return
        lost.setdefault(str(other + 1), time.monotonic())

    try:
        token = session.liveliness().declare_token(keys.alive(robot))
        watch = session.liveliness().declare_subscriber(keys.alive_robots, on_token)

        def on_plant(sample: Any) -> None:  # the plant's process is gone: leave too
            if sample.kind == zenoh.SampleKind.DELETE:
                inbox.put(None)

        plant_watch = session.liveliness().declare_subscriber(keys.alive_plant, on_plant)
        subscribers = [
            session.declare_subscriber(keys.sensors(robot), on_sample),
            session.declare_subscriber(keys.clock, on_sample),
            session.declare_subscriber(keys.progress, on_sample),
        ]
        if scenario.command.kind not in INDEPENDENT_KINDS:
            subscribers.append(session.declare_subscriber(keys.state("*"), on_sample))
        pub_command = session.declare_publisher(
            keys.command(robot), congestion_control=zenoh.CongestionControl.BLOCK
        )
        pub_state = session.declare_publisher(keys.state(robot))
        hello = Hello(run_id, robot, 0, pid=os.getpid(), n_robots=n, dt_s=scenario.dt_s)
        started = False
        idle_s = 0.0
        pending: Sensors | None = None  # a tick's sensors, waiting for the team's broadcast
        since = 0.0
        stale_ticks = 0  # ticks decided without the last tick's broadcast (waited too long)

        def decide(sensors: Sensors) -> None:
            command, state = controller.step(sensors)
            with lock:
                data_c, data_s = counters.send(command), counters.send(state)
            pub_command.put(data_c)
            pub_state.put(data_s)

        while True:
            if not started:
                with lock:
                    session.put(keys.hello, counters.send(hello))
            wait_s = _HELLO_EVERY_S if not started or pending is not None else 1.0
            try:
                message = inbox.get(timeout=wait_s)
            except queue.Empty:
                message = False
                idle_s += wait_s
                if idle_s >= _IDLE_LIMIT_S:
                    outcome["reason"] = 3
                    break
            if message is None:
                break  # Bye "stopped": the plant died
            if message is not False:
                idle_s = 0.0
                started = True
            if isinstance(message, Sensors) and message.robot == robot:
                pending, since = message, time.monotonic()
            elif isinstance(message, TeamProgress) and message.robot == PLANT:
                controller.hear_team(message)
            elif isinstance(message, State):
                controller.hear(message)
            elif isinstance(message, Tick) and message.robot == PLANT and message.stop:
                stopping.set()
                outcome["reason"] = 0
                break
            if pending is not None:
                heard = controller.team_tick >= pending.tick - 1 or controller.layout.width == 0
                late = time.monotonic() - since > _TEAM_WAIT_S
                if pending.tick == 0 or heard or late:
                    stale_ticks += int(not heard and pending.tick > 0)
                    decide(pending)
                    pending = None
        with lock:
            session.put(
                keys.bye(robot), counters.send(Bye(run_id, robot, 0, reason=outcome["reason"]))
            )
        watch.undeclare()
        plant_watch.undeclare()
        for sub in subscribers:
            sub.undeclare()
        token.undeclare()
    finally:
        session.close()
    return {
        "robot": robot,
        "bye": outcome["reason"],
        "lost": lost,
        "stale_ticks": stale_ticks,
        **counters.document(),
    }


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m firefleet.net.robot --robot I --run-id HEX --connect ENDPOINT``
    (the scenario pickled on stdin)."""
    parser = argparse.ArgumentParser(prog="python -m firefleet.net.robot")
    parser.add_argument("--robot", type=int, required=True)
    parser.add_argument("--run-id", required=True)
    parser.add_argument("--connect", required=True)
    args = parser.parse_args(argv)
    scenario = pickle.load(sys.stdin.buffer)  # from the plant that started us
    if not isinstance(scenario, Scenario):
        return 2
    summary = run_robot(scenario, args.robot, int(args.run_id, 16), args.connect)
    sys.stdout.write(json.dumps(summary) + "\n")
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
