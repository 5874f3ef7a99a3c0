"""Benchmark of FastSLAM: Victoria Park against GTSAM, PythonRobotics' FastSLAM 1.0 as a
peer, and steps per second by particle and landmark count.

``run(console)`` measures, prints rich tables with PASS/FAIL for issue 7's floors, and
returns every number as a JSON-able dict. Run directly: ``python bench/slam.py``.

1. Victoria Park (the whole 4 km set, 6,969 poses, 3,640 observations, given
   association): FastSLAM 2.0 with 100 particles, 20 seeds, estimating the odometry's
   systematic heading errors (``FastSlamParams.heading_drift_sigma`` and
   ``turn_scale_sigma``) with the log's sigmas x 2, beside white noise alone (sigmas x 4,
   the previous tuning); reference: GTSAM's batch optimum
   (iSAM2 over the poses in order, then Levenberg-Marquardt over all factors, from gtsam's
   ``load2D`` reading of the same file). Absolute trajectory error after rigid alignment.
   1b: the command a user runs, ``firefleet slam victoria_park.txt --seed S`` with no
   other option (300 particles), for S = 1, 2, 3: ATE and wall time of the command.
   The data is read from ``../shared/data`` beside the repository or ``$FIREFLEET_DATA``.
2. Peer: PythonRobotics ``SLAM/FastSLAM1/fast_slam1.py`` imported from a peer copy
   (a checkout or git directory named by ``$PYTHONROBOTICS``, never copied here) on
   its own scenario (8 RFID landmarks, its noise, 100 particles, 50 s at 0.1 s). The
   scenario is generated once with the peer's own ``observation`` function, then both
   filters run on the same inputs; firefleet's FastSLAM 1.0 gets the peer's motion noise
   ``R`` (on v and yaw rate) as the odometry covariance and its ``Q`` as observation noise.
3. Scaling: steps per second (one odometry step and two observations of known landmarks
   per step) for 100, 1,000 and 10,000 particles with 10 and 100 landmarks, and the
   tracemalloc peak.
"""

from __future__ import annotations

import os
import sys

if __name__ == "__main__":
    for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

import importlib
import subprocess
import tempfile
import time
import tracemalloc
from dataclasses import replace
from pathlib import Path
from typing import Any, Literal

import numpy as np
from rich.console import Console
from rich.table import Table

from firefleet.estimation import reference
from firefleet.estimation.alignment import absolute_trajectory_error
from firefleet.estimation.fastslam import (
    FastSlamParams,
    fastslam_init,
    fastslam_step,
    run_fastslam,
    slam_claims,
    slam_summary,
)
from firefleet.estimation.logs import SlamLog, gtsam_text, read_log

REPO = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("FIREFLEET_DATA", REPO.parent / "shared" / "data"))
"""The shared data folder: ``../shared/data`` beside the repository, or ``$FIREFLEET_DATA``."""
VICTORIA = DATA / "slam" / "victoria_park.txt"
PEER_ENV = "PYTHONROBOTICS"
"""Environment variable naming a PythonRobotics checkout (or its bare git directory)."""
SEEDS = tuple(range(20))
FLOOR_ATE_M = 5.0
FLOOR_TIME_S = 60.0
FLOOR_SPEEDUP = 50.0


def verdict(ok: bool) -> str:
    """PASS/FAIL for rich."""
    return "[bold green]PASS[/]" if ok else "[bold red]FAIL[/]"


def gtsam_optimum(log: SlamLog, path: Path) -> tuple[np.ndarray, float, float]:
    """GTSAM's batch optimum of the log's poses (T, 2), its final error, and the time."""
    t0 = time.perf_counter()
    ref, error = reference.gtsam_optimum(log, path)
    return ref, error, time.perf_counter() - t0


_CALIBRATED = FastSlamParams(version=2)  # the defaults: calibrated, sigmas x 2
VP_CONFIGS: tuple[tuple[str, FastSlamParams], ...] = (
    ("calibrated, x2", _CALIBRATED),
    (
        "white noise, x4",
        replace(
            _CALIBRATED, odometry_noise_scale=4.0, heading_drift_sigma=0.0, turn_scale_sigma=0.0
        ),
    ),
    ("calibrated, x2", replace(_CALIBRATED, n_particles=300)),
)


