"""Section 2.5's link study: the breakdown it states and its figure, on a known study."""

from __future__ import annotations

import math
from typing import Any

from firefleet.report.network import BURSTS, DELAYS_S, LOSSES, breakdown_delay_s, study_png


def _study(spread_at_delay: dict[float, float]) -> dict[str, Any]:
    points = []
    for seed in (0, 1):
        for v in LOSSES:
            spread = spread_at_delay[0.0] if v == 0.0 else 0.2
            points.append(
                {
                    "axis": "loss",
                    "value": v,
                    "seed": seed,
                    "arrival_spread_s": spread,
                    "cross_track_rms_max_m": 0.03,
                }
            )
        for b in BURSTS[1:]:
            points.append(
                {
                    "axis": "burst",
                    "value": b,
                    "seed": seed,
                    "arrival_spread_s": 0.3,
                    "cross_track_rms_max_m": 0.03,
                }
            )
        for d in DELAYS_S[1:]:
            spread = spread_at_delay[d] + 0.1 * seed
            points.append(
                {
                    "axis": "delay",
                    "value": d,
                    "seed": seed,
                    "arrival_spread_s": spread,
                    "cross_track_rms_max_m": 0.03,
                }
            )
    return {"points": points, "clock_spread_s": 1.8, "seeds": [0, 1]}


def test_the_breakdown_is_the_first_latency_where_a_seed_spreads_past_the_bound() -> None:
    spreads = {0.0: 0.1, 0.5: 0.3, 0.9: 0.45, 1.2: 8.0}
    # at 0.9 s the second seed reaches 0.55 s > 0.5 s: that is where it breaks
    assert breakdown_delay_s(_study(spreads)) == 0.9
    spreads[0.9] = 0.3
    assert breakdown_delay_s(_study(spreads)) == 1.2
    spreads[1.2] = 0.3
    assert math.isinf(breakdown_delay_s(_study(spreads)))
    spreads[0.0] = 0.7  # already broken without latency
    assert breakdown_delay_s(_study(spreads)) == 0.0


def test_the_figure_is_a_png() -> None:
    png = study_png(_study({0.0: 0.0, 0.5: 0.3, 0.9: 0.45, 1.2: 8.0}))
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(png) > 20_000
