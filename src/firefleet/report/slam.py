"""Figures of a SLAM run: the map and tracks (PNG) and their animation (GIF).

matplotlib is imported here, lazily, when a figure is made (Agg backend); the GIF is
written by matplotlib's ``PillowWriter`` (pillow comes with matplotlib).
"""

from __future__ import annotations

import io
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from firefleet._typing import FloatArray
from firefleet.estimation.fastslam import FastSlamResult
from firefleet.estimation.logs import SlamLog
from firefleet.report.html import ReportRun
from firefleet.scenarios.schema import Claim

__all__ = ["slam_animation_gif", "slam_figure_png", "slam_report_runs"]


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _limits(log: SlamLog, result: FastSlamResult) -> tuple[float, float, float, float]:
    pts = [result.trajectory[:, :2], result.dead_reckoning[:, :2], result.landmarks]
    if log.truth_pose is not None:
        pts.append(log.truth_pose[:, :2])
    if log.truth_landmarks is not None:
        pts.append(log.truth_landmarks)
    allp = np.concatenate([p for p in pts if p.size], axis=0)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    pad = 0.05 * float(np.max(hi - lo)) + 1.0
    return lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad


def _static(ax: Any, log: SlamLog, result: FastSlamResult) -> None:
    dr = result.dead_reckoning
    ax.plot(dr[:, 0], dr[:, 1], color="tab:orange", ls="--", lw=1.0, label="odometry only")
    if log.truth_pose is not None:
        t = log.truth_pose
        ax.plot(t[:, 0], t[:, 1], color="0.55", lw=2.5, alpha=0.6, label="ground truth")
    if log.truth_landmarks is not None:
        m = log.truth_landmarks
        ax.plot(m[:, 0], m[:, 1], "k+", ms=8, mew=1.2, label="true landmarks")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)


def _title(log: SlamLog, result: FastSlamResult) -> str:
    p = result.params
    return (
        f"FastSLAM {p.version}.0, {p.n_particles} particles, {p.association} association: "
        f"{Path(log.name).name}"
    )