DEFAULT_SEEDS = (1, 2, 3)


def bench_default_command(console: Console, ref: np.ndarray) -> dict[str, Any]:
    """``firefleet slam victoria_park.txt --seed S`` with no other option, S = 1, 2, 3.

    Each run is the command itself in a fresh process (its wall time includes start-up
    and numba's compiled-kernel cache); its ``trajectory.csv`` is compared with GTSAM's
    optimum ``ref`` (T, 2) by the ATE after rigid alignment.
    """
    runs: list[dict[str, Any]] = []
    code = "import sys; from firefleet.cli import main; sys.exit(main(sys.argv[1:]))"
    for seed in DEFAULT_SEEDS:
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "vp"
            args = [str(VICTORIA), "--seed", str(seed), "--out", str(out), "--no-plots"]
            t0 = time.perf_counter()
            proc = subprocess.run(
                [sys.executable, "-c", code, "slam", *args], capture_output=True, check=False
            )
            wall = time.perf_counter() - t0
            if proc.returncode != 0:
                raise RuntimeError(f"firefleet slam exited {proc.returncode}: {proc.stderr!r}")
            path = np.loadtxt(out / "trajectory.csv", delimiter=",", skiprows=1)[:, 1:3]
        runs.append(
            {"seed": seed, "ate_m": absolute_trajectory_error(path, ref), "wall_time_s": wall}
        )
    table = Table(title="1b. firefleet slam victoria_park.txt --seed S (default options)")
    for col in ("seed", "ATE vs GTSAM (m)", "wall time (s)"):
        table.add_column(col, justify="right")
    for r in runs:
        table.add_row(str(r["seed"]), f"{r['ate_m']:.2f}", f"{r['wall_time_s']:.1f}")
    console.print(table)
    return {
        "runs": runs,
        "median_ate_m": float(np.median([r["ate_m"] for r in runs])),
        "max_wall_time_s": max(r["wall_time_s"] for r in runs),
    }


def bench_victoria(console: Console) -> dict[str, Any]:
    """Whole Victoria Park set: ATE against GTSAM and run time, over SEEDS, two tunings."""
    if not VICTORIA.exists():
        console.print(f"  {VICTORIA} absent (set $FIREFLEET_DATA): Victoria Park skipped")
        return {"skipped": True}
    log = read_log(VICTORIA)
    console.print("  GTSAM reference (iSAM2 + Levenberg-Marquardt) ...")
    ref, err, gt_s = gtsam_optimum(log, VICTORIA)
    ate_odo = absolute_trajectory_error(log.dead_reckoning()[:, :2], ref)
    configs: list[dict[str, Any]] = []
    for name, prm in VP_CONFIGS:
        rows: list[dict[str, Any]] = []
        for seed in SEEDS:
            res = run_fastslam(log, np.random.default_rng(seed), params=prm)
            rows.append(
                {
                    "seed": seed,
                    "ate_m": absolute_trajectory_error(res.trajectory[:, :2], ref),
                    "filtered_ate_m": absolute_trajectory_error(res.filtered[:, :2], ref),
                    "run_time_s": res.run_time_s,
                    "calibration": None if res.calibration is None else res.calibration.tolist(),
                }
            )
        ate = np.array([r["ate_m"] for r in rows])
        times = [float(r["run_time_s"]) for r in rows]
        configs.append(
            {
                "name": name,
                "particles": prm.n_particles,
                "runs": rows,
                "median_ate_m": float(np.median(ate)),
                "p10_ate_m": float(np.percentile(ate, 10)),
                "p90_ate_m": float(np.percentile(ate, 90)),
                "max_ate_m": float(ate.max()),
                "share_within_floor": float(np.mean(ate <= FLOOR_ATE_M)),
                "max_run_time_s": max(times),
            }
        )
    table = Table(
        title=f"1. Victoria Park, whole set: FastSLAM 2.0 vs GTSAM, ATE (m), "
        f"seeds 0-{len(SEEDS) - 1}"
    )
    for col in ("odometry", "particles", "median", "10-90 %", "max", "<= 5 m", "time (s)"):
        table.add_column(col, justify="right", no_wrap=True)
    table.caption = (
        "calibrated: per-particle heading drift (prior 0.003 rad/m) and turn scale error "
        "(prior 0.05); x2, x4: factor on the log's odometry sigmas"
    )
    for c in configs:
        table.add_row(
            c["name"],
            str(c["particles"]),
            f"{c['median_ate_m']:.2f}",
            f"{c['p10_ate_m']:.1f}-{c['p90_ate_m']:.1f}",
            f"{c['max_ate_m']:.1f}",
            f"{100 * c['share_within_floor']:.0f} %",
            f"{c['max_run_time_s']:.2f}",
        )
    console.print(table)
    console.print(f"  odometry-only ATE {ate_odo:.1f} m; GTSAM final error {err:.1f}, {gt_s:.1f} s")
    default = bench_default_command(console, ref)
    return {
        "poses": log.n_poses,
        "observations": log.n_observations,
        "default_command": default,
        "configs": configs,
        "median_ate_m": configs[0]["median_ate_m"],
        "odometry_ate_m": ate_odo,
        "gtsam_error": err,
        "gtsam_time_s": gt_s,
        "max_run_time_s": configs[0]["max_run_time_s"],
    }


