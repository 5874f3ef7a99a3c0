"""Formation control (deliverable section 2.3): the team keeps a regular polygon around a leader.

The run is :func:`firefleet.sim.formation.simulate_formation` (its own loop: a point
mass's sub-stepped force law does not fit the world loop's wheel stages), its neighbours
over the world loop's link stage when the scenario's ``link:`` is impaired
(:mod:`firefleet.sim._formation_link`), its metrics
:func:`firefleet.sim.formation.formation_metrics`, its figures
:func:`firefleet.report.formation.formation_figures`.
"""

from __future__ import annotations

from firefleet.sim.formation import formation_metrics, simulate_formation
from firefleet.sim.registry import Metrics, TaskKind
from firefleet.sim.result import SimResult

__all__ = ["KINDS"]


def _figures(result: SimResult, metrics: Metrics) -> dict[str, bytes]:
    from firefleet.report.formation import formation_figures

    return formation_figures(result, metrics)


KINDS = (
    TaskKind(
        name="formation",
        metric_names=(
            "radius_error_max_m",
            "spacing_error_max_deg",
            "min_clearance_m",
            "radius_settling_time_s",
            "final_radius_m",
            "messages_sent",
            "messages_lost",
            "message_age_max_s",
        ),
        metrics=formation_metrics,
        figures=_figures,
        runner=simulate_formation,
    ),
)
"""The formation kind."""
