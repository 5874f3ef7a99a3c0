"""Path-following metrics of a run whose robots were not heard for its first ticks
(``firefleet team`` in real time: the plant holds NaN in a robot's series until its
first command arrives)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from firefleet import load_scenario, simulate
from firefleet.sim.kinds.path_following import path_following_metrics


def test_peaks_skip_the_ticks_before_a_robot_was_heard() -> None:
    result = simulate(load_scenario("coop-different-paths"))
    extra = dict(result.extra)
    for key in ("omega_ref_rad_s", "y_err_m"):
        a = np.array(extra[key], dtype=float)
        a[:7, 1] = np.nan  # robot 2 first heard at the 8th tick
        a[:3, 2] = np.nan
        extra[key] = a
    unheard = dataclasses.replace(result, extra=extra)
    m = path_following_metrics(unheard)
    for key, name in (("omega_ref_rad_s", "omega_peak_rad_s"), ("y_err_m", "y_err_peak_m")):
        a = np.abs(extra[key])
        want = [np.abs(a[k:, i]).max() for i, k in enumerate((0, 7, 3))]
        assert m[name] == want
    for name in ("longest_path_omega_peak_margin_rad_s", "longest_path_y_err_peak_margin_m"):
        margin = m[name]
        assert isinstance(margin, float)
        assert math.isfinite(margin)
