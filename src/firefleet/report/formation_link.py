"""Section 2.5 of the report, beyond the deliverable: a formation over an imperfect link.

``formation-moving`` (four diff-drive robots in the regular formation about a leader
driving a two-segment path), shortened to 20 s and started on its polygon so every
second of it is the formation travelling, run over the XBee link
(:mod:`firefleet.sim.link`, neighbours' points as messages:
:mod:`firefleet.sim._formation_link`) with one impairment swept at a time: independent
loss (0-50 %), loss bursts (mean length 8 at 25 % loss) and latency (0-500 ms, with 20
ms of jitter), several seeds per point. The formation error (the kind's
``radius_error_max_m`` and ``spacing_error_max_deg``) is drawn against each, every
seed's run shown; the delay at which the formation breaks down (some seed leaves the
scenario's bounds, 0.15 m or 2 degrees) is stated.
"""

from __future__ import annotations

import dataclasses
import io
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from firefleet.scenarios import load_scenario
from firefleet.scenarios._network import LinkSpec
from firefleet.scenarios.schema import Formation, Scenario
from firefleet.sim.formation import FormationDivergedError
from firefleet.sim.registry import task_kind

__all__ = [
    "BOUNDS",
    "BURSTS",
    "DELAYS_S",
    "LOSSES",
    "axis_points",
    "breakdown_delay_s",
    "formation_link_study",
    "formation_study_png",
    "impairment_points",
    "points",
    "study_scenario",
]

LOSSES = (0.0, 0.25, 0.5)
"""Independent loss ratios swept."""
BURSTS = (1.0, 8.0)
"""Mean loss burst lengths swept, at 25 % loss [messages]."""
DELAYS_S = (0.0, 0.1, 0.2, 0.3, 0.5)
"""Latencies swept [s] (jitter 20 ms; the link's timeout is 1 s)."""
BOUNDS = {"radius_error_max_m": 0.15, "spacing_error_max_deg": 2.0}
"""formation-moving's claims: the formation holds while both stay within."""


def study_scenario() -> Scenario:
    """``formation-moving`` shortened to 20 s, the leader driving a 4 m and a 3 m
    segment from 1 s on (it turns its corner at 13 s), the robots started on the
    regular polygon (look-ahead points on the 3 m circle).

    Examples
    --------
    >>> scn = study_scenario()
    >>> scn.duration_s, scn.n_robots, scn.command.leader.waypoints_m[-1]
    (20.0, 4, (6.4, 1.8))
    """
    base = load_scenario("formation-moving")
    cmd = base.command
    assert isinstance(cmd, Formation)
    n = base.n_robots
    angles = 2.0 * math.pi * np.arange(n) / n
    look = cmd.look_ahead_m
    poses = tuple(
        (float(cmd.alpha_m * math.cos(a) - look), float(cmd.alpha_m * math.sin(a)), 0.0)
        for a in angles
    )
    leader = dataclasses.replace(
        cmd.leader, waypoints_m=((0.0, 0.0), (4.0, 0.0), (6.4, 1.8)), start_s=1.0
    )
    command = dataclasses.replace(cmd, leader=leader, scatter_m=0.0, formed_by_s=0.0)
    return dataclasses.replace(base, duration_s=20.0, poses=poses, command=command)


def impairment_points(
    losses: Sequence[float], bursts: Sequence[float], delays_s: Sequence[float]
) -> list[tuple[str, float, LinkSpec]]:
    """(axis, value, link) of a study's points over XBee: each loss, each mean burst
    length (> 1) at 25 % loss, each delay (> 0) with 20 ms of jitter, one at a time (the
    path-following study of :mod:`firefleet.report.network` sweeps the same axes)."""
    out = [("loss", v, LinkSpec(preset="xbee", loss=v)) for v in losses]
    out += [
        ("burst", b, LinkSpec(preset="xbee", loss=0.25, burst_length=b)) for b in bursts if b > 1
    ]
    out += [
        ("delay", d, LinkSpec(preset="xbee", delay_s=d, jitter_s=0.02)) for d in delays_s if d > 0
    ]
    return out


def points() -> list[tuple[str, float, LinkSpec]]:
    """(axis, value, link) of every point of this study (:func:`impairment_points`)."""
    return impairment_points(LOSSES, BURSTS, DELAYS_S)


