"""A team run over the network: the plant here, each robot's controller its own process.

The plant (this process) is the world loop of :mod:`firefleet.sim.loop` run stage by
stage (:func:`~firefleet.sim.loop.run_staged`: the world, the wheel stack with its PIDs,
motors and encoders, the recorder), with two stages replaced: its sensors read each
robot's encoder counts and measured wheel speeds, and its decision is the network's.
Each tick it sends every robot its :class:`~firefleet.net.messages.Sensors`, collects
their :class:`~firefleet.net.messages.Command` (started by :mod:`firefleet.net.robot`,
one process per robot, over zenoh: :mod:`firefleet.net.transport`), and drives the
wheels with the references they sent.

Clocks:

- ``lockstep``: tick k waits for every live robot's command of tick k, up to
  ``timeout_s``; a command missing then is a *miss* (counted; the robot's last
  references are held). The run does not depend on the machine's speed: with an
  independent kind (path following) it equals the in-process staged run bit for bit.
- ``realtime``: tick k starts at ``t0 + k dt`` on the monotonic clock and a command is
  taken if it arrives before ``t0 + (k + 1) dt``; one that does not is a miss (counted;
  the last references are held), and dropped as *late* when it comes.

A robot whose process dies (its liveliness token goes: at once, or at the 0.8 s link
lease for a process that hangs) is marked failed at the tick the plant notices it: its
wheels get zero references from then on, its recorded series hold their last values,
the others carry on, and the team progress it is listed in says it is not alive. The
run then ends as usual.

Examples
--------
>>> from firefleet.net.team import CLOCKS
>>> CLOCKS
('lockstep', 'realtime')
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import pickle
import secrets
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.net.messages import MAX_SERIES, PLANT, Command, Hello, Sensors, TeamProgress, Tick
from firefleet.net.robot import DecisionLayout, decision_layout
from firefleet.net.transport import Counters, Keys, free_port, open_session, robot_of_key
from firefleet.scenarios.schema import Scenario
from firefleet.sim.drive import DriveState, discretise_drive, drive_init, encoder_phase
from firefleet.sim.loop import (
    DecideInputs,
    Decider,
    NoEstimation,
    ProgressCallback,
    Stages,
    StaticWorld,
    WheelCommand,
    WorldState,
    run_staged,
)
from firefleet.sim.registry import task_kind
from firefleet.sim.result import SimResult

__all__ = ["CLOCKS", "MAX_TEAM", "TeamRun", "run_team"]

CLOCKS = ("lockstep", "realtime")
"""The plant's clocks (see the module notes)."""

MAX_TEAM = 64
"""Most robot processes a team run starts."""

_START_TIMEOUT_S = 120.0
"""How long the plant waits for every robot's first hello [s]."""
_EXIT_TIMEOUT_S = 10.0
"""How long the plant waits for the robots to leave after the stop [s]."""


@dataclass(frozen=True)
class _NetSensors:
    """The plant's sensors for the robots: encoder counts and measured wheel speeds."""

    def read(self, world: WorldState, drive: DriveState) -> dict[str, FloatArray]:
        return {"counts": drive.encoder.history[-1], "measured_rad_s": drive.measured_rad_s}