def _peer_path() -> Path | None:
    """The PythonRobotics checkout or git directory of ``$PYTHONROBOTICS``, if present."""
    value = os.environ.get(PEER_ENV)
    return Path(value) if value and Path(value).exists() else None


def _peer_module(peer: Path, tmp: Path) -> Any:
    """PythonRobotics' fast_slam1 module, extracted from ``peer`` into ``tmp``."""
    for rel in ("SLAM/FastSLAM1/fast_slam1.py", "utils/angle.py", "utils/__init__.py"):
        out = tmp / rel
        out.parent.mkdir(parents=True, exist_ok=True)
        if (peer / rel).exists():  # a checkout
            out.write_text((peer / rel).read_text())
            continue
        text = subprocess.run(  # a git directory (a mirror)
            ["git", f"--git-dir={peer}", "show", f"HEAD:{rel}"],
            capture_output=True,
            check=False,
            text=True,
        )
        out.write_text(text.stdout if text.returncode == 0 else "")
    sys.path[:0] = [str(tmp), str(tmp / "SLAM/FastSLAM1")]
    mod: Any = importlib.import_module("fast_slam1")
    mod.show_animation = False
    return mod


def bench_peer(console: Console) -> dict[str, Any]:
    """Both FastSLAM 1.0s on the peer's own scenario, same inputs, one run each."""
    peer = _peer_path()
    if peer is None:
        console.print(f"  PythonRobotics not found (set ${PEER_ENV}): peer comparison skipped")
        return {"skipped": True}
    with tempfile.TemporaryDirectory() as tmp:
        pr = _peer_module(peer, Path(tmp))
        rfid = np.array(
            [
                [10.0, -2.0],
                [15.0, 10.0],
                [15.0, 15.0],
                [10.0, 20.0],
                [3.0, 15.0],
                [-5.0, 20.0],
                [-5.0, 5.0],
                [-10.0, 15.0],
            ]
        )
        np.random.seed(0)  # noqa: NPY002 (the peer draws from numpy's global generator)
        x_true = np.zeros((3, 1))
        x_dr = np.zeros((3, 1))
        t = 0.0
        inputs, obs, truth = [], [], []
        while t <= pr.SIM_TIME:
            t += pr.DT
            u = pr.calc_input(t)
            x_true, z, x_dr, ud = pr.observation(x_true, x_dr, u, rfid)
            inputs.append(ud.copy())
            obs.append(z.copy())
            truth.append(x_true[:, 0].copy())
        truth_arr = np.array(truth)
        n = len(inputs)
        # peer
        particles = [pr.Particle(rfid.shape[0]) for _ in range(pr.N_PARTICLE)]
        est_peer = np.empty((n, 3))
        t0 = time.perf_counter()
        for k in range(n):
            particles = pr.fast_slam1(particles, inputs[k], obs[k])
            est_peer[k] = pr.calc_final_state(particles)[:, 0]
        peer_s = time.perf_counter() - t0
        # ours, the same inputs: odometry (v dt, 0, w dt), covariance from the peer's R
        dt = pr.DT
        r_cov = np.diag([pr.R[0, 0] * dt * dt, 1e-8, pr.R[1, 1] * dt * dt])
        prm = FastSlamParams(n_particles=pr.N_PARTICLE, version=1, resample_threshold=1 / 1.5)
        state = fastslam_init(prm.n_particles, landmark_ids=np.arange(rfid.shape[0]))
        rng = np.random.default_rng(0)
        est_ours = np.empty((n, 3))
        # compile (or load from numba's cache) the kernels outside the timed loop
        warm = fastslam_init(2, landmark_ids=np.arange(1))
        fastslam_step(
            warm, np.zeros(3), r_cov, np.ones((1, 2)), pr.Q[None], np.zeros(1, dtype=np.int64),
            np.random.default_rng(0), params=FastSlamParams(n_particles=2),
        )  # fmt: skip
        t0 = time.perf_counter()
        for k in range(n):
            v, w = inputs[k][:, 0]
            z = obs[k]
            zz = np.ascontiguousarray(z[:2].T)
            fastslam_step(
                state,
                np.array([v * dt, 0.0, w * dt]),
                r_cov,
                zz,
                np.tile(pr.Q, (zz.shape[0], 1, 1)),
                z[2].astype(np.int64),
                rng,
                params=prm,
            )
            wts = state.weights()
            est_ours[k, :2] = wts @ state.poses[:, :2]
        ours_s = time.perf_counter() - t0
    sys.path[:] = [p for p in sys.path if not p.startswith(tmp)]
    rms_peer = float(np.sqrt(np.mean(np.sum((est_peer[:, :2] - truth_arr[:, :2]) ** 2, axis=1))))
    rms_ours = float(np.sqrt(np.mean(np.sum((est_ours[:, :2] - truth_arr[:, :2]) ** 2, axis=1))))
    table = Table(title="2. PythonRobotics FastSLAM 1.0 scenario (100 particles, 50 s, 501 steps)")
    for col in ("filter", "position RMS (m)", "time (s)", "ms/step"):
        table.add_column(col, justify="right")
    table.add_row(
        "PythonRobotics fast_slam1", f"{rms_peer:.3f}", f"{peer_s:.2f}", f"{1e3 * peer_s / n:.2f}"
    )
    table.add_row(
        "firefleet FastSLAM 1.0", f"{rms_ours:.3f}", f"{ours_s:.3f}", f"{1e3 * ours_s / n:.3f}"
    )
    console.print(table)
    return {
        "steps": n,
        "peer_rms_m": rms_peer,
        "ours_rms_m": rms_ours,
        "peer_time_s": peer_s,
        "ours_time_s": ours_s,
        "speedup_per_step": peer_s / ours_s,
    }


