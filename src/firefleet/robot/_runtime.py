"""The on-board loop: the robot's controllers on its hardware, at their rates.

Each control period (the scenario's, 10 ms) on a monotonic clock:

1. the motor board's newest encoder counts (:class:`~firefleet.robot.ArduinoLink`);
2. the robot's controller stack, the same object a team run's robot process holds
   (:class:`firefleet.net.robot.RobotController`: odometry from the counts, then the
   task kind's decision, e.g. the deliverable's fuzzy path follower) -> wheel-speed
   references;
3. the references, limited to what the motors can do at the supply voltage (the Table 2
   motor's no-load speed), sent as a SETPOINT (the PID runs on the Arduino);
4. every ``1 / rate_hz``: a thermal frame through :func:`firefleet.perception.thermal.detect`
   (fires, people) and a PT100 reading.

With ``--sim`` (:mod:`firefleet.robot._sim`) the motor board is the simulator's plant
over zenoh: the counts of step 1 are the plant's ``Sensors`` of the tick, whose
arrival starts the period, and the references of step 3 go to it as a ``Command``.
With a ``link`` in the configuration, every period also publishes the robot's progress
to its teammates and hears theirs (:mod:`firefleet.robot._teamlink`), the
coordination's inbox; a teammate silent for ``link.timeout_s`` trips the lost-link
e-stop (zero references, latched until the link is back for ``link.rearm_s``).

A period that ends after its deadline is an *overrun*: the loop does not try to catch
up (the next period starts now), counts it, and after ``overrun_streak`` overruns in a
row e-stops the motors and ends (exit 1): a controller that cannot keep its period
does not drive. The loop also ends on the scenario's duration, when the robot arrives,
or on SIGINT/SIGTERM (the CLI sets the stop event); in every case the motors are
commanded to zero and e-stopped, and the ports closed.
"""

from __future__ import annotations

import contextlib
import math
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from firefleet.errors import InputError
from firefleet.net.messages import Sensors, TeamProgress
from firefleet.net.robot import RobotController
from firefleet.net.transport import open_session
from firefleet.perception.stereo import load_calibration, process_pair
from firefleet.perception.thermal import KELVIN, detect
from firefleet.robot._arduino import ArduinoLink
from firefleet.robot._config import LinkConfig, RobotConfig, WebcamsConfig
from firefleet.robot._fake_board import FakeBoard
from firefleet.robot._lepton import FakeLepton, Lepton
from firefleet.robot._messages import EStop, Setpoint
from firefleet.robot._pt100 import FakeMax31865, Pt100
from firefleet.robot._sim import SimMotors
from firefleet.robot._teamlink import TeamLink
from firefleet.robot._ultrasonic import FakeHcSr04, HcSr04, speed_of_sound_m_s
from firefleet.robot._webcam import WebcamFrame, Webcams
from firefleet.scenarios.registry import load_scenario
from firefleet.scenarios.schema import Scenario

__all__ = ["Adapters", "OnboardResult", "load_role", "open_adapters", "run_onboard"]


@dataclass
class Adapters:
    """The devices the loop drives (None: not fitted).

    ``motors`` is the Arduino link (real or the fake board's), ``sim`` the plant over
    zenoh instead (``--sim``: then ``motors`` is None); ``session`` is the zenoh
    session of the team link (None: no team link)."""

    motors: ArduinoLink | None
    thermal: Lepton | None = None
    pt100: Pt100 | None = None
    board: FakeBoard | None = None
    sim: SimMotors | None = None
    session: Any = None
    ultrasonic: HcSr04 | None = None
    webcams: Webcams | None = None

    @property
    def link_errors(self) -> dict[str, int]:
        """The motor link's error counters (the plant link's drops with ``--sim``)."""
        if self.sim is not None:
            return {"dropped": self.sim.crc_errors}
        assert self.motors is not None
        return {"crc_errors": self.motors.crc_errors, "framing_errors": self.motors.framing_errors}


