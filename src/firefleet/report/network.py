"""Section 2.5 of the report, beyond the deliverable: cooperation over an imperfect link.

Experiment 1 with the motor fault (``coop-motor-fault``: the team must wait for robot
2, so the coordination has work to do) run over the XBee link
(:mod:`firefleet.sim.link`) with one impairment swept at a time: independent loss
(0-50 %), loss bursts (mean length 1-20 at 25 % loss) and latency (0-1.2 s, with 20 ms
of jitter), several seeds per point. The arrival spread and the worst robot's
cross-track error are drawn against each, every seed's run shown; the delay at which
cooperation breaks down (the spread first exceeds the scenario's 0.5 s) is stated.

Next to it, the formation over the same link (:mod:`firefleet.report.formation_link`:
``formation-moving``, each robot's neighbours' points as messages): its radius and
spacing errors against the same impairments, and the delay at which it breaks down.
"""

from __future__ import annotations

import dataclasses
import io
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from firefleet.report import formation_link
from firefleet.report.html import ReportRun
from firefleet.scenarios import Claim, load_scenario
from firefleet.scenarios._network import LinkSpec
from firefleet.scenarios.schema import PathFollowing
from firefleet.sim.kinds.path_following import path_following_metrics
from firefleet.sim.metrics import metrics_document
from firefleet.sim.registry import task_kind

__all__ = ["BURSTS", "DELAYS_S", "LOSSES", "link_study", "link_study_run"]

LOSSES = (0.0, 0.25, 0.5)
"""Independent loss ratios swept."""
BURSTS = (1.0, 5.0, 20.0)
"""Mean loss burst lengths swept, at 25 % loss [messages]."""
DELAYS_S = (0.0, 0.5, 0.9, 1.2)
"""Latencies swept [s] (the law's timeout is 1 s)."""
SPREAD_BOUND_S = 0.5
"""The scenario's arrival-spread claim [s]: cooperation holds while the spread stays below."""


def _points() -> list[tuple[str, float, LinkSpec]]:
    """(axis, value, link) of every point: loss, burst and delay, one at a time."""
    return formation_link.impairment_points(LOSSES, BURSTS, DELAYS_S)


def link_study(
    seeds: Sequence[int] = (0, 1),
    progress: Callable[[int, int], None] | None = None,
) -> dict[str, Any]:
    """Run the study (module notes).

    Returns
    -------
    dict
        ``points``: one dict per run (axis, value, seed, arrival spread [s], worst
        cross-track RMS [m], messages lost [share], oldest value used [s]); and
        ``clock_spread_s``, the spread without coordination (the open-loop clock).
    """
    base = load_scenario("coop-motor-fault")
    kind = task_kind("path-following")
    rec = np.arange(0, base.n_steps + 1, 10)
    runs = [(axis, value, spec, seed) for axis, value, spec in _points() for seed in seeds]
    total = len(runs) + 1
    out: list[dict[str, Any]] = []
    for done, (axis, value, spec, seed) in enumerate(runs):
        scn = dataclasses.replace(base, link=spec, seed=seed)
        m: dict[str, Any] = dict(path_following_metrics(kind.run(scn, rec)))
        sent = float(m["messages_sent"])
        out.append(
            {
                "axis": axis,
                "value": value,
                "seed": seed,
                "arrival_spread_s": m["arrival_spread_s"],
                "cross_track_rms_max_m": max(m["cross_track_rms_m"]),
                "lost_share": float(m["messages_lost"]) / sent if sent else math.nan,
                "message_age_max_s": m["message_age_max_s"],
            }
        )
        if progress is not None:
            progress(done + 1, total)
    assert isinstance(base.command, PathFollowing)
    clock = dataclasses.replace(
        base, command=dataclasses.replace(base.command, coordination="clock")
    )
    clock_spread = path_following_metrics(kind.run(clock, rec))["arrival_spread_s"]
    if progress is not None:
        progress(total, total)
    return {"points": out, "clock_spread_s": clock_spread, "seeds": list(seeds)}


