"""Benchmark: the on-board loop on fakes and the motor link (issue 19's measurements).

- **CPU** per second of ``firefleet robot``'s loop at 100 Hz with every device on its
  fake (the simulated Arduino on a pseudo-terminal, the Lepton, the PT100, the HC-SR04
  on gpiozero's MockFactory, a webcam pair from 640 x 480 video files at 2 Hz), as a
  share of one core: the robot's side (every thread but the fake Arduino's, which is
  the Arduino's work, measured apart with its thread's CPU clock) and the loop's own
  thread. Floor: < 10 % (a Pi 4 core is some 5-8x slower). Peer: the loop a user would
  write without the runtime, the same controller stepped at 100 Hz with a bare
  ``time.sleep(0.01)`` and no devices.
- **Jitter** of the period over ``--seconds`` (60 s): ``|period - 10 ms|``, p50 and p99,
  against the same bare ``time.sleep`` loop (it drifts: a sleep of 10 ms plus the
  work is longer than 10 ms; the runtime sleeps to a deadline).
- **Serial round trip** through the fake: ESTOP sent -> the STATUS frame with the e-stop
  flag received (and ESTOP_CLEAR -> flag cleared), p50/p99; the fake Arduino reads its
  port every 10 ms, as the sketch does between PID periods. Peer: a plain pyserial
  write and read of the same 6 bytes through an echo on a pseudo-terminal.
- **Bytes per second** at 100 Hz for 2 wheels, each way, against 115,200 baud 8N1
  (11,520 B/s).

``python bench/robot.py [--seconds 60]`` runs it alone (``bench/run.py --only robot``
runs it with the others, 60 s per loop).
"""

from __future__ import annotations

import argparse
import os
import select
import sys
import tempfile
import threading
import time
import tty
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from rich.console import Console
from rich.table import Table

import _harness as h
from firefleet.net.messages import Sensors
from firefleet.net.robot import RobotController
from firefleet.robot import (
    ArduinoLink,
    EStop,
    EStopClear,
    FakeBoard,
    Message,
    Setpoint,
    Status,
    load_role,
    open_adapters,
    pack,
    parse_robot_config,
    run_onboard,
)
from firefleet.robot._config import RobotConfig

SECONDS = 60.0
CPU_FLOOR_PCT = 10.0
UART_B_S = 115_200 / 10  # 8N1: ten bits a byte
ROUND_TRIPS = 200


def _thread_cpu_s(name: str) -> float:
    """CPU time of the live thread of this name so far [s] (0 if there is none)."""
    for t in threading.enumerate():
        if t.name == name and t.ident is not None:
            return time.clock_gettime(time.pthread_getcpuclockid(t.ident))
    return 0.0


def _videos(folder: Path, frames: int) -> tuple[str, str]:
    """A 640 x 480 MJPG pair, a textured scene shifted 16 px between the cameras.

    The texture is smoothed noise, as a camera's picture of a room is (pure noise would
    make frames of 360 kB, several times a real camera's, and as much slower to decode).
    """
    rng = np.random.default_rng(0)
    noise = rng.uniform(0, 255, (480, 680, 3)).astype(np.float32)
    scene = np.clip(cv2.GaussianBlur(noise, (0, 0), 3.0) * 4 - 384, 0, 255).astype(np.uint8)
    paths = []
    for name, shift in (("left.avi", 16), ("right.avi", 0)):
        path = folder / name
        writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), 2.0, (640, 480))
        for _ in range(frames):
            writer.write(np.ascontiguousarray(scene[:, shift : shift + 640]))
        writer.release()
        paths.append(str(path))
    return paths[0], paths[1]


def _jitter_ms(periods_s: list[float], dt_s: float) -> tuple[float, float]:
    j = np.abs(np.asarray(periods_s[1:]) - dt_s) * 1e3
    return float(np.percentile(j, 50)), float(np.percentile(j, 99))