def _fake_scene(frames: int = 9) -> np.ndarray:
    """Lepton frames (centikelvin) of a 21 deg C room with a person walking across."""
    out = np.full((frames, 60, 80), round((21.0 + KELVIN) * 100), dtype=np.uint16)
    for k in range(frames):
        c = 10 + 6 * k
        out[k, 22:50, c : c + 8] = round((34.0 + KELVIN) * 100)
    return out


@contextlib.contextmanager
def open_adapters(
    config: RobotConfig, *, fake: bool, sim: str | None = None, n_robots: int = 1,
    dt_s: float = 0.01,
) -> Iterator[Adapters]:  # fmt: skip
    """Open the configured devices (``fake``: every device replaced by its fake; ``sim``:
    the plant's endpoint, the motors and encoders are the plant's, over zenoh, and the
    other devices are not fitted, the plant simulating none yet), and the team link's
    session when the configuration has a link; close them at the end, motors stopped
    first. ``n_robots`` and ``dt_s`` (the scenario's) are what ``sim`` says hello with."""
    hw = config.hardware
    link = config.link
    with contextlib.ExitStack() as stack:
        if sim is not None:
            listen = link.listen if link is not None else "tcp/127.0.0.1:0"
            run_id = int((link or LinkConfig()).run_id, 16)
            session = open_session(listen=[listen], connect=[sim])
            stack.callback(session.close)
            plant = SimMotors(session, run_id, config.robot, n_robots, dt_s)
            stack.callback(plant.close)
            team = session if link is not None and link.team else None
            yield Adapters(motors=None, sim=plant, session=team)
            return
        session = None
        if link is not None and link.team:
            session = open_session(listen=[link.listen], connect=list(link.connect))
            stack.callback(session.close)
        board = None
        if fake or hw.motors.adapter == "fake":
            board = stack.enter_context(FakeBoard())
            port = board.port
        else:
            port = hw.motors.port
        motors = stack.enter_context(ArduinoLink(port, baud=hw.motors.baud))
        thermal = None
        if hw.thermal.adapter == "fake" or (fake and hw.thermal.adapter != "none"):
            camera = FakeLepton(_fake_scene(), lepton=2)
            thermal = Lepton(camera, cci=camera, lepton=2)
        elif hw.thermal.adapter == "lepton":
            thermal = _real_lepton(config, stack)
        pt100 = None
        if hw.pt100.adapter == "fake" or (fake and hw.pt100.adapter != "none"):
            pt100 = Pt100(FakeMax31865(temperature_c=_FAKE_AIR_C), wires=hw.pt100.wires)
        elif hw.pt100.adapter == "max31865":
            pt100 = Pt100(
                _spi(hw.pt100.spi_bus, hw.pt100.spi_device, 1, 1_000_000, stack),
                wires=hw.pt100.wires,
                mains_hz=hw.pt100.mains_hz,
            )
        adapters = Adapters(
            motors=motors, thermal=thermal, pt100=pt100, board=board, session=session
        )
        _open_range_and_cameras(adapters, config, fake=fake, stack=stack)
        yield adapters


_FAKE_AIR_C = 23.5
"""The fake PT100's air temperature [deg C], also the fake HC-SR04's air."""


def _open_range_and_cameras(
    adapters: Adapters, config: RobotConfig, *, fake: bool, stack: contextlib.ExitStack
) -> None:
    """Open the HC-SR04 and the webcams into ``adapters`` (their fakes with ``fake``)."""
    u = config.hardware.ultrasonic
    pin_factory = None
    if u.adapter == "fake" or (fake and u.adapter != "none"):
        echo_s = 2.0 * u.fake_distance_m / speed_of_sound_m_s(_FAKE_AIR_C)
        pin_factory = FakeHcSr04(u.trigger_gpio, u.echo_gpio, echo_s=lambda _: echo_s).factory
    if u.adapter != "none":
        adapters.ultrasonic = stack.enter_context(
            HcSr04(
                u.trigger_gpio,
                u.echo_gpio,
                max_distance_m=u.max_distance_m,
                shots=u.shots,
                air_temperature_c=u.air_temperature_c,
                pin_factory=pin_factory,
            )
        )
    w = config.hardware.webcams
    if w.adapter == "none":
        return
    sources = [w.fake_left, w.fake_right] if fake else [w.left, w.right]
    if sources[0] is None:
        return  # --fake without video files: no webcams
    opened = [s for s in sources if s is not None]
    cams = Webcams(opened, width=w.width, height=w.height, rate_hz=w.rate_hz,
                   process=_stereo_scan(w, len(opened)))  # fmt: skip
    stack.callback(cams.close)
    cams.start()
    adapters.webcams = cams