def breakdown_delay_s(study: dict[str, Any]) -> float:
    """The smallest latency swept at which some seed's spread exceeds the bound (inf if
    none); the loss-free point (delay 0) counts as the first."""
    for d in DELAYS_S:
        pts = [p for p in study["points"] if _on_delay_axis(p, d)]
        if any(not (p["arrival_spread_s"] <= SPREAD_BOUND_S) for p in pts):
            return d
    return math.inf


def _on_delay_axis(point: dict[str, Any], d: float) -> bool:
    if d == 0.0:
        return bool(point["axis"] == "loss" and point["value"] == 0.0)
    return bool(point["axis"] == "delay" and point["value"] == d)


def study_png(study: dict[str, Any]) -> bytes:
    """The study's figure: spread and cross-track error against each impairment."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    axes_spec = (
        ("loss", "independent loss [%]", 100.0),
        ("burst", "mean loss burst at 25 % loss [messages]", 1.0),
        ("delay", "latency [s] (jitter 20 ms)", 1.0),
    )
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.5), sharey="row")
    for col, (axis, label, scale) in enumerate(axes_spec):
        pts = formation_link.axis_points(study, axis)
        values = sorted({p["value"] for p in pts})
        for row, (key, ylabel) in enumerate(
            (
                ("arrival_spread_s", "arrival spread [s]"),
                ("cross_track_rms_max_m", "worst cross-track RMS [m]"),
            )
        ):
            ax = axes[row, col]
            x = np.array([p["value"] for p in pts]) * scale
            y = np.array([p[key] for p in pts], dtype=float)
            if row == 0:  # spreads from 0 to some 10 s: a log axis, 0 drawn at its floor
                y = np.maximum(y, 0.05)
            ax.plot(x, y, "o", color="tab:blue", alpha=0.5, label="one seed")
            floor = 0.05 if row == 0 else 0.0
            at = [[max(p[key], floor) for p in pts if p["value"] == v] for v in values]
            mean = [np.nanmean(a) for a in at]
            lo = [np.nanmin(a) for a in at]
            hi = [np.nanmax(a) for a in at]
            xs = np.array(values) * scale
            ax.plot(xs, mean, "-", color="tab:blue", label="mean over seeds")
            ax.fill_between(xs, lo, hi, color="tab:blue", alpha=0.15, label="seeds' range")
            if row == 0:
                ax.axhline(SPREAD_BOUND_S, color="tab:red", ls="--", lw=1, label="claim: 0.5 s")
                ax.axhline(
                    study["clock_spread_s"], color="0.4", ls=":", lw=1, label="open-loop clock"
                )
            if axis == "burst":
                ax.set_xscale("log")
            if row == 0:
                ax.set_yscale("log")
                ax.set_ylim(0.04, 20.0)
            else:
                ax.set_ylim(0.0, 0.06)
            ax.set_xlabel(label)
            if col == 0:
                ax.set_ylabel(ylabel)
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8, loc="upper left")
    axes[0, 0].text(
        0.98, 0.03, "0 drawn at 0.05 s", transform=axes[0, 0].transAxes, ha="right", fontsize=7
    )
    fig.suptitle(
        "coop-motor-fault over the XBee link: one impairment at a time, "
        f"{len(study['seeds'])} seeds per point"
    )
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    return buffer.getvalue()


def link_study_run(progress: Callable[[int, int], None] | None = None) -> ReportRun:
    """The study as an entry of the report, with its claims (the path-following study,
    then the formation's; ``progress`` counts the runs of both)."""
    first = 2 * len(_points()) + 1  # the two default seeds, and the clock
    total = first + 2 * len(formation_link.points()) + 1

    def shifted(offset: int) -> Callable[[int, int], None] | None:
        if progress is None:
            return None
        report = progress
        return lambda done, _: report(offset + done, total)

    study = link_study(progress=shifted(0))
    formation = formation_link.formation_link_study(progress=shifted(first))
    f_breakdown = formation_link.breakdown_delay_s(formation)
    f_loss = [p for p in formation["points"] if p["axis"] == "loss"]
    loss_pts = [p for p in study["points"] if p["axis"] in ("loss", "burst")]
    breakdown = breakdown_delay_s(study)
    metrics: dict[str, Any] = {
        "arrival_spread_max_under_loss_s": max(p["arrival_spread_s"] for p in loss_pts),
        "breakdown_delay_s": breakdown,
        "cross_track_rms_max_m": max(p["cross_track_rms_max_m"] for p in study["points"]),
        "clock_arrival_spread_s": study["clock_spread_s"],
        "formation_radius_error_max_under_loss_m": max(p["radius_error_max_m"] for p in f_loss),
        "formation_spacing_error_max_under_loss_deg": max(
            p["spacing_error_max_deg"] for p in f_loss
        ),
        "formation_breakdown_delay_s": f_breakdown,
        "runs": len(study["points"]) + 1 + len(formation["points"]) + 1,
    }
    claims = (
        Claim(
            metric="arrival_spread_max_under_loss_s",
            op="<=",
            value=SPREAD_BOUND_S,
            source="firefleet: the team still arrives together with up to 50 % of the "
            "messages lost, independent or in bursts (the law predicts from the last rate)",
        ),
        Claim(
            metric="breakdown_delay_s",
            op=">=",
            value=0.5,
            source="firefleet: cooperation holds up to 500 ms of latency",
        ),
        Claim(
            metric="formation_radius_error_max_under_loss_m",
            op="<=",
            value=0.15,
            source="firefleet: the moving formation stays within 5 % of alpha with up to "
            "50 % of its neighbours' messages lost independently (prediction from the "
            "last velocity)",
        ),
        Claim(
            metric="formation_spacing_error_max_under_loss_deg",
            op="<=",
            value=2.0,
            source="firefleet: and regular within 2 degrees",
        ),
    )
    if math.isfinite(breakdown):
        before = max((d for d in DELAYS_S if d < breakdown), default=0.0)
        verdict = f"Cooperation breaks down between {before:g} s and {breakdown:g} s of latency"
    else:
        verdict = "Cooperation held at every latency swept"
    if math.isfinite(f_breakdown):
        f_before = max((d for d in formation_link.DELAYS_S if d < f_breakdown), default=0.0)
        f_verdict = (
            f"the moving formation breaks down between {f_before * 1e3:g} and "
            f"{f_breakdown * 1e3:g} ms of latency (leaves 0.15 m or 2 degrees)"
        )
    else:
        f_verdict = "the moving formation held at every latency swept (up to 500 ms)"
    return ReportRun(
        name="link-study",
        title="Cooperation over an imperfect wireless link (XBee): loss, bursts, latency",
        reproduces="beyond Section 2.5: the deliverable assumes an ideal link",
        deliverable_says=(
            '"it has been assumed that ideal communication link between all the robots '
            "exists. A wireless connection can be established with either a Xbee, ZigBee or "
            f"NRF module.\" {verdict} (the spread first exceeds 0.5 s; the law's timeout "
            f"is 1 s); {f_verdict}."
        ),
        command="python -c 'from firefleet.report.network import link_study_run; link_study_run()'",
        files={
            "link_study.png": study_png(study),
            "formation_link_study.png": formation_link.formation_study_png(formation),
        },
        figures=("link_study.png", "formation_link_study.png"),
        document=metrics_document("link-study", claims, metrics),
        captions={
            "link_study.png": (
                "Arrival spread (top) and the worst robot's cross-track RMS (bottom) of "
                "coop-motor-fault against loss, burst length and latency; dots are single "
                "runs, the band the seeds' range. The dotted line is the open-loop clock's "
                "spread under the same fault."
            ),
            "formation_link_study.png": (
                "Largest radius error (top) and spacing error (bottom) of formation-moving "
                "(20 s, started formed) against loss, burst length and latency over the "
                "XBee link; dots are single runs, the band the seeds' range, the dashed "
                "line the scenario's bound, the dotted line the ideal link."
            ),
        },
    )