def onboard(seconds: float) -> dict[str, float]:
    """The runtime on every fake for ``seconds``: CPU shares [%] and jitter [ms]."""
    with tempfile.TemporaryDirectory() as folder:
        left, right = _videos(Path(folder), int(2 * seconds) + 4)
        config = parse_robot_config({
            "scenario": "coop-different-paths", "robot": 0, "duration_s": seconds,
            "hardware": {
                "motors": {"adapter": "fake"}, "thermal": {"adapter": "fake"},
                "pt100": {"adapter": "fake"}, "ultrasonic": {"adapter": "fake"},
                "webcams": {"adapter": "v4l2", "fake_left": left, "fake_right": right},
            },
        })  # fmt: skip
        scenario = load_role(config, Path("."))
        with open_adapters(config, fake=True) as adapters:
            board0 = _thread_cpu_s("fake-arduino")
            cpu0, thread0, wall0 = time.process_time(), time.thread_time(), time.monotonic()
            result = run_onboard(config, scenario, adapters, stop=threading.Event())
            wall = time.monotonic() - wall0
            loop_cpu = time.thread_time() - thread0
            board = _thread_cpu_s("fake-arduino") - board0
            process = time.process_time() - cpu0
            webcam_captures = len(result.webcam)
    p50, p99 = _jitter_ms(result.period_s, scenario.dt_s)
    return {
        "robot_side_pct": 100 * (process - board) / wall,
        "loop_thread_pct": 100 * loop_cpu / wall,
        "fake_arduino_pct": 100 * board / wall,
        "process_pct": 100 * process / wall,
        "jitter_p50_ms": p50,
        "jitter_p99_ms": p99,
        "overruns": result.overruns,
        "ticks": result.ticks,
        "wall_s": wall,
        "webcam_captures": webcam_captures,
        "range_readings": len(result.range_m),
        "thermal_frames": len(result.thermal),
    }


def bare_sleep_loop(config: RobotConfig, seconds: float) -> dict[str, float]:
    """The peer: the same controller at 100 Hz with ``time.sleep(dt)``, no devices."""
    scenario = load_role(config, Path("."))
    controller = RobotController(scenario, 0)
    dt = scenario.dt_s
    periods: list[float] = []
    cpu0, wall0 = time.process_time(), time.monotonic()
    last = wall0
    for tick in range(round(seconds / dt)):
        now = time.monotonic()
        periods.append(now - last)
        last = now
        sensors = Sensors(0, 0, tick, t_s=tick * dt, counts=(0.0, 0.0), measured_rad_s=(0.0, 0.0))
        controller.step(sensors)
        time.sleep(dt)
    wall = time.monotonic() - wall0
    p50, p99 = _jitter_ms(periods, dt)
    return {
        "cpu_pct": 100 * (time.process_time() - cpu0) / wall,
        "jitter_p50_ms": p50,
        "jitter_p99_ms": p99,
    }