def _stereo_scan(
    w: WebcamsConfig, n_cameras: int
) -> Callable[[WebcamFrame], dict[str, Any]] | None:
    """The stereo pipeline on a pair (in the webcams' thread), if calibrated."""
    if w.calibration is None:
        return None
    if n_cameras != 2:
        raise InputError("hardware.webcams.calibration: a stereo scan needs a right camera")
    calib = load_calibration(w.calibration)
    if calib.image_size != (w.width, w.height):
        raise InputError(
            f"hardware.webcams.calibration: {w.calibration} is for "
            f"{calib.image_size[0]}x{calib.image_size[1]} px, the webcams give "
            f"{w.width}x{w.height} (hardware.webcams.width/height)"
        )

    def scan(frame: WebcamFrame) -> dict[str, Any]:
        summary = process_pair(*frame.images, calib=calib).summary
        keys = ("nearest_obstacle_m", "depth_median_m", "measured_pct")
        return {k: summary.get(k) for k in keys}

    return scan


def _sample_range_and_cameras(
    adapters: Adapters, result: OnboardResult, tick: int, dt_s: float, range_every: int
) -> None:
    """This period's HC-SR04 reading (at the PT100's air temperature) and newest webcam
    capture, into the log."""
    t_s = tick * dt_s
    sonar = adapters.ultrasonic
    if sonar is not None and tick % range_every == 0:
        if result.pt100_c:
            sonar.set_air_temperature(result.pt100_c[-1][1])
        result.range_m.append((t_s, sonar.read().distance_m))
        result.ultrasonic_no_echoes = sonar.no_echoes
    cams = adapters.webcams
    if cams is not None:
        frame = cams.poll()
        if frame is not None:
            nearest = (frame.scan or {}).get("nearest_obstacle_m")
            result.webcam.append({
                "t_s": t_s,
                "index": frame.index,
                "skew_s": frame.t_s[-1] - frame.t_s[0],
                "nearest_obstacle_m": math.nan if nearest is None else float(nearest),
            })  # fmt: skip
        result.webcam_dropped, result.webcam_failed = cams.dropped, cams.failed


def _spi(bus: int, device: int, mode: int, hz: int, stack: contextlib.ExitStack) -> Any:
    try:
        import spidev
    except ImportError as error:
        raise InputError("SPI devices need spidev: pip install spidev==3.8") from error
    spi = spidev.SpiDev()
    try:
        spi.open(bus, device)
    except OSError as error:
        raise InputError(f"cannot open SPI bus {bus} device {device}: {error}") from error
    spi.mode = mode
    spi.max_speed_hz = hz
    stack.callback(spi.close)
    return spi


def _real_lepton(config: RobotConfig, stack: contextlib.ExitStack) -> Lepton:
    from firefleet.robot._lepton import LinuxI2c

    t = config.hardware.thermal
    spi = _spi(t.spi_bus, t.spi_device, 3, 18_000_000, stack)
    try:
        cci = LinuxI2c(t.i2c_bus)
    except OSError as error:
        raise InputError(f"cannot open I2C bus {t.i2c_bus}: {error}") from error
    stack.callback(cci.close)
    return Lepton(spi, cci=cci, lepton=t.lepton)