def bench_scaling(console: Console) -> list[dict[str, Any]]:
    """Steps per second and tracemalloc peak by particles and landmarks."""
    rows = []
    for n_lm in (10, 100):
        for n_p in (100, 1_000, 10_000):
            rng = np.random.default_rng(0)
            lms = rng.uniform(-20, 20, (n_lm, 2))
            state = fastslam_init(n_p, landmark_ids=np.arange(n_lm))
            prm = FastSlamParams(n_particles=n_p, version=1)
            cov = np.diag([1e-4, 1e-4, 1e-4])
            zc = np.tile(np.diag([0.01, 1e-4]), (2, 1, 1))

            def step(
                k: int,
                state: Any = state,
                lms: np.ndarray = lms,
                n_lm: int = n_lm,
                prm: FastSlamParams = prm,
                rng: np.random.Generator = rng,
                cov: np.ndarray = cov,
                zc: np.ndarray = zc,
            ) -> None:
                ids = np.array([k % n_lm, (k * 7 + 3) % n_lm])
                p = state.poses[0]
                d = lms[ids] - p[:2]
                z = np.stack([np.hypot(d[:, 0], d[:, 1]), np.arctan2(d[:, 1], d[:, 0]) - p[2]], 1)
                fastslam_step(state, np.array([0.1, 0.0, 0.01]), cov, z, zc, ids, rng, params=prm)

            for k in range(2 * n_lm):  # every landmark initialised before timing
                step(k)
            steps = 200 if n_p < 10_000 else 30
            t0 = time.perf_counter()
            for k in range(steps):
                step(k)
            sec = time.perf_counter() - t0
            tracemalloc.start()
            step(0)
            _, peak = tracemalloc.get_traced_memory()
            tracemalloc.stop()
            rows.append(
                {
                    "particles": n_p,
                    "landmarks": n_lm,
                    "steps_per_s": steps / sec,
                    "step_peak_mb": peak / 1e6,
                    "state_mb": (
                        state.mu.nbytes
                        + state.sigma.nbytes
                        + state.active.nbytes
                        + state.evidence.nbytes
                        + state.poses.nbytes
                    )
                    / 1e6,
                }
            )
    table = Table(title="3. FastSLAM 1.0 steps per second (2 observations per step)")
    for col in ("particles", "landmarks", "steps/s", "state (MB)", "step peak (MB)"):
        table.add_column(col, justify="right")
    for r in rows:
        table.add_row(
            f"{r['particles']:,}",
            str(r["landmarks"]),
            f"{r['steps_per_s']:,.0f}",
            f"{r['state_mb']:.1f}",
            f"{r['step_peak_mb']:.1f}",
        )
    console.print(table)
    return rows


