"""Benchmark of mapping and localisation on the grid (issue 14): grid SLAM against real
time, MCL's cost per scan.

1. Grid SLAM (:mod:`firefleet.estimation.grid`, 30 particles) on the built-in office
   (20 m x 10 m at 0.05 m) from a 90-beam 360-degree lidar (10 m, 1 cm noise) at 10 Hz
   and odometry with a 2 % scale error, a 3 % turn error and white noise, along a 60 s
   drive through two rooms and the corridor: the wall time of the whole run (best of
   2), hence the factor over real time (floor: >= 1, issue 14), and beside it the
   position RMS and map agreement of SLAM and of odometry alone.
2. MCL's cost per scan update (30 of the 90 beams): a global-localisation update
   (10,000 particles) and a tracking update (the KLD-sampled cloud once converged),
   from the lidar and from an 8-beam ultrasonic ring (4 m).

The ranges come from an exact grid ray caster written for the tests
(``tests/estimation/grid_world.py``) until ``firefleet.sim.ranging`` lands; only the
estimators are timed.

Peer: PythonRobotics has no grid SLAM (its SLAM folder holds EKF SLAM, FastSLAM 1.0 and
2.0 on point landmarks, graph SLAM and ICP). Python RBPF ports exist (e.g.
toolbuddy/2D-Grid-SLAM, Sollimann/Occupancy-Grid-FastSLAM), but none on the same input
format with a stated scan rate and particle count; they were not measured here, so the
numbers are absolute.
"""

from __future__ import annotations

import os
import sys

if __name__ == "__main__":  # one BLAS thread, set before numpy loads (as bench/run.py)
    for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

import _harness as h
from firefleet.estimation.grid import (
    GridMclParams,
    GridSlamParams,
    LikelihoodField,
    MclState,
    Scanner,
    likelihood_field,
    map_agreement_pct,
    mapping_step,
    mcl_global,
    mcl_step,
    mcl_tracking,
    occupancy_probability,
    slam_estimate,
    slam_init,
    slam_map,
    slam_step,
)
from firefleet.world import load_map

REPO = Path(__file__).resolve().parents[1]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))
from tests.estimation.grid_world import cast, drive, odometry  # noqa: E402

RATE_HZ = 10.0
DURATION_S = 60.0
OFFICE_PATH = np.array(
    [[2.5, 2.0], [2.5, 5.0], [12.5, 5.0], [12.5, 7.5], [12.5, 5.0], [17.5, 5.0], [17.5, 2.0]]
)
"""Room 1 (south-west), the corridor, a north room, the corridor, room 4 (south-east)."""


def _rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((a[:, :2] - b[:, :2]) ** 2, axis=1))))


def bench_slam(console: Console) -> dict[str, Any]:
    """Grid SLAM on the office at 10 Hz: wall time, x real time, RMS and agreement."""
    grid = load_map("office")
    scanner = Scanner.ring(90, 360.0, 10.0)
    prm = GridSlamParams(n_particles=30)
    rng = np.random.default_rng(0)
    truth = drive(DURATION_S, rate_hz=RATE_HZ, waypoints=OFFICE_PATH)
    delta, dead = odometry(truth, rng)
    ranges = cast(grid, truth, scanner.bearings_rad, 10.0, noise_m=0.01, rng=rng)
    out: dict[str, Any] = {}

    def once() -> None:
        r = np.random.default_rng(1)
        state = slam_init(grid, truth[0], prm)
        est = [truth[0]]
        for k in range(1, len(truth)):
            state = slam_step(state, delta[k - 1], ranges[k], grid, scanner, prm, r)
            est.append(slam_estimate(state))
        out["est"], out["state"] = np.array(est), state

    timing = h.best_of(once, 2, warmup=0)
    wall = timing.best_s
    dead_map = np.zeros((1, *grid.shape), np.float32)
    for k in range(len(truth)):
        dead_map = mapping_step(dead_map, dead[k : k + 1], ranges[k : k + 1], grid, scanner)
    res = {
        "particles": prm.n_particles,
        "scans": len(truth) - 1,
        "duration_s": DURATION_S,
        "wall_time_s": wall,
        "ms_per_scan": 1e3 * wall / (len(truth) - 1),
        "x_real_time": DURATION_S / wall,
        "slam_rms_m": _rms(out["est"], truth),
        "odometry_rms_m": _rms(dead, truth),
        "slam_map_agreement_pct": map_agreement_pct(
            occupancy_probability(slam_map(out["state"])), grid
        ),
        "odometry_map_agreement_pct": map_agreement_pct(occupancy_probability(dead_map[0]), grid),
        "maps_mb": out["state"].log_odds.nbytes / 1e6,
        "resamplings": out["state"].resamplings,
    }
    table = Table(title="1. Grid SLAM, office 20 m x 10 m at 0.05 m, 30 particles, 10 Hz lidar")
    for col in (
        "scans",
        "ms/scan",
        "x real time",
        "RMS SLAM / odometry (m)",
        "map agreement SLAM / odometry (%)",
        "maps (MB)",
    ):
        table.add_column(col, justify="right")
    table.add_row(
        str(res["scans"]),
        f"{res['ms_per_scan']:.1f}",
        f"{res['x_real_time']:.1f}",
        f"{res['slam_rms_m']:.3f} / {res['odometry_rms_m']:.3f}",
        f"{res['slam_map_agreement_pct']:.1f} / {res['odometry_map_agreement_pct']:.1f}",
        f"{res['maps_mb']:.1f}",
    )
    console.print(table)
    return res