@dataclass
class TeamRun:
    """What a team run measured about its network (besides the run itself).

    Attributes
    ----------
    run_id : int
    clock : str
    counters : Counters
        The plant's message counters.
    robots : list of dict
        Each robot process's own counters (its last line on stdout), by robot.
    misses : list of int
        Ticks each robot's command missed (lock-step timeout or real-time deadline).
    late : int
        Commands that arrived after their tick was over (dropped).
    failed : dict of int to dict
        Robots whose process died: the tick and the monotonic time [s] it was noticed.
    wall_s : float
        Wall-clock time of the ticks [s] (start-up and shut-down excluded).
    ticks : int
        Ticks run.
    start_s : float
        Start-up: from spawning the robot processes to every robot's hello [s].
    """

    run_id: int
    clock: str
    n_robots: int
    counters: Counters = field(default_factory=Counters)
    robots: list[dict[str, Any]] = field(default_factory=list)
    misses: list[int] = field(default_factory=list)
    failed: dict[int, dict[str, float]] = field(default_factory=dict)
    wall_s: float = 0.0
    ticks: int = 0
    start_s: float = 0.0
    late: int = 0

    def document(self) -> dict[str, Any]:
        """The network counters as metrics.json records them (``network``)."""
        dropped = dict(self.counters.dropped)
        for robot in self.robots:
            for reason, n in robot.get("dropped", {}).items():
                dropped[reason] = dropped.get(reason, 0) + n
        return {
            "transport": "zenoh",
            "run_id": f"{self.run_id:016x}",
            "clock": self.clock,
            "robots": self.n_robots,
            "ticks": self.ticks,
            "wall_s": self.wall_s,
            "ticks_per_s": self.ticks / self.wall_s if self.wall_s > 0 else None,
            "start_up_s": self.start_s,
            "misses": self.misses,
            "late_commands": self.late,
            "failed_robots": [i + 1 for i in sorted(self.failed)],
            "failures": {str(i + 1): v for i, v in sorted(self.failed.items())},
            "dropped_total": sum(dropped.values()),
            "dropped": dict(sorted(dropped.items())),
            "plant": self.counters.document(),
            "robot_processes": self.robots,
        }


class _Exchange:
    """The plant's side of the conversation: what has arrived, under one condition."""

    def __init__(self, run: TeamRun) -> None:
        self.run = run
        self.cond = threading.Condition()
        self.hello: set[int] = set()
        self.alive: set[int] = set()
        self.dead: set[int] = set()
        self.commands: dict[int, Command] = {}
        self.late = 0
        self.tick = 0
        self.stopping = False
        self.dt_s = math.nan  # the scenario's tick [s]: a hello with another is refused

    def on_sample(self, sample: Any) -> None:
        data = sample.payload.to_bytes()
        with self.cond:
            msg = self.run.counters.receive(
                data, run_id=self.run.run_id, n_robots=self.run.n_robots
            )
            if msg is None or msg.robot == PLANT:
                return
            if isinstance(msg, Hello):
                if msg.n_robots != self.run.n_robots or msg.dt_s != self.dt_s:
                    self.run.counters.dropped["mismatch"] += 1  # another scenario's robot
                    return
                self.hello.add(msg.robot)
            elif isinstance(msg, Command):
                if msg.tick == self.tick:
                    self.commands[msg.robot] = msg
                else:
                    self.late += 1
            self.cond.notify_all()

    def on_token(self, sample: Any) -> None:
        import zenoh

        robot = robot_of_key(str(sample.key_expr))
        if robot is None or robot >= self.run.n_robots:
            return
        with self.cond:
            if sample.kind == zenoh.SampleKind.PUT:
                self.alive.add(robot)
            elif robot in self.alive:
                self.alive.discard(robot)
                if self.stopping:  # leaving at the end of the run, not failing
                    return
                self.dead.add(robot)
                self.run.failed[robot] = {"tick": float(self.tick), "noticed_s": time.monotonic()}
            self.cond.notify_all()


def _spawn(
    scenario: Scenario, robot: int, run_id: int, endpoint: str, log: Any
) -> subprocess.Popen[bytes]:
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "firefleet.net.robot",
            "--robot",
            str(robot),
            "--run-id",
            f"{run_id:016x}",
            "--connect",
            endpoint,
        ],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=log,
        env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)},
    )
    assert proc.stdin is not None
    proc.stdin.write(pickle.dumps(scenario))
    proc.stdin.close()
    proc.stdin = None  # written and closed: communicate() must not flush it
    return proc


