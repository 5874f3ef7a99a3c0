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
positions the team heard (their ``State`` messages), and this robot's row of the result
is what it sends. A kind whose robots are independent (:data:`INDEPENDENT_KINDS`: path
following, the motor steps) thus gives exactly the in-process numbers, and its robots do
not listen to one another; a kind that couples them would see its neighbours as the
network delivers them.

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
from firefleet.scenarios.schema import Scenario
from firefleet.sim.drive import dead_reckoning, discretise_drive
from firefleet.sim.loop import DecideInputs, Decider
from firefleet.sim.registry import task_kind

__all__ = ["RobotController", "flat_series", "main"]

INDEPENDENT_KINDS = frozenset({"path-following", "wheel-speed-step", "voltage-step"})
"""Kinds whose robots decide from their own row alone: their processes do not listen to
the team's states (each would decode N - 1 messages a tick for nothing)."""

_HELLO_EVERY_S = 0.1
"""Hello is repeated this often [s] until the plant's first message arrives."""
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
        state, params = self.decider.init(scenario)
        estimate = self.team_pose.copy() if self.decider.uses_estimate else None
        self.decider.decide(state, DecideInputs(0.0, 0, estimate, {}, {}), params, self.dt_s)
        self.state, self.params = self.decider.init(scenario)

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
        inputs = DecideInputs(sensors.t_s, sensors.tick, estimate, {}, {})
        self.state, decision = self.decider.decide(self.state, inputs, self.params, self.dt_s)
        reference = decision.reference_rad_s[i]
        series = flat_series(dict(decision.series), self.decider.series, i)
        head = (sensors.run_id, i, sensors.tick)
        command = Command(
            *head,
            t_s=sensors.t_s,
            reference_rad_s=(float(reference[0]), float(reference[1])),
            series=series,
        )
        index = decision.series.get("desired_index")
        segment = int(np.asarray(index)[i]) if index is not None else 0
        arrived = np.asarray(self.state)[i] if np.ndim(self.state) == 1 else False
        pose = self.team_pose[i]
        state = State(
            *head,
            t_s=sensors.t_s,
            pose=(float(pose[0]), float(pose[1]), float(pose[2])),
            wheel_speed_rad_s=(float(sensors.measured_rad_s[0]), float(sensors.measured_rad_s[1])),
            segment=max(segment, 0),
            fraction=0.0,
            arrived=bool(arrived),
        )
        return command, state

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
        while True:
            if not started:
                with lock:
                    session.put(keys.hello, counters.send(hello))
            try:
                message = inbox.get(timeout=_HELLO_EVERY_S if not started else 1.0)
            except queue.Empty:
                idle_s += _HELLO_EVERY_S if not started else 1.0
                if idle_s >= _IDLE_LIMIT_S:
                    outcome["reason"] = 3
                    break
                continue
            idle_s = 0.0
            started = True
            if isinstance(message, Sensors) and message.robot == robot:
                command, state = controller.step(message)
                with lock:
                    data_c, data_s = counters.send(command), counters.send(state)
                pub_command.put(data_c)
                pub_state.put(data_s)
            elif isinstance(message, State):
                controller.hear(message)
            elif isinstance(message, Tick) and message.robot == PLANT and message.stop:
                stopping.set()
                outcome["reason"] = 0
                break
            elif isinstance(message, TeamProgress):
                pass  # the team's progress and who is alive: for a coordinating kind
        with lock:
            session.put(
                keys.bye(robot), counters.send(Bye(run_id, robot, 0, reason=outcome["reason"]))
            )
        watch.undeclare()
        for sub in subscribers:
            sub.undeclare()
        token.undeclare()
    finally:
        session.close()
    return {"robot": robot, "bye": outcome["reason"], "lost": lost, **counters.document()}


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