def formation_link_study(
    seeds: Sequence[int] = (0, 1),
    progress: Callable[[int, int], None] | None = None,
) -> dict[str, Any]:
    """Run the study (module notes).

    Returns
    -------
    dict
        ``points``: one dict per run (axis, value, seed, ``radius_error_max_m`` [m],
        ``spacing_error_max_deg``, ``lost_share``, ``message_age_max_s`` [s]; a run that
        diverged has infinite errors); ``ideal``: the errors over the ideal link;
        ``seeds``.
    """
    base = study_scenario()
    kind = task_kind("formation")
    rec = np.arange(0, base.n_steps + 1, 10)
    runs = [(axis, value, spec, seed) for axis, value, spec in points() for seed in seeds]
    total = len(runs) + 1
    out: list[dict[str, Any]] = []
    for done, (axis, value, spec, seed) in enumerate(runs):
        scn = dataclasses.replace(base, link=spec, seed=seed)
        point: dict[str, Any] = {"axis": axis, "value": value, "seed": seed}
        try:
            m = kind.metrics(kind.run(scn, rec))
        except FormationDivergedError:
            point.update(dict.fromkeys(BOUNDS, math.inf), lost_share=math.nan)
            point["message_age_max_s"] = math.nan
        else:
            sent = float(m["messages_sent"])  # type: ignore[arg-type]
            point.update({key: m[key] for key in BOUNDS})
            point["lost_share"] = float(m["messages_lost"]) / sent if sent else math.nan  # type: ignore[arg-type]
            point["message_age_max_s"] = m["message_age_max_s"]
        out.append(point)
        if progress is not None:
            progress(done + 1, total)
    ideal = kind.metrics(kind.run(base, rec))
    if progress is not None:
        progress(total, total)
    return {
        "points": out,
        "ideal": {key: ideal[key] for key in BOUNDS},
        "seeds": list(seeds),
    }


def _holds(point: dict[str, Any]) -> bool:
    return all(point[key] <= bound for key, bound in BOUNDS.items())


def axis_points(study: dict[str, Any], axis: str) -> list[dict[str, Any]]:
    """The points of an axis, with the shared ones (loss 0 for delay 0, loss 25 % for
    burst 1): of this study, or of the path-following one (the same axes)."""
    pts = study["points"]
    if axis == "delay":
        zero = [
            dict(p, axis="delay", value=0.0)
            for p in pts
            if p["axis"] == "loss" and p["value"] == 0.0
        ]
        return zero + [p for p in pts if p["axis"] == "delay"]
    if axis == "burst":
        one = [
            dict(p, axis="burst", value=1.0)
            for p in pts
            if p["axis"] == "loss" and p["value"] == 0.25
        ]
        return one + [p for p in pts if p["axis"] == "burst"]
    return [p for p in pts if p["axis"] == axis]


def breakdown_delay_s(study: dict[str, Any]) -> float:
    """The smallest latency swept at which some seed leaves :data:`BOUNDS` (inf if none).

    Examples
    --------
    >>> pts = [{"axis": "loss", "value": 0.0, "radius_error_max_m": 0.01,
    ...         "spacing_error_max_deg": 0.5},
    ...        {"axis": "delay", "value": 0.3, "radius_error_max_m": 0.2,
    ...         "spacing_error_max_deg": 0.5}]
    >>> breakdown_delay_s({"points": pts})
    0.3
    """
    pts = axis_points(study, "delay")
    for d in sorted({p["value"] for p in pts}):
        if not all(_holds(p) for p in pts if p["value"] == d):
            return float(d)
    return math.inf


def formation_study_png(study: dict[str, Any]) -> bytes:
    """The study's figure: radius and spacing error against each impairment."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    axes_spec = (
        ("loss", "independent loss [%]", 100.0),
        ("burst", "mean loss burst at 25 % loss [messages]", 1.0),
        ("delay", "latency [ms] (jitter 20 ms)", 1000.0),
    )
    rows = (
        ("radius_error_max_m", "largest radius error [m]"),
        ("spacing_error_max_deg", "largest spacing error [deg]"),
    )
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.5), sharey="row")
    for col, (axis, label, scale) in enumerate(axes_spec):
        pts = axis_points(study, axis)
        values = sorted({p["value"] for p in pts})
        for row, (key, ylabel) in enumerate(rows):
            ax = axes[row, col]
            top = 20.0 * BOUNDS[key]  # a diverged run drawn at the top
            y = np.minimum(np.array([p[key] for p in pts], dtype=float), top)
            x = np.array([p["value"] for p in pts]) * scale
            ax.plot(x, y, "o", color="tab:blue", alpha=0.5, label="one seed")
            at = [[min(p[key], top) for p in pts if p["value"] == v] for v in values]
            xs = np.array(values) * scale
            ax.plot(xs, [np.mean(a) for a in at], "-", color="tab:blue", label="mean over seeds")
            ax.fill_between(
                xs,
                [min(a) for a in at],
                [max(a) for a in at],
                color="tab:blue",
                alpha=0.15,
                label="seeds' range",
            )
            ax.axhline(BOUNDS[key], color="tab:red", ls="--", lw=1, label="scenario's bound")
            ax.axhline(study["ideal"][key], color="0.4", ls=":", lw=1, label="ideal link")
            ax.set_yscale("log")
            ax.set_ylim(BOUNDS[key] / 200.0, top * 1.5)
            if axis == "burst":
                ax.set_xscale("log")
                ax.set_xticks(xs, [f"{v:g}" for v in values])
                ax.xaxis.set_minor_formatter(NullFormatter())
            ax.set_xlabel(label)
            if col == 0:
                ax.set_ylabel(ylabel)
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8, loc="upper left")
    fig.suptitle(
        "formation-moving (20 s, 4 diff-drive robots) over the XBee link: one impairment "
        f"at a time, {len(study['seeds'])} seeds per point"
    )
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    return buffer.getvalue()