def sim_optimum_rms(log: SlamLog) -> float:
    """Position RMS against the truth of GTSAM's batch optimum of a simulated log."""
    import gtsam

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "log.txt"
        path.write_text(gtsam_text(log))
        graph, initial = gtsam.load2D(str(path), noiseFormat=gtsam.NoiseFormat.NoiseFormatCOV)
    graph.add(
        gtsam.PriorFactorPose2(0, gtsam.Pose2(), gtsam.noiseModel.Diagonal.Sigmas([1e-4] * 3))
    )
    best = gtsam.LevenbergMarquardtOptimizer(graph, initial, gtsam.LevenbergMarquardtParams())
    est = best.optimize()
    xy = np.array([[est.atPose2(int(i)).x(), est.atPose2(int(i)).y()] for i in log.pose_ids])
    assert log.truth_pose is not None
    return float(np.sqrt(np.mean(np.sum((xy - log.truth_pose[:, :2]) ** 2, axis=1))))


def bench_simulation(console: Console) -> dict[str, Any]:
    """The simulated 100 m loop's claims over 4 drives x 3 filter seeds, per filter."""
    from firefleet.sim.world import simulate_drive

    logs = {d: simulate_drive(np.random.default_rng(d)).log for d in (1, 2, 3, 4)}
    optimum = {d: sim_optimum_rms(log) for d, log in logs.items()}
    rows: list[dict[str, Any]] = []
    versions: tuple[Literal[1, 2], ...] = (1, 2)
    associations: tuple[Literal["known", "unknown"], ...] = ("known", "unknown")
    for version in versions:
        for association in associations:
            prm = FastSlamParams(version=version, association=association)
            runs = []
            for drive, log in logs.items():
                for seed in (0, 1, 2):
                    doc = slam_summary(
                        log, run_fastslam(log, np.random.default_rng(seed), params=prm)
                    )
                    claims = slam_claims(doc, association=association)
                    runs.append(
                        {
                            "drive": drive,
                            "seed": seed,
                            "position_rms_m": doc["position_rms_m"],
                            "landmark_rms_m": doc["landmark_rms_m"],
                            "odometry_position_rms_m": doc["odometry_position_rms_m"],
                            "duplicate_landmarks": doc["duplicate_landmarks"],
                            "all_claims": all(c.holds(doc[c.metric]) for c in claims),
                        }
                    )
            rows.append({"version": version, "association": association, "runs": runs})
    table = Table(title="4. Simulated 100 m loop, 100 particles: 4 drives x 3 seeds")
    for col in ("filter", "position RMS (m)", "landmark RMS (m)", "duplicates", "all claims"):
        table.add_column(col, justify="right", no_wrap=True)
    for r in rows:
        pos = [x["position_rms_m"] for x in r["runs"]]
        lm = [x["landmark_rms_m"] for x in r["runs"]]
        dup = sum(x["duplicate_landmarks"] > 0 for x in r["runs"])
        ok = sum(x["all_claims"] for x in r["runs"])
        table.add_row(
            f"{r['version']}.0 {r['association']}",
            f"{np.median(pos):.2f} ({max(pos):.2f})",
            f"{np.median(lm):.2f} ({max(lm):.2f})",
            f"{dup} of {len(r['runs'])}" if r["association"] == "unknown" else "-",
            f"{ok}/{len(r['runs'])}",
        )
    table.caption = "median (worst); dead reckoning: 3.7-5.2 m"
    console.print(table)
    console.print(
        "  GTSAM's batch optimum of the same logs, position RMS: "
        + ", ".join(f"drive {d} {v:.3f} m" for d, v in optimum.items())
    )
    return {"gtsam_optimum_position_rms_m": optimum, "filters": rows}