def slam_figure_png(
    log: SlamLog, result: FastSlamResult, *, reference: FloatArray | None = None
) -> bytes:
    """The estimated trajectory and map over the odometry-only track (and the truth).

    Parameters
    ----------
    log : SlamLog
    result : FastSlamResult
    reference : ndarray, shape (T, 2), optional
        A reference trajectory to draw too (GTSAM's batch optimum on real data) [m].

    Returns
    -------
    bytes
        A PNG image.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 7))
    _static(ax, log, result)
    if reference is not None:
        ax.plot(
            reference[:, 0], reference[:, 1], color="0.2", lw=2.4, alpha=0.35, label="GTSAM optimum"
        )
    tr = result.trajectory
    ax.plot(tr[:, 0], tr[:, 1], color="tab:blue", lw=1.2, label="FastSLAM trajectory")
    lm = result.landmarks
    ax.plot(lm[:, 0], lm[:, 1], "o", mfc="none", mec="tab:red", ms=6, label="FastSLAM landmarks")
    ax.plot([0.0], [0.0], "g^", ms=9, label="start")
    x0, x1, y0, y1 = _limits(log, result)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_title(_title(log, result), fontsize=10)
    ax.legend(loc="best", fontsize=8)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    return buffer.getvalue()


def slam_animation_gif(log: SlamLog, result: FastSlamResult, *, fps: int = 8) -> bytes:
    """An animation of the run: the filtered track growing and the map at each snapshot.

    Parameters
    ----------
    log : SlamLog
    result : FastSlamResult
        Run with ``n_snapshots > 0``; one frame per snapshot.
    fps : int
        Frames per second of the GIF.

    Returns
    -------
    bytes
        A GIF image.
    """
    plt = _pyplot()
    from matplotlib.animation import FuncAnimation, PillowWriter

    steps = result.snapshot_steps
    if steps.size == 0:
        steps = np.array([result.trajectory.shape[0] - 1])
        snaps: tuple[FloatArray, ...] = (result.landmarks,)
    else:
        snaps = result.snapshot_landmarks
    fig, ax = plt.subplots(figsize=(6, 5.4))
    _static(ax, log, result)
    x0, x1, y0, y1 = _limits(log, result)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    (track,) = ax.plot([], [], color="tab:blue", lw=1.2, label="FastSLAM (filtered)")
    (marks,) = ax.plot([], [], "o", mfc="none", mec="tab:red", ms=5, label="landmarks")
    (robot,) = ax.plot([], [], "b>", ms=8)
    ax.legend(loc="upper right", fontsize=7)
    title = ax.set_title("", fontsize=9)

    def draw(i: int) -> tuple[Any, ...]:
        k = int(steps[i])
        f = result.filtered[: k + 1]
        track.set_data(f[:, 0], f[:, 1])
        lm = snaps[i]
        marks.set_data(lm[:, 0], lm[:, 1])
        robot.set_data([f[-1, 0]], [f[-1, 1]])
        title.set_text(f"pose {k + 1} of {result.filtered.shape[0]}: {lm.shape[0]} landmarks")
        return track, marks, robot, title

    anim = FuncAnimation(fig, draw, frames=len(steps), blit=False)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "slam.gif"
        anim.save(str(path), writer=PillowWriter(fps=fps), dpi=70)
        data = path.read_bytes()
    plt.close(fig)
    return data


def slam_report_runs(victoria_park: Path | None = None, *, seed: int = 1) -> tuple[ReportRun, ...]:
    """Section 2.7.3 of the report: FastSLAM on the simulated loop and on Victoria Park.

    Parameters
    ----------
    victoria_park : Path, optional
        The Victoria Park log in GTSAM's text format; without it (or without GTSAM) only
        the simulated loop is run.
    seed : int
        Seed of the filter's randomness on Victoria Park (the simulated loop uses 0,
        as ``firefleet slam sim-loop`` does).

    Returns
    -------
    tuple of ReportRun
        ``slam-sim-loop`` (FastSLAM 2.0 with firefleet's defaults against the known
        truth: the claims of ``firefleet slam sim-loop``), and ``slam-victoria-park``
        (the default run's absolute trajectory error against GTSAM's optimum, claimed
        at most 5 m).
    """
    from firefleet.estimation.alignment import absolute_trajectory_error
    from firefleet.estimation.fastslam import (
        FastSlamParams,
        default_n_particles,
        run_fastslam,
        slam_claims,
        slam_summary,
    )
    from firefleet.estimation.logs import read_log
    from firefleet.estimation.reference import gtsam_optimum
    from firefleet.sim.metrics import metrics_document
    from firefleet.sim.world import SIM_LOOP, load_or_simulate_log

    says = (
        '"In our case, we will use a Particle Filter (PF) based SLAM" (2.7.3); the posterior '
        "p(x_t | o_t) is proportional to p(o_t | x_t) p(x_t | x_t-1). The deliverable leaves "
        'the details "to the next report".'
    )
    params = FastSlamParams(version=2, n_particles=default_n_particles("known"))
    log = load_or_simulate_log(SIM_LOOP, seed=0)
    result = run_fastslam(log, np.random.default_rng(0), params=params, n_snapshots=0)
    summary = slam_summary(log, result)
    runs = [
        ReportRun(
            name="slam-sim-loop",
            title="FastSLAM 2.0 on a simulated 100 m loop among heat sources",
            reproduces="Section 2.7.3: particle-filter SLAM",
            deliverable_says=says,
            command="firefleet slam sim-loop",
            files={"slam.png": slam_figure_png(log, result)},
            figures=("slam.png",),
            document=metrics_document(
                "slam-sim-loop", slam_claims(summary, association="known"), dict(summary)
            ),
        )
    ]
    if victoria_park is None:
        return tuple(runs)
    try:
        import gtsam  # noqa: F401
    except ImportError:
        return tuple(runs)
    vp = read_log(victoria_park)
    reference, _ = gtsam_optimum(vp, victoria_park)
    vp_result = run_fastslam(vp, np.random.default_rng(seed), params=params, n_snapshots=0)
    ate = absolute_trajectory_error(vp_result.trajectory[:, :2], reference)
    odometry_ate = absolute_trajectory_error(vp_result.dead_reckoning[:, :2], reference)
    vp_claims = (
        Claim(
            metric="ate_vs_gtsam_m",
            op="<=",
            value=5.0,
            source="firefleet's bound: within 5 m of GTSAM's batch optimum over the 4 km drive "
            "(the default options, no tuning)",
        ),
    )
    vp_metrics: dict[str, float | list[float]] = {
        "ate_vs_gtsam_m": ate,
        "odometry_ate_vs_gtsam_m": odometry_ate,
        "particles": float(params.n_particles),
        "seed": float(seed),
    }
    runs.append(
        ReportRun(
            name="slam-victoria-park",
            title="FastSLAM 2.0 on Victoria Park against GTSAM's batch optimum",
            reproduces="Section 2.7.3: particle-filter SLAM on real data",
            deliverable_says=says,
            command=f"firefleet slam {victoria_park.name} --seed {seed}",
            files={"slam.png": slam_figure_png(vp, vp_result, reference=reference)},
            figures=("slam.png",),
            document=metrics_document("slam-victoria-park", vp_claims, vp_metrics),
        )
    )
    return tuple(runs)
