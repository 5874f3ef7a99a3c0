"""Scenario keys of the team's hardware faults and of its wireless link (issue 16).

``faults`` lists motor faults (a robot's motors get a fraction of the voltage their
PIDs ask for, over a time window); ``link`` chooses the link model of the world loop
(:mod:`firefleet.sim.link`): a radio preset and the impairments that override it.
"""

from __future__ import annotations

import math
from typing import Literal

import pydantic

from firefleet.errors import InputError, check_fields
from firefleet.scenarios._claims import _STRICT

__all__ = ["LINK_PRESETS", "LinkSpec", "MotorFault"]

LINK_PRESETS = ("ideal", "xbee", "zigbee", "nrf24", "wifi")
"""The radio presets of :mod:`firefleet.sim.link`."""


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class MotorFault:
    """Robot ``robot`` (numbered from 1) drives its motors at ``voltage_scale`` times the
    voltage its PIDs command, from ``start_s`` (included) to ``end_s`` (excluded).

    Examples
    --------
    >>> from firefleet.scenarios._network import MotorFault
    >>> MotorFault(robot=2, start_s=20.0, end_s=40.0, voltage_scale=0.5).voltage_scale
    0.5
    """

    robot: int
    start_s: float
    end_s: float
    voltage_scale: float = 0.5

    def __post_init__(self) -> None:
        if self.robot < 1:
            raise InputError(f"faults.robot is numbered from 1, got {self.robot}")
        check_fields(self, "faults", non_negative=("start_s", "voltage_scale"))
        if not (math.isfinite(self.end_s) and self.end_s > self.start_s):
            raise InputError(
                f"faults.end_s must be after start_s ({self.start_s} s), got {self.end_s}"
            )
        if self.voltage_scale > 1.0:
            raise InputError(f"faults.voltage_scale must be in [0, 1], got {self.voltage_scale}")


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class LinkSpec:
    """The team's wireless link: a preset and what overrides it (None: the preset's).

    Attributes
    ----------
    preset : {"ideal", "xbee", "zigbee", "nrf24", "wifi"}
        The radio (:data:`firefleet.sim.link.PRESETS`, numbers from the data sheets).
    loss : float, optional
        Mean packet loss ratio of the channel's loss process, in [0, 1).
    burst_length : float, optional
        Mean length of a loss burst [messages], >= 1; 1 makes the loss independent
        (Bernoulli), more makes it a Gilbert-Elliott chain.
    delay_s, jitter_s : float, optional
        Latency [s] and the standard deviation of its Gaussian jitter [s] (truncated at
        0 delay).
    range_m : float, optional
        Hard range limit [m]; the path loss reaches the receiver's sensitivity there.
    rate_bit_s : float, optional
        Channel bit rate [bit/s].
    period_s : float, optional
        How often each robot broadcasts its progress [s] (None: every tick).
    timeout_s : float
        A value older than this is flagged stale and no longer used [s].
    shadowing_db : float, optional
        Standard deviation of the log-normal shadowing [dB].
    """

    preset: Literal["ideal", "xbee", "zigbee", "nrf24", "wifi"] = "ideal"
    loss: float | None = None
    burst_length: float | None = None
    delay_s: float | None = None
    jitter_s: float | None = None
    range_m: float | None = None
    rate_bit_s: float | None = None
    period_s: float | None = None
    timeout_s: float = 1.0
    shadowing_db: float | None = None

    def __post_init__(self) -> None:
        if self.loss is not None and not (0.0 <= self.loss < 1.0):
            raise InputError(f"link.loss must be in [0, 1), got {self.loss}")
        if self.burst_length is not None and not (
            math.isfinite(self.burst_length) and self.burst_length >= 1.0
        ):
            raise InputError(f"link.burst_length must be >= 1 message, got {self.burst_length}")
        for name in ("delay_s", "jitter_s", "shadowing_db"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value >= 0):
                raise InputError(f"link.{name} must be >= 0, got {value}")
        for name in ("range_m", "rate_bit_s", "period_s", "timeout_s"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value > 0):
                raise InputError(f"link.{name} must be > 0, got {value}")