@dataclass
class OnboardResult:
    """What the loop did.

    Attributes
    ----------
    stop_reason : str
        ``duration``, ``arrived``, ``signal``, ``overruns``; with ``--sim`` also
        ``plant stopped`` (the run's end) or ``plant lost`` (its process went).
    ticks, overruns, worst_overrun_streak : int
    period_s : list of float
        The measured period of every tick [s].
    cpu_s, wall_s : float
        Process CPU time and wall time of the loop [s].
    t_s, counts, reference_rad_s, pose : list
        The log: time [s], encoder counts (right, left), references sent [rad/s], the
        pose estimate (x, y, theta).
    thermal : list of dict
        Per thermal frame: time, fires, people, hottest pixel [deg C].
    pt100_c : list of tuple
        (time [s], air temperature [deg C]) per reading.
    range_m : list of tuple
        (time [s], HC-SR04 distance [m]: inf out of range, NaN no echo) per reading.
    webcam : list of dict
        Per webcam capture taken by the loop: time, capture index, stereo skew [s],
        the stereo scan's nearest obstacle [m] (NaN without a calibration or a match).
    ultrasonic_no_echoes, webcam_dropped, webcam_failed : int
        The adapters' counters at the end.
    team_link : dict or None
        The team link's summary (:meth:`~firefleet.robot._teamlink.TeamLink.summary`:
        lost-link e-stops, their times, counters); None without a link.
    """

    stop_reason: str = "duration"
    ticks: int = 0
    overruns: int = 0
    worst_overrun_streak: int = 0
    period_s: list[float] = field(default_factory=list)
    cpu_s: float = 0.0
    wall_s: float = 0.0
    t_s: list[float] = field(default_factory=list)
    counts: list[tuple[int, int]] = field(default_factory=list)
    reference_rad_s: list[tuple[float, float]] = field(default_factory=list)
    pose: list[tuple[float, float, float]] = field(default_factory=list)
    thermal: list[dict[str, float]] = field(default_factory=list)
    pt100_c: list[tuple[float, float]] = field(default_factory=list)
    range_m: list[tuple[float, float]] = field(default_factory=list)
    webcam: list[dict[str, float]] = field(default_factory=list)
    ultrasonic_no_echoes: int = 0
    webcam_dropped: int = 0
    webcam_failed: int = 0
    team_link: dict[str, Any] | None = None

    def summary(self) -> dict[str, Any]:
        """The numbers a person reads: counts, period statistics, CPU share."""
        periods = np.asarray(self.period_s[1:]) if len(self.period_s) > 1 else np.zeros(1)
        return {
            "stop_reason": self.stop_reason,
            "ticks": self.ticks,
            "overruns": self.overruns,
            "worst_overrun_streak": self.worst_overrun_streak,
            "period_p50_s": float(np.percentile(periods, 50)),
            "period_p99_s": float(np.percentile(periods, 99)),
            "cpu_share_of_one_core": self.cpu_s / self.wall_s if self.wall_s else 0.0,
            "thermal_frames": len(self.thermal),
            "people_seen": int(sum(f["people"] for f in self.thermal)),
            "pt100_readings": len(self.pt100_c),
            **self._range_and_camera_summary(),
            "team_link": self.team_link,
        }

    def _range_and_camera_summary(self) -> dict[str, Any]:
        ranges = np.array([d for _, d in self.range_m])
        seen = ranges[np.isfinite(ranges)]
        return {
            "range_readings": len(ranges),
            "range_median_m": float(np.median(seen)) if len(seen) else None,
            "range_out_of_range": int(np.isposinf(ranges).sum()),
            "range_no_echo": int(np.isnan(ranges).sum()),
            "ultrasonic_no_echoes": self.ultrasonic_no_echoes,
            "webcam_captures": len(self.webcam),
            "webcam_dropped": self.webcam_dropped,
            "webcam_failed": self.webcam_failed,
        }


