"""The world loop: one fixed-step loop over the whole team, for every task kind.

Each tick ``k`` (time ``t = k dt``), for N robots at once (batch-first arrays, no
per-robot Python objects), in this order::

    world.step          the world at t: static now; the motors' load torque   (N, 2)
    sensors.read        readings from the world and the team's true state    by name
    link.exchange       the messages the team sent last tick, as delivered   by name
    estimation.step     each robot's pose estimate: odometry (dead reckoning
                        of the encoder counts) by default                    (N, 3)
    kind.decide         the task kind's decision for the whole team: wheel
                        speed references (or voltages) and what to record    (N, 2)
    drive               the wheel stack (:mod:`firefleet.sim.drive`): the PIDs'
                        voltages (:func:`speed_control`), then motors,
                        kinematics, encoders (:func:`drive_step`)            (N, 2), (N, 3)
    recorder            every k-th tick and the last

The samples a tick records are the state at ``t`` (before the drive step) with what was
decided at ``t``; the last tick records and stops. Randomness (each wheel's encoder
phase) comes from one ``numpy.random.Generator`` seeded with the scenario's ``seed``.

A Python loop per tick costs some 100 us of NumPy overhead, far too slow for the long
runs of small teams. So a kind may bring a *fused* run (:data:`FusedRun`): one compiled
loop, run in chunks of ticks, that performs the same stage sequence for the default
stages (static world, no sensors, ideal link, odometry). :func:`run_loop` takes it
whenever the stages are the defaults; the staged path, each stage a function on arrays
and the ticks in chunks of Python, is the reference (tests/sim/test_loop.py shows the
two agree).

A kind with stages of its own runs the staged path, where most ticks between its events
(a world step, a scan, a frame, a decision that changes) only turn the wheels. If its
decider and stages say which (:data:`QuietTicks`, :mod:`firefleet.sim._quiet_stretch`),
each such *quiet stretch* runs in one compiled call, and every tick's wheel step in
another: the same numbers bit for bit (tests/sim/test_loop_stretch.py).
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.scenarios.schema import Scenario
from firefleet.sim._link_stage import IdealLink, Link, link_impaired
from firefleet.sim._recorder import Recorder, Recording
from firefleet.sim._stages import (
    Estimation,
    Messages,
    NoEstimation,
    NoSensors,
    Odometry,
    OdometryState,
    Sensors,
    StaticWorld,
    TruePose,
    WorldState,
)
from firefleet.sim.drive import (
    DriveStack,
    DriveState,
    discretise_drive,
    drive_init,
    drive_step,
    encoder_phase,
    speed_control,
)
from firefleet.sim.result import SimResult

__all__ = [
    "CHUNKS",
    "DecideInputs",
    "Decider",
    "Estimation",
    "FusedRun",
    "HeldCommand",
    "IdealLink",
    "Link",
    "Messages",
    "NoEstimation",
    "NoSensors",
    "Odometry",
    "OdometryState",
    "ProgressCallback",
    "Recording",
    "Sensors",
    "Stages",
    "StagesFactory",
    "StaticWorld",
    "TruePose",
    "WheelCommand",
    "WorldState",
    "chunk_bounds",
    "default_stages",
    "run_loop",
    "run_staged",
]

ProgressCallback = Callable[[int, int], None]
"""Called as ``progress(steps_done, steps_total)`` about a hundred times a run."""

CHUNKS = 100
"""The loop runs in this many chunks of ticks (so that a progress bar can move)."""


# --- stages ------------------------------------------------------------------------------


@dataclass(frozen=True)
class Stages:
    """The loop's stages before the decision, by name (see the module notes)."""

    world: StaticWorld
    sensors: Sensors = field(default_factory=NoSensors)
    link: Link = field(default_factory=IdealLink)
    estimation: Estimation = field(default_factory=Odometry)

    def names(self) -> dict[str, str]:
        """Each stage's class name, as a run records them."""
        return {
            "world": type(self.world).__name__,
            "sensors": type(self.sensors).__name__,
            "link": type(self.link).__name__,
            "estimation": type(self.estimation).__name__,
        }