def run_team(
    scenario: Scenario,
    rec_steps: Any,
    *,
    clock: str = "lockstep",
    timeout_s: float = 1.0,
    progress: ProgressCallback | None = None,
    started: Callable[[dict[str, Any]], None] | None = None,
    external: bool = False,
    listen: str | None = None,
    run_id: int | None = None,
    wait_s: float = _START_TIMEOUT_S,
) -> tuple[SimResult, TeamRun]:
    """Run ``scenario`` with each robot's controller in its own process, over zenoh.

    Parameters
    ----------
    scenario : Scenario
        A scenario whose task kind decides on the world loop (path following, formation).
    rec_steps : ndarray of int
        Ticks to record (as :func:`firefleet.sim.loop.run_loop`).
    clock : {"lockstep", "realtime"}
    timeout_s : float
        Lock-step: how long a tick waits for a command before counting a miss [s].
    progress : callable, optional
        ``progress(done, total)`` between chunks of ticks.
    started : callable, optional
        Called once every robot has said hello, before the first tick, with
        ``{"run_id": int, "endpoint": the plant's zenoh endpoint, "pids": the robot
        processes' ids}``.
    external : bool
        Start no robot process: wait up to ``wait_s`` for the scenario's robots to join
        (their liveliness tokens and hellos), e.g. ``firefleet robot CONFIG --sim
        ENDPOINT`` on each (hardware in the loop); their summaries are their own.
    listen : str, optional
        The plant's endpoint (``tcp/127.0.0.1:PORT``; default a free port).
    run_id : int, optional
        The run's id (default random; external robots must know it: their
        configuration's ``link.run_id``).
    wait_s : float
        How long the plant waits for every robot to join [s].

    Returns
    -------
    result : SimResult
        As the in-process run records it.
    network : TeamRun
        The counters, misses and failures.

    Raises
    ------
    InputError
        For a kind without a decision on the world loop (or one whose command would carry
        more than :data:`~firefleet.net.messages.MAX_SERIES` values), a team over
        :data:`MAX_TEAM`,
        an unknown clock, or robot processes that do not start.
    """
    kind = task_kind(scenario.command.kind)
    if kind.decider is None:
        raise InputError(f"command.kind: {kind.name!r} runs its own loop, not a team of deciders")
    if clock not in CLOCKS:
        raise InputError(f"--clock: expected one of {', '.join(CLOCKS)}, got {clock!r}")
    if not timeout_s > 0:
        raise InputError(f"timeout_s must be > 0, got {timeout_s}")
    n = scenario.n_robots
    if n > MAX_TEAM:
        raise InputError(
            f"poses: a team run starts one process per robot, at most {MAX_TEAM}; got {n}"
        )
    decider = kind.decider
    layout = decision_layout(scenario, decider)
    if layout.series_size + layout.width > MAX_SERIES:
        raise InputError(
            f"command.kind: {kind.name!r} records and broadcasts "
            f"{layout.series_size + layout.width} values per robot a tick; a command "
            f"carries at most {MAX_SERIES}"
        )
    run = TeamRun(
        run_id=secrets.randbits(64) if run_id is None else run_id,
        clock=clock,
        n_robots=n,
        misses=[0] * n,
    )
    keys = Keys(run.run_id)
    ex = _Exchange(run)
    ex.dt_s = scenario.dt_s
    endpoint = listen if listen is not None else f"tcp/127.0.0.1:{free_port()}"
    session = open_session(listen=[endpoint], connect=[])
    procs: list[subprocess.Popen[bytes]] = []
    with tempfile.TemporaryFile() as log:
        try:
            subs = [
                *(
                    session.declare_subscriber(key, ex.on_sample)
                    for key in (keys.hello, keys.command("*"), keys.state("*"), keys.bye("*"))
                ),
                session.liveliness().declare_subscriber(
                    keys.alive_robots, ex.on_token, history=True
                ),
            ]
            token = session.liveliness().declare_token(keys.alive_plant)
            t_start = time.monotonic()
            if not external:
                procs = [_spawn(scenario, i, run.run_id, endpoint, log) for i in range(n)]
            with ex.cond:
                while len(ex.hello) < n or len(ex.alive) < n:
                    if external and time.monotonic() - t_start > wait_s:
                        missing = sorted(set(range(n)) - (ex.hello & ex.alive))
                        raise InputError(
                            f"--wait: {wait_s:g} s passed and robots "
                            f"{[i + 1 for i in missing]} of {n} did not join at {endpoint} "
                            f"(run id {run.run_id:016x}); start each with `firefleet robot "
                            f"CONFIG --sim {endpoint}`, its config's link.run_id the same"
                            + (
                                f"; {run.counters.dropped['mismatch']} hellos refused (team "
                                f"size or tick not the scenario's: {n} robots, {ex.dt_s} s)"
                                if run.counters.dropped["mismatch"]
                                else ""
                            )
                        )
                    gone = [i for i, p in enumerate(procs) if p.poll() is not None]
                    if gone or time.monotonic() - t_start > wait_s:
                        log.seek(0)
                        tail = log.read().decode(errors="replace").strip().splitlines()[-3:]
                        raise InputError(
                            f"robot processes {[i + 1 for i in gone]} did not start: "
                            + " | ".join(tail)
                        )
                    ex.cond.wait(0.1)
            run.start_s = time.monotonic() - t_start
            if started is not None:
                started(
                    {"run_id": run.run_id, "endpoint": endpoint, "pids": [p.pid for p in procs]}
                )
            result = _plant(
                scenario,
                decider,
                layout,
                rec_steps,
                run,
                ex,
                session,
                keys,
                clock,
                timeout_s,
                progress,
            )
            with ex.cond:
                ex.stopping = True
                run.late = ex.late
            session.put(
                keys.clock,
                run.counters.send(
                    Tick(
                        run.run_id,
                        PLANT,
                        run.ticks,
                        t_s=scenario.duration_s,
                        last_tick=scenario.n_steps,
                        stop=True,
                    )
                ),
            )
            deadline = time.monotonic() + _EXIT_TIMEOUT_S
            if external:  # stay until the robots have heard the stop and left (their
                # tokens gone), else one may see the plant vanish first: "plant lost"
                with ex.cond:
                    while ex.alive and time.monotonic() < deadline:
                        ex.cond.wait(0.05)
            for i, proc in enumerate(procs):
                if i in ex.dead:  # failed: nothing to wait for (a hung one is killed below)
                    continue
                try:
                    out, _ = proc.communicate(timeout=max(deadline - time.monotonic(), 0.1))
                except subprocess.TimeoutExpired:
                    continue
                lines = out.decode(errors="replace").strip().splitlines()
                if lines:
                    with contextlib.suppress(json.JSONDecodeError):
                        run.robots.append(json.loads(lines[-1]))
            for sub in subs:
                sub.undeclare()
            token.undeclare()
        finally:
            for proc in procs:
                if proc.poll() is None:
                    proc.kill()
                proc.wait()
                if proc.stdout is not None:
                    proc.stdout.close()
            session.close()
    return result, run


