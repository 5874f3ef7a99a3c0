"""The recorded time series of a run."""

from __future__ import annotations

import io
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from firefleet._typing import FloatArray
from firefleet.scenarios.schema import Scenario

__all__ = ["SimResult"]


@dataclass(frozen=True)
class SimResult:
    """Time series of a run, sampled every ``record_every`` steps (T samples, N robots).

    Attributes
    ----------
    scenario : Scenario
        What was run (with the seed actually used).
    t : ndarray, shape (T,)
        Time [s].
    pose : ndarray, shape (T, N, 3)
        True poses: x [m], y [m], theta [rad].
    wheel_speed_rad_s : ndarray, shape (T, N, 2)
        True wheel speeds, right and left [rad/s].
    wheel_speed_measured_rad_s : ndarray, shape (T, N, 2)
        Speeds measured by the encoders [rad/s].
    wheel_speed_ref_rad_s : ndarray, shape (T, N, 2)
        Speed references [rad/s] (NaN in open loop).
    current_a : ndarray, shape (T, N, 2)
        Motor currents [A].
    voltage_v : ndarray, shape (T, N, 2)
        Motor voltages applied from that sample on [V].
    load_torque_n_m : ndarray, shape (T, N, 2)
        Load torques applied from that sample on [N m].
    extra : mapping of str to ndarray
        What the scenario's controller adds, by the name ``result.npz`` gives it, the
        unit in the name's suffix, time first (for example ``y_err_m`` (T, N)).

    Robots without wheels (point masses) have wheel arrays of shape (T, N, 0), and
    ``result.npz`` leaves those out.

    Examples
    --------
    >>> import firefleet
    >>> result = firefleet.simulate(firefleet.load_scenario("motor-pid"), record_every=100)
    >>> result.t.shape, result.pose.shape, result.wheel_speed_rad_s.shape
    ((11,), (11, 1, 3), (11, 1, 2))
    >>> sorted(result.arrays())[:3]
    ['current_a', 'load_torque_n_m', 'pose']
    """

    scenario: Scenario
    t: FloatArray
    pose: FloatArray
    wheel_speed_rad_s: FloatArray
    wheel_speed_measured_rad_s: FloatArray
    wheel_speed_ref_rad_s: FloatArray
    current_a: FloatArray
    voltage_v: FloatArray
    load_torque_n_m: FloatArray
    extra: Mapping[str, FloatArray] = field(default_factory=dict)

    def arrays(self) -> dict[str, FloatArray]:
        """The arrays by the names ``result.npz`` uses (``t``, ``pose``, and the rest)."""
        wheels = {
            "wheel_speed_rad_s": self.wheel_speed_rad_s,
            "wheel_speed_measured_rad_s": self.wheel_speed_measured_rad_s,
            "wheel_speed_ref_rad_s": self.wheel_speed_ref_rad_s,
            "current_a": self.current_a,
            "voltage_v": self.voltage_v,
            "load_torque_n_m": self.load_torque_n_m,
        }
        return {
            "t": self.t,
            "pose": self.pose,
            **{name: a for name, a in wheels.items() if a.shape[-1] > 0},
            **self.extra,
        }

    def to_npz_bytes(self) -> bytes:
        """The arrays as the bytes of a compressed ``.npz`` file."""
        buffer = io.BytesIO()
        np.savez_compressed(buffer, **self.arrays())  # type: ignore[arg-type]
        return buffer.getvalue()