# --- what a task kind brings -------------------------------------------------------------


@dataclass(frozen=True)
class DecideInputs:
    """What a kind's decision sees at a tick.

    Attributes
    ----------
    t_s : float
        Time [s].
    step : int
        Tick index k.
    pose_estimate : ndarray, shape (N, 3), or None
        The estimation stage's poses (None without an estimator).
    readings : mapping
        The sensors' readings by name.
    inbox : mapping
        The messages the link delivered, by name.
    """

    t_s: float
    step: int
    pose_estimate: FloatArray | None
    readings: Messages
    inbox: Messages


@dataclass(frozen=True)
class WheelCommand:
    """A decision for the whole team.

    Attributes
    ----------
    reference_rad_s : ndarray, shape (N, 2)
        Wheel speed references [rad/s] for the PIDs (NaN where ``voltage_v`` is given).
    voltage_v : ndarray, shape (N, 2), or None
        Motor voltages held over the tick [V], the PIDs skipped (open loop); None: the
        PIDs give them.
    series : mapping of str to ndarray
        The decision's quantities at this tick, by the name the result records them
        under (``result.extra``), robot axis first.
    outbox : mapping of str to ndarray
        Messages to the team, delivered by the link at the next tick.
    done : bool
        The task is over (every robot arrived): the loop records this tick and stops
        before ``n_steps``.
    actions : mapping of str to ndarray
        What the team does to the world besides driving (a mission's spray), handed to
        the world stage's ``act(world, actions, true_poses)`` at once, for its next step.
    """

    reference_rad_s: FloatArray
    voltage_v: FloatArray | None = None
    series: Messages = field(default_factory=dict)
    outbox: Messages = field(default_factory=dict)
    done: bool = False
    actions: Messages = field(default_factory=dict)


DecideStep = Callable[[Any, DecideInputs, Any, float], tuple[Any, WheelCommand]]
"""``new_state, command = decide(state, inputs, params, dt_s)``."""

QuietTicks = Callable[[Any, DecideInputs, Any, int, float, int], int]
"""``m = quiet_ticks(state, inputs, params, k, dt_s, limit)``: after a tick (its
``inputs``) whose decision returned its state object unchanged (nothing new), how many
of the ticks ``k, k + 1, ...`` (at most ``limit``) it would answer the same way, the same
state and the same command, with the same readings, inbox and no new pose but the time
(the stages see to that: `sim._quiet_stretch.stretch_ok`)."""

HeldCommand = Callable[[Any, DecideInputs], "WheelCommand | None"]
"""``command = held(state, inputs)``: after a tick whose decision returned a new
``state``, the command the decision gives at a quiet tick that follows it with the
readings ``inputs`` (:data:`QuietTicks` on that state then says how many); None: it
does not know (the next tick runs in full)."""


@dataclass(frozen=True)
class Decider:
    """A task kind's decision step on the loop.

    Attributes
    ----------
    init : callable
        ``state, params = init(scenario)``: the decision's memory and its constants.
    decide : callable
        ``new_state, command = decide(state, inputs, params, dt_s)``
        (:class:`DecideInputs`, :class:`WheelCommand`).
    series : tuple of str
        Names of the quantities ``decide`` reports each tick, in the order the result
        lists them.
    uses_estimate : bool
        Whether ``decide`` reads ``pose_estimate`` (the default stages then include
        odometry).
    quiet_ticks : callable, optional
        The decision's quiet ticks (:data:`QuietTicks`) for the staged loop's quiet
        stretches; None: none.
    held : callable, optional
        The command of the quiet ticks after a tick that changed the state
        (:data:`HeldCommand`): with it (and sensors that tell their quiet readings) a
        stretch may start right after such a tick; None: a stretch starts only after a
        tick that left the state as it was.
    """

    init: Callable[[Scenario], tuple[Any, Any]]
    decide: DecideStep
    series: tuple[str, ...] = ()
    uses_estimate: bool = False
    quiet_ticks: QuietTicks | None = None
    held: HeldCommand | None = None


