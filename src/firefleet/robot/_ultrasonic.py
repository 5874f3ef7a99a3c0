"""The HC-SR04 ultrasonic range finder through gpiozero's ``DistanceSensor``.

A 10 us pulse on TRIG makes the HC-SR04 send eight 40 kHz bursts; ECHO then stays high
for the sound's time of flight there and back, so (the datasheet's formula)

    distance = c * t_echo / 2,    c = 331.3 + 0.606 T  m/s  (air at T deg C),

rated from 2 cm to 4 m, one measurement per 60 ms at most. The echo is a 5 V signal:
on a Raspberry Pi it goes through a divider (1 kohm over 2 kohm) to the 3.3 V GPIO.

gpiozero's ``DistanceSensor`` fires the trigger and times the echo from the GPIO
driver's edge timestamps (lgpio's on a Pi 5 and on Bookworm), in a background thread
every 60 ms. This adapter keeps every shot's echo time with the moment it was taken and
reads the **median** of the fresh shots (a stray multipath echo is one spike among
them, filtered out), at the speed of sound of the air's current temperature (the PT100
sets it: :meth:`HcSr04.set_air_temperature`). A reading is ``inf`` when the median echo
is beyond ``max_distance_m`` (nothing in range) and NaN when no fresh shot came back
(a missing echo: the sensor or its wiring has failed), never a made-up distance.

Tests and ``--fake`` use gpiozero's own ``MockFactory`` with :class:`FakeHcSr04`'s pins:
its echo pin's edges carry exact timestamps (not ``sleep()``-timed ones), so the adapter
is held to ``c * t_echo / 2`` exactly, whatever the machine's load.

References
----------
Cytron Technologies, HC-SR04 User's Manual v1.0 (2013), "range = high level time x
velocity / 2". gpiozero 2.0 documentation, ``DistanceSensor`` and ``MockFactory``.
"""

from __future__ import annotations

import math
import time
import warnings
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from firefleet.errors import InputError

__all__ = ["FakeHcSr04", "HcSr04", "RangeReading", "speed_of_sound_m_s"]

HCSR04_MAX_RANGE_M = 4.0
"""The datasheet's maximum range [m]."""


def speed_of_sound_m_s(air_temperature_c: float) -> float:
    """The speed of sound in air at a temperature, ``331.3 + 0.606 T`` [m/s].

    Parameters
    ----------
    air_temperature_c : float
        Air temperature [deg C].

    Examples
    --------
    >>> from firefleet.robot import speed_of_sound_m_s
    >>> round(speed_of_sound_m_s(0.0), 1), round(speed_of_sound_m_s(20.0), 2)
    (331.3, 343.42)
    """
    return 331.3 + 0.606 * air_temperature_c


@dataclass(frozen=True)
class RangeReading:
    """One reading: the median of the fresh shots.

    Attributes
    ----------
    distance_m : float
        Distance to the nearest echo [m]; ``inf`` beyond ``max_distance_m``, NaN when no
        fresh shot returned an echo.
    echo_s : float
        The median echo time [s] (``inf``/NaN as above).
    shots : int
        Fresh shots with an echo behind the median.
    speed_of_sound_m_s : float
        The speed of sound the distance was computed with [m/s].
    """

    distance_m: float
    echo_s: float
    shots: int
    speed_of_sound_m_s: float