def load_role(config: RobotConfig, folder: Path) -> Scenario:
    """The scenario the configuration names (a path relative to its file, or built-in)."""
    name = config.scenario
    candidate = folder / name
    scenario = load_scenario(candidate if candidate.suffix in (".yaml", ".yml") else name)
    if config.robot >= scenario.n_robots:
        raise InputError(
            f"robot: {config.robot} but scenario {scenario.name!r} has {scenario.n_robots} "
            f"robots (0 to {scenario.n_robots - 1})"
        )
    return scenario


def _team_link(
    config: RobotConfig, scenario: Scenario, adapters: Adapters, controller: RobotController
) -> TeamLink | None:
    link = config.link
    if link is None or adapters.session is None:
        return None
    return TeamLink(
        adapters.session, int(link.run_id, 16), config.robot, scenario.n_robots,
        controller.layout.width, scenario.dt_s, timeout_s=link.timeout_s,
        rearm_s=link.rearm_s, tick_ages=adapters.sim is not None,
    )  # fmt: skip


def run_onboard(
    config: RobotConfig,
    scenario: Scenario,
    adapters: Adapters,
    *,
    stop: threading.Event,
    progress: Callable[[int, int], None] | None = None,
) -> OnboardResult:
    """Run the on-board loop until the duration, arrival, a stop or an overrun streak
    (with ``--sim``: until the plant stops the run; arrival does not end it)."""
    controller = RobotController(scenario, config.robot)
    team = _team_link(config, scenario, adapters, controller)
    try:
        return _loop(config, scenario, adapters, controller, team, stop, progress)
    finally:
        if team is not None:
            team.close()