def _wait(check: Callable[[], bool], timeout_s: float = 1.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not check():
        if time.monotonic() > deadline:
            raise TimeoutError("no answer from the fake board")
        time.sleep(50e-6)


def round_trips(n: int) -> list[float]:
    """ESTOP -> STATUS(e-stop) and ESTOP_CLEAR -> STATUS(clear) times through the fake [s]."""
    out: list[float] = []
    with FakeBoard() as board, ArduinoLink(board.port) as link:

        def flag(on: bool) -> Callable[[], bool]:
            def seen() -> bool:
                return any(isinstance(m, Status) and bool(m.flags & 2) == on for m in link.poll())

            return seen

        rng = np.random.default_rng(1)
        for k in range(n + 4):
            message: Message = EStop() if k % 2 == 0 else EStopClear()
            time.sleep(rng.uniform(0.0, 0.01))  # a command comes at any phase of the board's
            link.poll()  # drop what is waiting
            t0 = time.perf_counter()
            link.send(message)
            _wait(flag(k % 2 == 0))
            if k >= 4:  # the first few: warm-up
                out.append(time.perf_counter() - t0)
    return out


def echo_round_trips(n: int) -> list[float]:
    """The peer: pyserial writes the ESTOP frame's 6 bytes to an echo on a pty, reads
    them back [s]."""
    import serial  # the robot extra's pyserial, as ArduinoLink uses it

    master, slave = os.openpty()
    tty.setraw(slave)
    stop = threading.Event()

    def echo() -> None:
        while not stop.is_set():
            ready, _, _ = select.select([master], [], [], 0.05)
            if ready:
                os.write(master, os.read(master, 4096))

    thread = threading.Thread(target=echo, name="pty-echo", daemon=True)
    thread.start()
    port: Any = serial.Serial(os.ttyname(slave), 115_200, timeout=0)
    frame = pack(EStop())
    out: list[float] = []
    try:
        for k in range(n + 4):
            t0 = time.perf_counter()
            port.write(frame)
            got = b""
            while len(got) < len(frame):
                got += port.read(len(frame) - len(got))
                if len(got) < len(frame):
                    time.sleep(50e-6)
            if k >= 4:
                out.append(time.perf_counter() - t0)
    finally:
        stop.set()
        thread.join()
        port.close()
        for fd in (master, slave):
            os.close(fd)
    return out


def link_bytes(seconds: float) -> dict[str, float]:
    """Bytes per second each way with setpoints at 100 Hz, counted frame by frame."""
    down = up = 0
    with FakeBoard() as board, ArduinoLink(board.port) as link:
        link.poll()
        start = next_t = time.monotonic()
        while time.monotonic() - start < seconds:
            sent = pack(Setpoint(1.0, -1.0))
            link.send(Setpoint(1.0, -1.0))
            down += len(sent)
            up += sum(len(pack(m)) for m in link.poll())
            next_t += 0.01
            time.sleep(max(0.0, next_t - time.monotonic()))
        wall = time.monotonic() - start
    return {"down_b_s": down / wall, "up_b_s": up / wall}


def run(console: Console, seconds: float = SECONDS) -> h.TopicResult:
    """Measure, print the tables, return the rows and the floor."""
    ours = onboard(seconds)
    config = parse_robot_config({"scenario": "coop-different-paths", "robot": 0})
    peer = bare_sleep_loop(config, seconds)
    rtt = np.asarray(round_trips(ROUND_TRIPS)) * 1e3
    echo = np.asarray(echo_round_trips(ROUND_TRIPS)) * 1e3
    rate = link_bytes(min(5.0, seconds))
    rtt50, rtt99 = (float(np.percentile(rtt, q)) for q in (50, 99))
    echo50, echo99 = (float(np.percentile(echo, q)) for q in (50, 99))

    table = Table(title=f"on-board loop at 100 Hz on fakes, {seconds:.0f} s each")
    for col in ("", "firefleet robot", "bare time.sleep loop", "ratio"):
        table.add_column(col, justify="left" if not col else "right")
    table.add_row(
        "CPU, % of one core",
        f"{ours['robot_side_pct']:.1f} (loop thread {ours['loop_thread_pct']:.1f}, "
        f"fake Arduino {ours['fake_arduino_pct']:.1f})",
        f"{peer['cpu_pct']:.1f}",
        f"{ours['robot_side_pct'] / peer['cpu_pct']:.1f}x",
    )
    for q in ("p50", "p99"):
        a, b = ours[f"jitter_{q}_ms"], peer[f"jitter_{q}_ms"]
        table.add_row(f"|period - 10 ms| {q}, ms", f"{a:.3f}", f"{b:.3f}", f"{a / b:.2f}x")
    console.print(table)
    serial_table = Table(title="motor link through the pseudo-terminal fake")
    for col in ("", "firefleet (ESTOP -> STATUS)", "pyserial echo", "ratio"):
        serial_table.add_column(col, justify="left" if not col else "right")
    serial_table.add_row(
        "round trip p50, ms", f"{rtt50:.2f}", f"{echo50:.3f}", f"{rtt50 / echo50:.0f}x"
    )
    serial_table.add_row(
        "round trip p99, ms", f"{rtt99:.2f}", f"{echo99:.3f}", f"{rtt99 / echo99:.0f}x"
    )
    for way in ("down", "up"):
        b_s = rate[f"{way}_b_s"]
        serial_table.add_row(f"{way}, B/s at 100 Hz", f"{b_s:,.0f}", f"UART {UART_B_S:,.0f}",
                             f"{b_s / UART_B_S:.1%}")  # fmt: skip
    console.print(serial_table)

    def row(key: str, value: float, unit: str, label: str, better_high: bool = False) -> h.Row:
        return h.Row(f"robot.{key}", value, unit, better_high, label=label)

    rows = (
        row("loop.cpu_pct", ours["robot_side_pct"], "% of a core", "on-board loop CPU on fakes"),
        row("loop.thread_cpu_pct", ours["loop_thread_pct"], "% of a core", "loop thread CPU"),
        row("bare_loop.cpu_pct", peer["cpu_pct"], "% of a core", "bare time.sleep loop CPU"),
        row("loop.jitter_p50_ms", ours["jitter_p50_ms"], "ms", "loop period jitter p50"),
        row("loop.jitter_p99_ms", ours["jitter_p99_ms"], "ms", "loop period jitter p99"),
        row("bare_loop.jitter_p50_ms", peer["jitter_p50_ms"], "ms", "bare loop jitter p50"),
        row("bare_loop.jitter_p99_ms", peer["jitter_p99_ms"], "ms", "bare loop jitter p99"),
        row("serial.round_trip_p50_ms", rtt50, "ms", "ESTOP -> STATUS p50 (fake board)"),
        row("serial.round_trip_p99_ms", rtt99, "ms", "ESTOP -> STATUS p99 (fake board)"),
        row("serial.echo_round_trip_p50_ms", echo50, "ms", "pyserial pty echo p50"),
        row("serial.echo_round_trip_p99_ms", echo99, "ms", "pyserial pty echo p99"),
        row("serial.down_uart_pct", 100 * rate["down_b_s"] / UART_B_S, "% of UART", "down"),
        row("serial.up_uart_pct", 100 * rate["up_b_s"] / UART_B_S, "% of UART", "up"),
    )
    floor = h.Floor.on(rows[0], "<", CPU_FLOOR_PCT, "on-board loop at 100 Hz on fakes, CPU")
    uart = h.Floor.on(
        rows[-1], "<", 50.0, "motor link at 100 Hz, busier direction, of 115,200 baud"
    )
    return h.TopicResult(
        rows=rows,
        floors=(floor, uart),
        details={
            "seconds": seconds,
            "onboard": ours,
            "bare_sleep_loop": peer,
            "round_trip_ms": {"p50": rtt50, "p99": rtt99, "n": len(rtt)},
            "echo_round_trip_ms": {"p50": echo50, "p99": echo99, "n": len(echo)},
            "bytes_per_s": rate,
            "ratios": {
                "cpu": ours["robot_side_pct"] / peer["cpu_pct"],
                "jitter_p50": ours["jitter_p50_ms"] / peer["jitter_p50_ms"],
                "jitter_p99": ours["jitter_p99_ms"] / peer["jitter_p99_ms"],
                "round_trip_p50": rtt50 / echo50,
                "round_trip_p99": rtt99 / echo99,
            },
        },
    )


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=SECONDS, help="each loop's duration [s]")
    args = ap.parse_args()
    result = run(Console(), args.seconds)
    sys.exit(0 if all(f.passed for f in result.floors) else 1)