FusedRun = Callable[[Scenario, FloatArray, NDArray[np.int64], "ProgressCallback | None"], SimResult]
"""``result = fused(scenario, encoder_phase_rad, rec_steps, progress)``: a kind's compiled
loop for the default stages, from the encoders' phases (N, 2) [rad] the loop drew, the
ticks to record, and a progress callback to call between its chunks of ticks."""


StagesFactory = Callable[[Scenario, Decider, np.random.Generator], Stages]
"""``stages = make_stages(scenario, decider, rng)``: a kind's own stages (sensors, maps,
filters), drawing their randomness from the run's generator ``rng``."""


def default_stages(scenario: Scenario, decider: Decider) -> Stages:
    """The stages a scenario runs with: static world with its load step, no sensors, an
    ideal link, and odometry if the kind uses a pose estimate.

    Examples
    --------
    >>> from firefleet import load_scenario
    >>> from firefleet.sim.loop import default_stages
    >>> from firefleet.sim.registry import task_kind
    >>> scenario = load_scenario("path-straight")
    >>> decider = task_kind(scenario.command.kind).decider
    >>> default_stages(scenario, decider).names()
    {'world': 'StaticWorld', 'sensors': 'NoSensors', 'link': 'IdealLink', 'estimation': 'Odometry'}
    """
    link: Link = IdealLink()
    if link_impaired(scenario):
        from firefleet.sim.link import LinkModel  # the link imports this module's types

        link = LinkModel.from_spec(scenario.link, seed=scenario.seed)
    return Stages(
        world=StaticWorld(
            torque_n_m=scenario.load.torque_n_m,
            start_s=scenario.load.start_s,
            faults=scenario.faults,
        ),
        link=link,
        estimation=Odometry() if decider.uses_estimate else NoEstimation(),
    )


def chunk_bounds(n_steps: int) -> NDArray[np.int64]:
    """Tick boundaries of the chunks of a run of ``n_steps`` steps (ticks 0 .. n_steps).

    Examples
    --------
    >>> from firefleet.sim.loop import CHUNKS, chunk_bounds
    >>> chunk_bounds(5).tolist()
    [0, 1, 2, 3, 4, 5, 6]
    >>> CHUNKS, len(chunk_bounds(1000)) - 1
    (100, 100)
    """
    return np.unique(np.linspace(0, n_steps + 1, CHUNKS + 1).astype(np.int64))


def run_loop(
    scenario: Scenario,
    decider: Decider,
    rec_steps: NDArray[np.int64],
    *,
    fused: FusedRun | None = None,
    stages: Stages | None = None,
    make_stages: StagesFactory | None = None,
    progress: ProgressCallback | None = None,
) -> SimResult:
    """Run a scenario on the world loop.

    Parameters
    ----------
    scenario : Scenario
    decider : Decider
        The task kind's decision.
    rec_steps : ndarray of int
        Ticks to record (ascending, the last one ``n_steps`` included).
    fused : callable, optional
        The kind's compiled loop (:data:`FusedRun`), taken when ``stages`` is None (the
        defaults).
    stages : Stages, optional
        The stages; None: :func:`default_stages`.
    make_stages : callable, optional
        Builds the stages from the run's generator (:data:`StagesFactory`), after the
        encoders' phases are drawn; instead of ``stages``.
    progress : callable, optional
        ``progress(done, total)`` after each chunk.

    Returns
    -------
    SimResult
        The recorded run; ``extra`` holds the decision's series, time first.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet import load_scenario
    >>> from firefleet.sim.loop import run_loop
    >>> from firefleet.sim.registry import task_kind
    >>> scenario = load_scenario("motor-pid")
    >>> decider = task_kind(scenario.command.kind).decider
    >>> result = run_loop(scenario, decider, np.array([0, 100, scenario.n_steps]))
    >>> result.t.tolist(), result.pose.shape, scenario.n_steps * scenario.dt_s
    ([0.0, 1.0, 10.0], (3, 1, 3), 10.0)
    """
    rng = np.random.default_rng(scenario.seed)
    n = scenario.n_robots
    n_steps = scenario.n_steps
    steps = np.asarray(rec_steps)
    if steps.ndim != 1 or steps.size == 0 or steps[-1] != n_steps or np.any(np.diff(steps) <= 0):
        raise InputError(
            f"rec_steps must rise strictly and end at the last step {n_steps}, "
            f"got {steps.size} steps ending at {steps[-1] if steps.size else None}"
        )
    if steps[0] < 0:
        raise InputError(f"rec_steps must be >= 0, got {steps[0]}")
    phase = encoder_phase(scenario.encoder, n, rng)
    if make_stages is not None:
        stages = make_stages(scenario, decider, rng)
    # the fused loops run the ideal link; of them only path following's knows faults
    fault_free = not scenario.faults or scenario.command.kind == "path-following"
    if fused is not None and stages is None and not link_impaired(scenario) and fault_free:
        return fused(scenario, phase, rec_steps, progress)

    stg = stages if stages is not None else default_stages(scenario, decider)
    stack = discretise_drive(
        scenario.robot, scenario.motor, scenario.speed_pid, scenario.encoder, scenario.dt_s
    )
    drive = drive_init(scenario.initial_poses, phase, stack)
    state, params = decider.init(scenario)
    rec = run_staged(
        drive,
        stack,
        stg,
        decider.decide,
        state,
        params,
        rec_steps,
        n_steps,
        progress=progress,
        quiet=decider.quiet_ticks,
        held=decider.held,
    )
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
        extra={
            **{name: rec.series[name] for name in decider.series if name in rec.series},
            **{name: v for name, v in rec.series.items() if name not in decider.series},
            **rec.final,
        },
    )