def _update(
    state: MclState,
    delta: np.ndarray,
    z: np.ndarray,
    fld: LikelihoodField,
    scanner: Scanner,
    prm: GridMclParams,
) -> MclState:
    """One MCL update (the same random draws each call)."""
    return mcl_step(state, delta, z, fld, scanner, prm, np.random.default_rng(0))


def bench_mcl(console: Console) -> dict[str, Any]:
    """MCL's cost per scan update: global (10,000 particles) and tracking (KLD)."""
    grid = load_map("office")
    fld = likelihood_field(grid)
    truth = drive(20.0, rate_hz=RATE_HZ, waypoints=OFFICE_PATH)
    rng = np.random.default_rng(2)
    delta, _ = odometry(truth, rng)
    rows: dict[str, Any] = {}
    for name, scanner in (
        ("lidar", Scanner.ring(90, 360.0, 10.0)),
        ("ultrasonic", Scanner.ring(8, 360.0, 4.0)),
    ):
        z = cast(grid, truth, scanner.bearings_rad, scanner.max_range_m, 0.01, rng)
        prm = GridMclParams()
        glob = mcl_global(fld, prm, np.random.default_rng(0))
        t_global = h.best_of(partial(_update, glob, delta[0], z[1], fld, scanner, prm), 5)
        track = mcl_tracking(truth[0], prm, np.random.default_rng(0))
        r = np.random.default_rng(0)
        for k in range(1, 50):  # let KLD shrink the cloud
            track = mcl_step(track, delta[k - 1], z[k], fld, scanner, prm, r)
        t_track = h.best_of(partial(_update, track, delta[50], z[51], fld, scanner, prm), 20)
        rows[name] = {
            "beams_used": min(prm.max_beams, scanner.bearings_rad.size),
            "global_particles": prm.n_particles,
            "global_ms": 1e3 * t_global.best_s,
            "tracking_particles": int(track.particles.shape[0]),
            "tracking_ms": 1e3 * t_track.best_s,
        }
    table = Table(title="2. MCL: cost of one scan update (office, 0.05 m)")
    for col in ("sensor", "beams used", "global: particles", "ms", "tracking: particles", "ms"):
        table.add_column(col, justify="right")
    for name, r in rows.items():
        table.add_row(
            name,
            str(r["beams_used"]),
            f"{r['global_particles']:,}",
            f"{r['global_ms']:.2f}",
            f"{r['tracking_particles']:,}",
            f"{r['tracking_ms']:.3f}",
        )
    console.print(table)
    return rows


def run(console: Console) -> h.TopicResult:
    """Measure, print, and return the rows and the floor."""
    slam = bench_slam(console)
    mcl = bench_mcl(console)
    rows = [
        h.Row(
            "gridslam.office.p30.x_real_time",
            slam["x_real_time"],
            "x real time",
            label="grid SLAM, office, 30 particles, 10 Hz 90-beam lidar: x real time",
        ),
        h.Row(
            "gridslam.office.p30.maps_mb",
            slam["maps_mb"],
            "MB",
            higher_is_better=False,
            kind="memory",
            label="grid SLAM: the particles' maps",
        ),
    ]
    for name, r in mcl.items():
        rows.append(
            h.Row(
                f"gridslam.mcl.{name}.global_ms",
                r["global_ms"],
                "ms",
                higher_is_better=False,
                label=f"MCL {name}: one update, {r['global_particles']:,} particles",
            )
        )
        rows.append(
            h.Row(
                f"gridslam.mcl.{name}.tracking_ms",
                r["tracking_ms"],
                "ms",
                higher_is_better=False,
                label=f"MCL {name}: one tracking update (KLD cloud)",
            )
        )
    floors = (h.Floor.on(rows[0], ">=", 1.0),)
    peer = (
        "none measured: PythonRobotics has no grid SLAM; the Python RBPF ports found "
        "(toolbuddy/2D-Grid-SLAM, Sollimann/Occupancy-Grid-FastSLAM) take other inputs "
        "and were not run on this scene"
    )
    console.print(f"  peer: {peer}")
    return h.TopicResult(tuple(rows), floors, {"slam": slam, "mcl": mcl, "peer": peer})


if __name__ == "__main__":
    run(Console())
