"""Live mode: a run's poses to the browser while it simulates, never slowing it.

The simulation publishes into a :class:`LiveHub` (from its own thread); the hub keeps
only the latest frame, and each websocket sends the newest frame when it is ready for
one. A browser that draws slowly gets frames dropped; the simulation never waits for
it, and with no browser connected a publish is a lock, a counter and one dict.

The frames come from a tap on the world loop's sensor stage (:class:`LiveTap`), which
sees the team's true state each tick: it hands a frame to the hub at most ``fps`` times
a second of wall time, and, with ``speed`` > 0, holds the run to ``speed`` times real
time (sleeping only when ahead). A kind with its own loop (no stages) sends its
progress only, and its poses when the run ends.

References
----------
The pattern is a "latest value" mailbox (a conflating queue), as in ROS topics with a
queue of depth 1.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import json
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from firefleet.scenarios.schema import Scenario
from firefleet.sim.loop import Messages, Sensors, WorldState, default_stages, run_loop
from firefleet.sim.result import SimResult

__all__ = ["LiveHub", "LiveTap", "simulate_live"]


class LiveHub:
    """The latest frame of a live run, and who waits for it.

    Examples
    --------
    >>> from firefleet.serve.live import LiveHub
    >>> hub = LiveHub()
    >>> hub.publish({"t": 0.5}); hub.publish({"t": 1.0})
    >>> hub.latest()  # only the newest frame is kept
    (2, '{"t":1.0}')
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._seq = 0
        self._frame = ""
        self._hello = "{}"
        self._waiters: list[tuple[asyncio.AbstractEventLoop, asyncio.Event]] = []

    def set_hello(self, message: Mapping[str, Any]) -> None:
        """The first message every websocket gets (the scene, the team's size)."""
        with self._lock:
            self._hello = json.dumps(message, separators=(",", ":"))

    def hello(self) -> str:
        """The first message, as JSON text."""
        with self._lock:
            return self._hello

    def publish(self, frame: Mapping[str, Any]) -> None:
        """Make ``frame`` the latest (from any thread); never blocks on a reader."""
        text = json.dumps(frame, separators=(",", ":"))
        with self._lock:
            self._seq += 1
            self._frame = text
            waiters = list(self._waiters)
        for loop, event in waiters:
            with contextlib.suppress(RuntimeError):  # that reader's loop has closed
                loop.call_soon_threadsafe(event.set)

    def latest(self) -> tuple[int, str]:
        """``(sequence number, frame JSON)``; sequence 0 before the first frame."""
        with self._lock:
            return self._seq, self._frame

    async def frames(self, after: int) -> tuple[int, str]:
        """Wait for a frame newer than sequence ``after``; the newest one."""
        loop = asyncio.get_running_loop()
        event = asyncio.Event()
        entry = (loop, event)
        with self._lock:
            self._waiters.append(entry)
        try:
            while True:
                seq, text = self.latest()
                if seq > after:
                    return seq, text
                await event.wait()
                event.clear()
        finally:
            with self._lock:
                self._waiters.remove(entry)


@dataclass
class _Pace:
    """Wall-clock bookkeeping of a tap: when it last published, when the run began."""

    start: float = field(default_factory=time.perf_counter)
    last: float = -1.0
    ticks: int = 0


@dataclass(frozen=True)
class LiveTap:
    """A sensor stage that also shows the team's true poses to a :class:`LiveHub`.

    Attributes
    ----------
    inner : Sensors
        The stage it wraps: its readings are returned unchanged.
    hub : LiveHub
    dt_s : float
        The tick [s] (to know the simulated time).
    fps : float
        Frames a second of wall time at most.
    speed : float
        Simulated seconds per wall second (0: as fast as it runs).
    n_steps : int
        The run's last tick (for the progress in each frame).
    """

    inner: Sensors
    hub: LiveHub
    dt_s: float
    fps: float = 30.0
    speed: float = 0.0
    n_steps: int = 0
    pace: _Pace = field(default_factory=_Pace)

    def read(self, world: WorldState, drive: Any) -> Messages:
        """The inner stage's readings; a frame to the hub when one is due."""
        pace = self.pace
        k = pace.ticks
        pace.ticks += 1
        if k % 8 == 0 or k == self.n_steps:  # the clock is read every 8th tick
            now = time.perf_counter()
            t_s = k * self.dt_s
            if self.speed > 0:
                ahead = t_s / self.speed - (now - pace.start)
                if ahead > 0:
                    time.sleep(ahead)
                    now = time.perf_counter()
            if now - pace.last >= 1.0 / self.fps and k < self.n_steps:  # the last: at the end
                pace.last = now
                pose = np.round(drive.pose, 4).tolist()
                self.hub.publish(
                    {"type": "frame", "t": t_s, "pose": pose, "done": k, "total": self.n_steps}
                )
        return self.inner.read(world, drive)


def simulate_live(
    scenario: Scenario,
    hub: LiveHub,
    rec_steps: np.ndarray,
    *,
    speed: float = 0.0,
    fps: float = 30.0,
    progress: Callable[[int, int], None] | None = None,
) -> SimResult:
    """Run ``scenario`` (its kind's staged loop), streaming its poses into ``hub``.

    Parameters
    ----------
    scenario : Scenario
    hub : LiveHub
    rec_steps : ndarray of int
        Ticks to record (as :func:`firefleet.sim.loop.run_loop`).
    speed : float
        Simulated seconds per wall second; 0: as fast as it runs.
    fps : float
        Frames a second to the browser at most.
    progress : callable, optional
        ``progress(done, total)``, also sent to the hub.

    Returns
    -------
    SimResult
        The same run as :func:`firefleet.simulate` with ``backend="array"``.
    """
    from firefleet.serve.scene import scene_of
    from firefleet.sim.registry import task_kind

    kind = task_kind(scenario.command.kind)
    hub.set_hello({"type": "hello", "scenario": scenario.name, "scene": scene_of(scenario)})

    def tell(done: int, total: int) -> None:
        if progress is not None:
            progress(done, total)

    if kind.decider is None:  # a kind with its own loop: progress, then the poses
        hub.publish({"type": "progress", "done": 0, "total": scenario.n_steps})

        def relay(done: int, total: int) -> None:
            hub.publish({"type": "progress", "done": done, "total": total})
            tell(done, total)

        result = kind.run(scenario, rec_steps, relay)
    else:
        stages = default_stages(scenario, kind.decider)
        tap = LiveTap(
            inner=stages.sensors,
            hub=hub,
            dt_s=scenario.dt_s,
            fps=fps,
            speed=speed,
            n_steps=scenario.n_steps,
        )
        stages = dataclasses.replace(stages, sensors=tap)
        result = run_loop(scenario, kind.decider, rec_steps, stages=stages, progress=tell)
    hub.publish(
        {
            "type": "frame",
            "t": float(result.t[-1]),
            "pose": np.round(result.pose[-1], 4).tolist(),
            "done": scenario.n_steps,
            "total": scenario.n_steps,
            "finished": True,
        }
    )
    return result