def run_staged(
    drive: DriveState,
    stack: DriveStack,
    stages: Stages,
    decide: DecideStep,
    state: Any,
    params: Any,
    rec_steps: NDArray[np.int64],
    n_steps: int,
    *,
    progress: ProgressCallback | None = None,
    rng: np.random.Generator | None = None,
    quiet: QuietTicks | None = None,
    held: HeldCommand | None = None,
) -> Recording:
    """The staged loop: ticks 0 .. ``n_steps``, each stage a function on arrays.

    Parameters
    ----------
    drive : DriveState
        The team's wheel stacks at the start (N robots).
    stack : DriveStack
        Their constants (the control period ``stack.dt_s`` is the tick).
    stages : Stages
    decide : callable
        ``new_state, command = decide(state, inputs, params, dt_s)``.
    state, params
        The decision's memory at the start, and its constants.
    rec_steps : ndarray of int
        Ticks to record, ascending (at most ``n_steps``).
    n_steps : int
        Number of drive steps (the last tick, ``n_steps``, decides and records only).
    progress : callable, optional
        ``progress(done, total)`` after each chunk of ticks.
    rng : numpy.random.Generator, optional
        Draws the wheels' slip in each drive step (:func:`drive_step`); None: no slip.
    quiet : callable, optional
        The decision's quiet ticks (:data:`QuietTicks`): with it, and stages that know
        theirs (:mod:`firefleet.sim._quiet_stretch`), the ticks where only the wheels turn
        run in one compiled call, the same numbers as tick by tick; None: every tick in
        full.
    held : callable, optional
        The decision's command at the quiet ticks after a tick that changed its state
        (:data:`HeldCommand`): a stretch may start there too (with sensors that give
        their ``quiet_readings``); None: only after a tick that left the state alone.

    Returns
    -------
    Recording

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.control.pid import PidParams
    >>> from firefleet.models import EncoderParams, MotorParams, RobotGeometry
    >>> from firefleet.sim.drive import discretise_drive, drive_init
    >>> from firefleet.sim.loop import Stages, StaticWorld, WheelCommand, run_staged
    >>> stack = discretise_drive(RobotGeometry(), MotorParams(), PidParams(), EncoderParams(), 0.01)
    >>> def decide(state, inputs, params, dt_s):  # both wheels at 10 rad/s, always
    ...     return state, WheelCommand(reference_rad_s=np.full((1, 2), 10.0))
    >>> start = drive_init(np.zeros((1, 3)), np.zeros((1, 2)), stack)
    >>> stages = Stages(world=StaticWorld())
    >>> rec = run_staged(start, stack, stages, decide, None, None, np.array([0, 200]), 200)
    >>> rec.t_s.tolist(), rec.pose.shape, round(float(rec.wheel_speed_rad_s[-1, 0, 0]), 1)
    ([0.0, 2.0], (2, 1, 3), 10.0)
    """
    dt = stack.dt_s
    n = drive.pose.shape[0]
    world = stages.world.init(n)
    estimate = stages.estimation.init(drive.pose, drive)
    sent: Messages = {}
    link = stages.link.init(n, dt)
    rec = Recorder(rec_steps, n)
    estimation_series = getattr(stages.estimation, "series", None)
    from firefleet.sim import _quiet_stretch as qs  # it imports this module's types

    fast = quiet is not None and qs.stretch_ok(stages, drive, rng)
    consts = qs.stretch_constants(stack, n) if fast else None
    quiet_readings = getattr(stages.sensors, "quiet_readings", None) if fast else None
    after = held if callable(quiet_readings) else None  # a stretch after a new state
    rec_next = 0  # index of the next tick to record in rec_steps
    for k0, k1 in itertools.pairwise(chunk_bounds(n_steps)):
        k = int(k0)
        while k < int(k1):
            t = k * dt
            world = stages.world.step(world, t)
            readings = stages.sensors.read(world, drive)
            inbox, link = stages.link.exchange(link, sent, t, drive.pose)
            if k > 0:  # the encoders have counted since the last tick
                estimate = stages.estimation.step(estimate, drive, stack, readings)
            inputs = DecideInputs(t, k, stages.estimation.pose(estimate), readings, inbox)
            before = state
            state, command = decide(state, inputs, params, dt)
            if estimation_series is not None:  # the estimator's own quantities
                command = dataclasses.replace(
                    command, series={**command.series, **estimation_series(estimate)}
                )
            sent = command.outbox
            if command.actions:  # the world takes them at its next step
                world = stages.world.act(world, command.actions, drive.pose)  # type: ignore[attr-defined]
            stepped = None
            if fast and command.voltage_v is None:  # the same tick in one compiled call
                stepped, voltage = qs.drive_tick(
                    drive,
                    stack,
                    command.reference_rad_s,
                    world.voltage_scale,
                    world.load_torque_n_m,
                    consts,
                )
            elif command.voltage_v is None:
                drive, voltage = speed_control(drive, command.reference_rad_s, stack)
            else:
                voltage = command.voltage_v
            if world.voltage_scale is not None and stepped is None:  # a motor fault
                voltage = voltage * world.voltage_scale[:, None]
            rec.record(
                k, drive, command, voltage, world, stages.link.counters(link), force=command.done
            )
            if k == n_steps or command.done:
                break
            if stepped is not None:
                drive = stepped
            else:
                drive = drive_step(
                    drive, voltage, stack, load_torque_n_m=world.load_torque_n_m, rng=rng
                )
            k += 1
            if fast and not sent and command.voltage_v is None:
                # the quiet stretch: ticks where only the wheels turn (module notes)
                hold, inputs = qs.held_command(
                    state, before, command, inputs, readings, k, dt, after, quiet_readings
                )
                if hold is not None:
                    while rec_next < rec_steps.size and rec_steps[rec_next] < k:
                        rec_next += 1
                    limit = min(int(k1), n_steps) - k
                    if rec_next < rec_steps.size:
                        limit = min(limit, int(rec_steps[rec_next]) - k)
                    m = qs.quiet_ticks(stages, world, quiet, state, inputs, params, k, dt, limit)
                    if m > 0:
                        drive, estimate, world = qs.run_stretch(
                            m, k, drive, stack, stages, world, hold, estimate, consts
                        )
                        k += m
        if progress is not None:
            progress(n_steps if command.done else min(int(k1), n_steps), n_steps)
        if command.done:
            break
    final = getattr(stages.estimation, "final", None)
    world_final = getattr(stages.world, "final", None)  # a world that logs what happened
    recording = rec.recording(
        dt,
        {
            **(final(estimate) if final is not None else {}),
            **(world_final(world) if world_final is not None else {}),
        },
    )
    return dataclasses.replace(recording, estimation_state=estimate)