class HcSr04:
    """An HC-SR04 on two GPIO pins (module notes).

    Parameters
    ----------
    trigger_gpio, echo_gpio : int
        BCM GPIO numbers (the echo through a 5 V -> 3.3 V divider).
    max_distance_m : float
        Readings beyond this are ``inf`` (0 < max <= 4 m, the datasheet's range).
    shots : int
        How many recent shots the median takes (>= 1; 5 shots span 0.3 s).
    stale_s : float
        Shots older than this are not used [s].
    air_temperature_c : float
        The air's temperature until :meth:`set_air_temperature` says otherwise [deg C].
    pin_factory : gpiozero pin factory, optional
        gpiozero's default (lgpio on a Pi) when None; :class:`FakeHcSr04`'s ``factory``
        in tests.
    clock : callable
        Monotonic clock [s] (the shots' timestamps and the freshness test).

    Raises
    ------
    InputError
        On out-of-range parameters (naming them), or if gpiozero is missing or cannot
        open the pins.

    Examples
    --------
    >>> from firefleet.robot import FakeHcSr04, HcSr04, speed_of_sound_m_s
    >>> fake = FakeHcSr04(23, 24, echo_s=lambda shot: 2 * 1.5 / speed_of_sound_m_s(20.0))
    >>> with HcSr04(23, 24, pin_factory=fake.factory, air_temperature_c=20.0) as sonar:
    ...     reading = sonar.wait_for_reading(timeout_s=10.0)
    >>> round(reading.distance_m, 9)
    1.5
    """

    def __init__(
        self,
        trigger_gpio: int,
        echo_gpio: int,
        *,
        max_distance_m: float = HCSR04_MAX_RANGE_M,
        shots: int = 5,
        stale_s: float = 0.5,
        air_temperature_c: float = 20.0,
        pin_factory: Any = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if not 0.0 < max_distance_m <= HCSR04_MAX_RANGE_M:
            raise InputError(
                f"max_distance_m: {max_distance_m} m, expected 0 < max <= "
                f"{HCSR04_MAX_RANGE_M} m (the HC-SR04's range)"
            )
        if shots < 1 or not stale_s > 0.0:
            raise InputError(f"shots: {shots}, stale_s: {stale_s}; expected >= 1 and > 0")
        if trigger_gpio == echo_gpio:
            raise InputError(f"trigger_gpio and echo_gpio are both GPIO{echo_gpio}")
        self.max_distance_m = max_distance_m
        self.stale_s = stale_s
        self._clock = clock
        self._speed_m_s = speed_of_sound_m_s(air_temperature_c)
        self._shots: deque[tuple[float, float]] = deque(maxlen=shots)
        self.no_echoes = 0
        """Shots that returned no echo (gpiozero waited 100 ms for it)."""
        self.shots_fired = 0
        try:
            import gpiozero  # type: ignore[import-untyped]
        except ImportError as error:
            raise InputError(
                "the HC-SR04 needs gpiozero: pip install 'firefleet[robot]'"
            ) from error
        sensor_class = _timed_sensor_class(gpiozero.DistanceSensor)
        try:
            with warnings.catch_warnings():  # "use pigpio": lgpio's edge ticks are the kernel's
                warnings.simplefilter("ignore", gpiozero.PWMSoftwareFallback)
                self._sensor = sensor_class(
                    echo=echo_gpio,
                    trigger=trigger_gpio,
                    queue_len=1,
                    max_distance=max_distance_m,
                    threshold_distance=max_distance_m / 2,
                    partial=True,
                    pin_factory=pin_factory,
                    on_shot=self._on_shot,
                )
        except gpiozero.GPIOZeroError as error:
            raise InputError(
                f"HC-SR04 on trigger GPIO{trigger_gpio}, echo GPIO{echo_gpio}: {error}"
            ) from error
        self._sensor.speed_of_sound = self._speed_m_s

    def _on_shot(self, value: float | None) -> None:
        """One shot from gpiozero's thread: its value is ``min(1, d / max_distance)``."""
        self.shots_fired += 1
        if value is None:
            self.no_echoes += 1
            echo = math.nan
        elif value >= 1.0:
            echo = math.inf
        else:  # back to the echo time, so a later temperature applies to it too
            echo = 2.0 * value * self.max_distance_m / self._speed_m_s
        self._shots.append((self._clock(), echo))

    def set_air_temperature(self, air_temperature_c: float) -> None:
        """Use the speed of sound at this air temperature [deg C] (NaN: keep the last)."""
        if math.isfinite(air_temperature_c):
            self._speed_m_s = speed_of_sound_m_s(air_temperature_c)
            self._sensor.speed_of_sound = self._speed_m_s

    def read(self) -> RangeReading:
        """The median of the fresh shots that returned an echo (never blocks)."""
        now = self._clock()
        echoes = [e for t, e in list(self._shots) if now - t <= self.stale_s and not math.isnan(e)]
        if not echoes:
            return RangeReading(math.nan, math.nan, 0, self._speed_m_s)
        echo = float(np.median(echoes))
        distance = echo * self._speed_m_s / 2.0
        if not distance < self.max_distance_m:
            distance, echo = math.inf, math.inf
        return RangeReading(distance, echo, len(echoes), self._speed_m_s)

    def wait_for_reading(self, *, timeout_s: float, shots: int | None = None) -> RangeReading:
        """Wait until ``shots`` (default: the median's length) fresh shots are in [s]."""
        want = self._shots.maxlen if shots is None else shots
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            reading = self.read()
            if reading.shots >= (want or 1):
                return reading
            time.sleep(0.01)
        return self.read()

    def close(self) -> None:
        """Stop the sampling thread and release the pins."""
        if self._sensor.closed:
            return
        # gpiozero's DistanceSensor.close drops the trigger before it stops the thread
        # that fires it (an AttributeError in that thread); stop the thread first
        self._sensor._queue.stop()
        self._sensor.close()

    def __enter__(self) -> HcSr04:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _timed_sensor_class(base: Any) -> Any:
    """gpiozero's DistanceSensor that hands every shot to a callback (gpiozero is only
    imported when an HC-SR04 is opened, hence the class built here)."""

    class TimedDistanceSensor(base):  # type: ignore[misc]
        def __init__(self, *args: Any, on_shot: Callable[[float | None], None], **kwargs: Any):
            self._on_shot = on_shot  # before gpiozero starts its thread and freezes attributes
            super().__init__(*args, **kwargs)

        def _read(self) -> float | None:
            value: float | None = super()._read()
            self._on_shot(value)
            return value

    return TimedDistanceSensor


class FakeHcSr04:
    """An HC-SR04 on gpiozero's ``MockFactory`` with exactly timed echoes.

    gpiozero's own ``MockTriggerPin`` times its echo with ``sleep()``, which reads
    centimetres long on a loaded machine. Here the trigger pin, when driven high, raises
    and drops the echo pin at once with edge timestamps exactly ``echo_s(shot)`` apart
    (the ticks gpiozero's ``DistanceSensor`` measures between).

    Parameters
    ----------
    trigger_gpio, echo_gpio : int
        The pins the adapter will open.
    echo_s : callable
        Shot number (0, 1, ...) -> echo time [s], or None for a shot with no echo.

    Attributes
    ----------
    factory : gpiozero.pins.mock.MockFactory
        Pass it as the adapter's ``pin_factory``.
    """

    def __init__(
        self, trigger_gpio: int, echo_gpio: int, *, echo_s: Callable[[int], float | None]
    ) -> None:
        try:
            from gpiozero.pins.mock import (  # type: ignore[import-untyped]
                MockFactory,
                MockPin,
            )
        except ImportError as error:
            raise InputError("the HC-SR04 fake needs gpiozero") from error
        self.echo_s = echo_s
        self.factory = MockFactory()
        echo_class = _echo_pin_class(MockPin)
        trigger_class = _trigger_pin_class(MockPin)
        echo_pin = self.factory.pin(f"GPIO{echo_gpio}", pin_class=echo_class)
        self.factory.pin(
            f"GPIO{trigger_gpio}", pin_class=trigger_class, echo_pin=echo_pin, fake=self
        )


def _echo_pin_class(mock_pin: Any) -> Any:
    class ExactEchoPin(mock_pin):  # type: ignore[misc]
        """A mock input pin whose edges carry given timestamps."""

        def edge(self, state: bool, ticks: float) -> None:
            self._state = state
            self._last_change = ticks
            if self._when_changed is not None:
                self._call_when_changed()

    return ExactEchoPin


def _trigger_pin_class(mock_pin: Any) -> Any:
    class ExactTriggerPin(mock_pin):  # type: ignore[misc]
        """A mock output pin that, driven high, makes the echo pin pulse."""

        def __init__(self, factory: Any, info: Any, *, echo_pin: Any, fake: FakeHcSr04) -> None:
            super().__init__(factory, info)
            self._echo_pin, self._fake, self._shot = echo_pin, fake, 0

        def _set_state(self, value: bool) -> None:
            super()._set_state(value)
            if not value:
                return
            echo = self._fake.echo_s(self._shot)
            self._shot += 1
            if echo is None:
                return  # no echo: gpiozero waits for it, then gives up
            rise = float(self._shot)  # distinct, exactly representable ticks
            self._echo_pin.edge(True, rise)
            self._echo_pin.edge(False, rise + echo)

    return ExactTriggerPin