def _loop(
    config: RobotConfig,
    scenario: Scenario,
    adapters: Adapters,
    controller: RobotController,
    team: TeamLink | None,
    stop: threading.Event,
    progress: Callable[[int, int], None] | None,
) -> OnboardResult:
    dt_s = scenario.dt_s
    duration_s = min(config.duration_s or scenario.duration_s, scenario.duration_s)
    n_steps = round(duration_s / dt_s)
    top_rad_s = scenario.motor.speed_gain_rad_s_per_v * scenario.motor.supply_v
    cpr = scenario.encoder.counts_per_rev or 2048
    rad_per_count = 2.0 * np.pi / cpr
    thermal_every = max(1, round(1.0 / (config.hardware.thermal.rate_hz * dt_s)))
    pt100_every = max(1, round(1.0 / (config.hardware.pt100.rate_hz * dt_s)))
    range_every = max(1, round(1.0 / (config.hardware.ultrasonic.rate_hz * dt_s)))
    width = controller.layout.width
    result = OnboardResult()
    history: list[tuple[int, int]] = []
    streak = 0
    cpu0, wall0 = time.process_time(), time.monotonic()
    deadline = wall0 + dt_s
    last_start = wall0
    motors, plant = adapters.motors, adapters.sim
    row: tuple[float, ...] = ()
    if motors is not None:
        motors.send(Setpoint(0.0, 0.0))
    tick = 0
    try:
        while True:
            if plant is not None:  # the plant's sensors pace the loop
                sensors = plant.next_sensors(stop)
                if sensors is None:
                    result.stop_reason = "signal" if stop.is_set() else plant.end or "signal"
                    break
                tick = sensors.tick
                if config.duration_s is not None and sensors.t_s >= config.duration_s:
                    result.stop_reason = "duration"  # the plant's run ends on its own
                    break
                start = time.monotonic()
                if team is not None and tick > 0:  # the teammates' last broadcast
                    team.wait_for(tick - 1, 0.5 * dt_s)
            else:
                if tick >= n_steps:
                    break
                start = time.monotonic()
                if stop.is_set():
                    result.stop_reason = "signal"
                    break
                assert motors is not None
                motors.poll()
                enc = motors.encoders
                counts = (enc.right_counts, enc.left_counts) if enc is not None else (0, 0)
                history = [*history[-2:], counts] if history else [counts] * 3
                measured = (
                    (np.array(history[-1]) - np.array(history[0])) * rad_per_count / (2 * dt_s)
                )
                sensors = Sensors(
                    0, config.robot, tick, t_s=tick * dt_s,
                    counts=(float(counts[0]), float(counts[1])),
                    measured_rad_s=(float(measured[0]), float(measured[1])),
                )  # fmt: skip
            result.period_s.append(start - last_start)
            last_start = start
            if team is not None and (heard := team.progress(tick)) is not None:
                heard = TeamProgress(
                    heard.run_id, heard.robot, heard.tick, width=width,
                    values=_own_row(heard.values, row, config.robot, width),
                    age_s=heard.age_s, alive=heard.alive,
                )  # fmt: skip
                controller.hear_team(heard)
            command, state = controller.step(sensors)
            ref = np.clip(command.reference_rad_s, -top_rad_s, top_rad_s)
            if team is not None:
                row = tuple(command.series[len(command.series) - width :]) if width else ()
                team.publish(tick, row)
                if team.estopped():
                    ref = np.zeros(2)
            reference = (float(ref[0]), float(ref[1]))
            if plant is not None:
                plant.send(reference, command.series)
            else:
                assert motors is not None
                motors.send(Setpoint(*reference))
            result.t_s.append(sensors.t_s)
            result.counts.append((int(sensors.counts[0]), int(sensors.counts[1])))
            result.reference_rad_s.append(reference)
            result.pose.append(state.pose)
            _sense(adapters, result, tick, dt_s, thermal_every, pt100_every)
            _sample_range_and_cameras(adapters, result, tick, dt_s, range_every)
            result.ticks += 1
            if progress is not None and tick % 100 == 0:
                progress(tick, n_steps)
            if state.arrived and plant is None:
                result.stop_reason = "arrived"
                break
            now = time.monotonic()
            # with the plant: late when the command missed the plant's tick
            late = now > start + dt_s if plant is not None else now > deadline
            if late:
                result.overruns += 1
                streak += 1
                result.worst_overrun_streak = max(result.worst_overrun_streak, streak)
                if streak >= config.safety.overrun_streak:
                    result.stop_reason = "overruns"
                    break
                deadline = now + dt_s  # do not catch up: the next period starts now
            else:
                streak = 0
                if plant is None:
                    time.sleep(deadline - now)
                    deadline += dt_s
            if plant is None:
                tick += 1
    finally:
        if plant is not None:
            plant.send((0.0, 0.0), ())
        if motors is not None:
            motors.send(Setpoint(0.0, 0.0))
            motors.send(EStop())
        if team is not None:
            team.publish(tick, row, alive=False)  # goodbye: not a lost link
            result.team_link = team.summary()
    result.cpu_s = time.process_time() - cpu0
    result.wall_s = time.monotonic() - wall0
    return result


def _own_row(
    values: tuple[float, ...], row: tuple[float, ...], robot: int, width: int
) -> tuple[float, ...]:
    """The team's values with this robot's row its own last broadcast."""
    if not row:
        return values
    out = list(values)
    out[robot * width : (robot + 1) * width] = row
    return tuple(out)


def _sense(
    adapters: Adapters,
    result: OnboardResult,
    tick: int,
    dt_s: float,
    thermal_every: int,
    pt100_every: int,
) -> None:
    """The thermal camera and the PT100, each at its rate."""
    if adapters.thermal is not None and tick % thermal_every == 0:
        frame = adapters.thermal.read_frame(max_windows=1)
        if frame is not None:
            frame_c = frame.astype(float) / 100.0 - KELVIN
            found = detect(frame_c).detections
            result.thermal.append({
                "t_s": tick * dt_s,
                "fires": sum(d.kind == "fire" for d in found),
                "people": sum(d.kind == "person" for d in found),
                "max_c": float(frame_c.max()),
            })  # fmt: skip
    if adapters.pt100 is not None and tick % pt100_every == 0:
        result.pt100_c.append((tick * dt_s, adapters.pt100.read().temperature_c))