def run(console: Console) -> dict[str, Any]:
    """Every measurement of issue 7, with its floors."""
    console.print("[bold]slam 1. Victoria Park[/]")
    vp = bench_victoria(console)
    console.print("[bold]slam 2. PythonRobotics peer[/]")
    peer = bench_peer(console)
    console.print("[bold]slam 3. scaling[/]")
    scaling = bench_scaling(console)
    console.print("[bold]slam 4. simulated loop[/]")
    simulation = bench_simulation(console)
    floors = []
    if not vp.get("skipped"):
        floors.append(
            (
                f"Victoria Park median ATE vs GTSAM ({len(SEEDS)} seeds)",
                f"<= {FLOOR_ATE_M} m",
                f"{vp['median_ate_m']:.2f} m",
                vp["median_ate_m"] <= FLOOR_ATE_M,
            )
        )
        floors.append(
            (
                "Victoria Park whole set, 100 particles, one core",
                f"< {FLOOR_TIME_S} s",
                f"{vp['max_run_time_s']:.2f} s",
                vp["max_run_time_s"] < FLOOR_TIME_S,
            )
        )
        dflt = vp["default_command"]
        floors.append(
            (
                "Victoria Park, default options, median ATE (seeds 1-3)",
                f"<= {FLOOR_ATE_M} m",
                f"{dflt['median_ate_m']:.2f} m",
                dflt["median_ate_m"] <= FLOOR_ATE_M,
            )
        )
        floors.append(
            (
                "Victoria Park, default options, each command",
                f"< {FLOOR_TIME_S} s",
                f"{dflt['max_wall_time_s']:.1f} s",
                dflt["max_wall_time_s"] < FLOOR_TIME_S,
            )
        )
    if not peer.get("skipped"):
        floors.append(
            (
                "error vs PythonRobotics (one run)",
                "no worse",
                f"{peer['ours_rms_m']:.3f} vs {peer['peer_rms_m']:.3f} m",
                peer["ours_rms_m"] <= peer["peer_rms_m"],
            )
        )
        floors.append(
            (
                "speed per step vs PythonRobotics",
                f">= {FLOOR_SPEEDUP:g}x",
                f"{peer['speedup_per_step']:.0f}x",
                peer["speedup_per_step"] >= FLOOR_SPEEDUP,
            )
        )
    table = Table(title="slam floors")
    for col in ("floor", "required", "measured", "verdict"):
        table.add_column(col)
    for name, req, meas, ok in floors:
        table.add_row(name, req, meas, verdict(ok))
    console.print(table)
    return {
        "victoria_park": vp,
        "peer": peer,
        "scaling": scaling,
        "simulation": simulation,
        "floors": [
            {"name": f[0], "required": f[1], "measured": f[2], "pass": f[3]} for f in floors
        ],
    }


if __name__ == "__main__":
    run(Console())