def _plant(
    scenario: Scenario,
    decider: Decider,
    layout: DecisionLayout,
    rec_steps: Any,
    run: TeamRun,
    ex: _Exchange,
    session: Any,
    keys: Keys,
    clock: str,
    timeout_s: float,
    progress: ProgressCallback | None,
) -> SimResult:
    """The staged world loop with the network as its decision."""
    import zenoh

    n = scenario.n_robots
    rng = np.random.default_rng(scenario.seed)
    phase = encoder_phase(scenario.encoder, n, rng)
    stack = discretise_drive(
        scenario.robot, scenario.motor, scenario.speed_pid, scenario.encoder, scenario.dt_s
    )
    drive = drive_init(scenario.initial_poses, phase, stack)
    last_ref = np.zeros((n, 2))
    size = layout.series_size
    last_values = np.full((n, size + layout.width), np.nan)  # series, then broadcast
    heard_tick = np.full(n, -1)  # the tick of each robot's last command (-1: never)
    pubs = [
        session.declare_publisher(keys.sensors(i), congestion_control=zenoh.CongestionControl.BLOCK)
        for i in range(n)
    ]
    pub_progress = session.declare_publisher(
        keys.progress, congestion_control=zenoh.CongestionControl.BLOCK
    )
    dt = scenario.dt_s
    t0 = time.monotonic()

    def decide(
        state: None, inputs: DecideInputs, params: None, dt_s: float
    ) -> tuple[None, WheelCommand]:
        k = inputs.step
        counts, measured = inputs.readings["counts"], inputs.readings["measured_rad_s"]
        if clock == "realtime":
            wait = t0 + k * dt - time.monotonic()
            if wait > 0:
                time.sleep(wait)
        with ex.cond:
            ex.tick = k
            ex.commands = {}
            live = [i for i in range(n) if i not in ex.dead]
            data = [
                run.counters.send(
                    Sensors(
                        run.run_id,
                        i,
                        k,
                        t_s=inputs.t_s,
                        counts=(float(counts[i, 0]), float(counts[i, 1])),
                        measured_rad_s=(float(measured[i, 0]), float(measured[i, 1])),
                    )
                )
                for i in live
            ]
        for i, payload in zip(live, data, strict=True):
            pubs[i].put(payload)
        deadline = t0 + (k + 1) * dt if clock == "realtime" else time.monotonic() + timeout_s
        with ex.cond:
            while True:
                waiting = [i for i in range(n) if i not in ex.dead and i not in ex.commands]
                left = deadline - time.monotonic()
                if not waiting or left <= 0:
                    break
                ex.cond.wait(left)
            for i in waiting:
                run.misses[i] += 1
            for i, cmd in ex.commands.items():
                last_ref[i] = cmd.reference_rad_s
                if len(cmd.series) == last_values.shape[1]:
                    last_values[i] = cmd.series
                    heard_tick[i] = k
            for i in ex.dead:
                last_ref[i] = 0.0
            # the broadcast as the robots will hold it at the next tick (one tick old
            # when fresh), relayed before that tick's sensors
            age = np.where(heard_tick >= 0, (k + 1 - heard_tick) * dt, np.inf)
            team = TeamProgress(
                run.run_id,
                PLANT,
                k,
                width=layout.width,
                values=tuple(float(v) for v in last_values[:, size:].ravel()),
                age_s=tuple(float(a) for a in age),
                alive=tuple(i not in ex.dead for i in range(n)),
            )
            payload = run.counters.send(team)
        pub_progress.put(payload)
        series = layout.split(last_values[:, :size], "series")
        run.ticks = k + 1
        return None, WheelCommand(reference_rad_s=last_ref.copy(), series=series)

    stages = Stages(
        world=StaticWorld(  # the world of the in-process loop, its motor faults included
            torque_n_m=scenario.load.torque_n_m,
            start_s=scenario.load.start_s,
            faults=scenario.faults,
        ),
        sensors=_NetSensors(),
        estimation=NoEstimation(),
    )
    rec = run_staged(
        drive,
        stack,
        stages,
        decide,
        None,
        None,
        np.asarray(rec_steps),
        scenario.n_steps,
        progress=progress,
    )
    run.wall_s = time.monotonic() - t0
    return SimResult(
        scenario=scenario,
        t=rec.t_s,
        pose=rec.pose,
        wheel_speed_rad_s=rec.wheel_speed_rad_s,
        wheel_speed_measured_rad_s=rec.wheel_speed_measured_rad_s,
        wheel_speed_ref_rad_s=rec.wheel_speed_ref_rad_s,
        current_a=rec.current_a,
        voltage_v=rec.voltage_v,
        load_torque_n_m=rec.load_torque_n_m,
        extra={name: rec.series[name] for name in decider.series},
    )
