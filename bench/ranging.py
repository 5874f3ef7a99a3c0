"""Benchmark of the range sensors in the world loop (issue 14), against IR-SIM.

1. **10 robots, 90-beam lidar, a 50 m x 50 m building at 0.05 m**: one world step of
   firefleet's staged loop (``run_staged``: the range-sensor stage, a constant wheel
   command, the wheel stack's PID, motors, kinematics and encoders) with every robot's
   360-degree lidar scanned every tick (rate 100 Hz = the loop's 1 / dt), against
   IR-SIM (``irsim``, headless: ``irsim.make(world, headless=True)``) on the same scene:
   the same walls, each one of IR-SIM's polygon obstacles, 10 differential-drive disc
   robots at the same poses, each with a 90-beam 360-degree ``lidar2d`` stepped every
   ``env.step``. Steps per second of each, timed in turn (best of the rounds), and
   their ratio. Floor: 10x IR-SIM.
2. **1,000 robots with an 8-beam ultrasonic ring on the built-in warehouse map**:
   simulated seconds per wall second of the staged loop with the ring read at 15 Hz
   (HC-SR04: a 60 ms cycle) and held between readings, the other robots as discs.
   The floor row: 8 beams (one ray per sensor, ``rays_per_cone=1``), >= 10x real
   time. Beside it the default cone of 5 rays per sensor (40 rays per robot), the ring
   read every tick (100 Hz), the loop without sensors, and one scan alone.

The building: a 50 m x 50 m floor of 5 x 5 rooms (10 m apart), 0.2 m outer walls,
0.15 m inner walls with a 1 m door in every wall between two rooms; every wall an
axis-aligned rectangle on the 0.05 m grid, rasterised to the occupancy grid by cell
centre and handed to IR-SIM as the same rectangle.

Run directly: ``python bench/ranging.py``.
"""

from __future__ import annotations

import os

if __name__ == "__main__":  # single-threaded BLAS, as bench/run.py sets it
    for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

import contextlib
import io
import logging
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray
from rich.console import Console
from rich.table import Table
from scipy import ndimage

from _harness import Floor, Row, TopicResult, best_of, best_of_interleaved
from firefleet.control.pid import PidParams
from firefleet.models import EncoderParams, MotorParams, RobotGeometry
from firefleet.sim._ranging_cast import cast_team
from firefleet.sim.drive import discretise_drive, drive_init
from firefleet.sim.loop import Stages, StaticWorld, WheelCommand, run_staged
from firefleet.sim.ranging import (
    LidarParams,
    RangeSensors,
    UltrasonicParams,
    lidar_scan,
    ultrasonic_scan,
)
from firefleet.world import OccupancyGrid, load_map

FloatArray = NDArray[np.float64]

SIZE_M, RES_M, ROOMS = 50.0, 0.05, 5
RADIUS_M = 0.2
DT_S = 0.01
N_LIDAR = 10
LIDAR_STEPS = 200
"""Ticks per timed run of the 10-robot lidar scene (each side)."""
ROUNDS = 3
N_SONAR = 1_000
SONAR_S = 2.0
"""Simulated seconds per timed run of the 1,000-robot ultrasonic scene."""
FLOOR_RATIO = 10.0
FLOOR_X_REAL_TIME = 10.0
IRSIM_MEASURED_HERE = 259.0
"""IR-SIM's steps per second on this scene as issue 14 quotes it."""


# ---------------------------------------------------------------------------- scene


def building_walls() -> FloatArray:
    """Wall rectangles ``x0, y0, x1, y1`` [m] of the 50 m x 50 m building, (M, 4)."""
    room = SIZE_M / ROOMS
    outer, inner, door = 0.2, 0.15, 1.0
    walls = [
        [0.0, 0.0, SIZE_M, outer],
        [0.0, SIZE_M - outer, SIZE_M, SIZE_M],
        [0.0, 0.0, outer, SIZE_M],
        [SIZE_M - outer, 0.0, SIZE_M, SIZE_M],
    ]
    for k in range(1, ROOMS):
        c = k * room
        for q in range(ROOMS):  # the wall segment between two rooms, a door in its middle
            a, b = q * room, (q + 1) * room
            mid = 0.5 * (a + b)
            for lo, hi in ((a, mid - door / 2), (mid + door / 2, b)):
                walls.append([c - inner / 2, lo, c + inner / 2, hi])  # vertical
                walls.append([lo, c - inner / 2, hi, c + inner / 2])  # horizontal
    return np.round(np.array(walls) / RES_M) * RES_M


def rasterise(walls: FloatArray) -> OccupancyGrid:
    """The walls on a 0.05 m grid: a cell is occupied when its centre lies in a wall."""
    n = round(SIZE_M / RES_M)
    empty = OccupancyGrid(np.zeros((n, n), bool), np.ones((n, n), bool), resolution_m=RES_M)
    xy = empty.center_of(np.stack(np.meshgrid(np.arange(n), np.arange(n), indexing="ij"), -1))
    occ = np.zeros((n, n), bool)
    for x0, y0, x1, y1 in walls:
        occ |= (xy[..., 0] >= x0) & (xy[..., 0] < x1) & (xy[..., 1] >= y0) & (xy[..., 1] < y1)
    return OccupancyGrid(occ, ~occ, resolution_m=RES_M, name="building 50 m")


def place_robots(grid: OccupancyGrid, n: int, seed: int) -> FloatArray:
    """``n`` poses on free cells at least ``2 RADIUS_M`` from a wall and 2.5 radii apart."""
    rng = np.random.default_rng(seed)
    clearance = ndimage.distance_transform_edt(~grid.occupied) * grid.resolution_m
    cells = np.argwhere(clearance > 2 * RADIUS_M)
    xy = grid.center_of(cells[rng.permutation(len(cells))])
    chosen: list[FloatArray] = []
    for p in xy:
        if not chosen or np.min(np.hypot(*(np.array(chosen) - p).T)) > 2.5 * RADIUS_M:
            chosen.append(p)
            if len(chosen) == n:
                break
    if len(chosen) < n:
        raise RuntimeError(f"only {len(chosen)} robots fit on {grid.name}")
    heading = rng.uniform(-np.pi, np.pi, n)
    return np.column_stack([np.array(chosen), heading])


# ---------------------------------------------------------------------- firefleet


def firefleet_run(
    grid: OccupancyGrid, poses: FloatArray, sensors: dict[str, Any], n_steps: int
) -> Callable[[], object]:
    """A staged run of ``n_steps`` ticks with the range sensors ``sensors``, as a thunk."""
    stack = discretise_drive(RobotGeometry(), MotorParams(), PidParams(), EncoderParams(), DT_S)
    n = len(poses)
    ref = np.column_stack([np.full(n, 6.0), np.full(n, 4.0)])  # a gentle left turn
    command = WheelCommand(reference_rad_s=ref)

    def decide(state: None, inputs: Any, params: None, dt_s: float) -> tuple[None, WheelCommand]:
        return state, command

    rec = np.array([n_steps])

    def run() -> object:
        stage = RangeSensors(grid, RADIUS_M, dt_s=DT_S, rng=np.random.default_rng(1), **sensors)
        start = drive_init(poses, np.zeros((n, 2)), stack)
        return run_staged(
            start,
            stack,
            Stages(world=StaticWorld(), sensors=stage),
            decide,
            None,
            None,
            rec,
            n_steps,
        )

    return run


# ------------------------------------------------------------------------- IR-SIM


def irsim_world(walls: FloatArray, poses: FloatArray, folder: Path) -> Path:
    """IR-SIM's world file for the same scene (walls as polygons, robots with lidar)."""
    world = {
        "world": {
            "height": SIZE_M,
            "width": SIZE_M,
            "step_time": DT_S,
            "sample_time": DT_S,
            "offset": [0, 0],
            "collision_mode": "unobstructed",
        },
        "robot": [
            {
                "number": len(poses),
                "distribution": {"name": "manual"},
                "kinematics": {"name": "diff"},
                "shape": {"name": "circle", "radius": RADIUS_M},
                "state": poses.tolist(),
                "goal": np.add(poses, [1.0, 0.0, 0.0]).tolist(),
                "sensors": [
                    {
                        "name": "lidar2d",
                        "range_min": 0.0,
                        "range_max": 10.0,
                        "angle_range": 2 * np.pi,
                        "number": 90,
                        "noise": False,
                    }
                ],
            }
        ],
        "obstacle": [
            {
                "number": len(walls),
                "distribution": {"name": "manual"},
                "shape": [
                    {
                        "name": "polygon",
                        "vertices": [[x0, y0], [x1, y0], [x1, y1], [x0, y1]],
                    }
                    for x0, y0, x1, y1 in walls.tolist()
                ],
                "state": [[0.0, 0.0, 0.0]] * len(walls),
            }
        ],
    }
    path = folder / "building.yaml"
    path.write_text(yaml.safe_dump(world), encoding="utf-8")
    return path


def irsim_run(world: Path, n_robots: int, n_steps: int) -> tuple[Callable[[], object], Any]:
    """A thunk stepping IR-SIM's headless environment ``n_steps`` times, and the env."""
    import irsim

    with contextlib.redirect_stdout(io.StringIO()):
        env = irsim.make(str(world), headless=True, log_level="ERROR")
    action = [np.array([[0.25], [0.05]])] * n_robots  # v [m/s], omega [rad/s]
    ids = list(range(n_robots))

    def run() -> object:
        for _ in range(n_steps):
            env.step(action, action_id=ids)
        return None

    return run, env


def scan_agreement(grid: OccupancyGrid, env: Any) -> dict[str, float]:
    """IR-SIM's current scans against firefleet's casts at the same poses and angles."""
    diffs, both, only_one = [], 0, 0
    poses = np.array([r.state.ravel()[:3] for r in env.robot_list])
    for a, robot in enumerate(env.robot_list):
        lidar = robot.sensors[0]
        ours, _ = cast_team(
            grid.occupied,
            grid.resolution_m,
            grid.origin_m,
            np.roll(poses, -a, axis=0),
            np.asarray(lidar.angle_list),
            10.0,
            RADIUS_M,
        )
        theirs = np.where(lidar.valid, lidar.range_data, np.inf)
        hit = np.isfinite(ours[0]) & np.isfinite(theirs)
        both += int(hit.sum())
        only_one += int((np.isfinite(ours[0]) != np.isfinite(theirs)).sum())
        diffs.extend(np.abs(ours[0][hit] - theirs[hit]).tolist())
    return {
        "beams_both_hit": both,
        "beams_one_hit": only_one,
        "max_abs_difference_m": max(diffs) if diffs else float("nan"),
        "median_abs_difference_m": float(np.median(diffs)) if diffs else float("nan"),
    }


# ------------------------------------------------------------------------- cases


def bench_lidar(console: Console) -> dict[str, Any]:
    walls = building_walls()
    grid = rasterise(walls)
    poses = place_robots(grid, N_LIDAR, seed=3)
    lidar = LidarParams(beams=90, fov_deg=360.0, max_range_m=10.0, noise_m=0.0, rate_hz=1.0 / DT_S)
    ours = firefleet_run(grid, poses, {"lidar": lidar}, LIDAR_STEPS)
    out: dict[str, Any] = {"walls": len(walls), "grid": list(grid.shape), "steps": LIDAR_STEPS}
    with tempfile.TemporaryDirectory() as tmp:
        world = irsim_world(walls, poses, Path(tmp))
        theirs, env = irsim_run(world, N_LIDAR, LIDAR_STEPS)
        # the same scene: IR-SIM's first scan beside ours, at its poses and beam angles
        r0 = lidar_scan(grid, poses, lidar, robot_radius_m=RADIUS_M, rng=np.random.default_rng(0))
        out["irsim_agreement"] = scan_agreement(grid, env)
        times = best_of_interleaved({"firefleet": ours, "irsim": theirs}, ROUNDS)
        del env
    ours_sps = LIDAR_STEPS / times["firefleet"].best_s
    theirs_sps = LIDAR_STEPS / times["irsim"].best_s
    scan = best_of(
        lambda: lidar_scan(
            grid, poses, lidar, robot_radius_m=RADIUS_M, rng=np.random.default_rng(0)
        ),
        20,
    )
    out.update(
        {
            "firefleet_steps_per_s": ours_sps,
            "irsim_steps_per_s": theirs_sps,
            "ratio": ours_sps / theirs_sps,
            "lidar_scan_10_robots_s": scan.best_s,
            "mean_finite_range_m": float(np.mean(r0[np.isfinite(r0)])),
            "share_of_beams_with_a_return": float(np.isfinite(r0).mean()),
            "times": {k: v.to_dict() for k, v in times.items()},
        }
    )
    table = Table(title="10 robots, 90-beam lidar each tick, 50 m x 50 m building at 0.05 m")
    for col in ("", "steps/s", "vs IR-SIM"):
        table.add_column(col, justify="right")
    table.add_row(
        "firefleet (staged loop + lidar)", f"{ours_sps:,.0f}", f"{ours_sps / theirs_sps:.1f}x"
    )
    table.add_row("IR-SIM (headless env.step)", f"{theirs_sps:,.0f}", "1x")
    table.add_row("firefleet lidar scan alone", f"{1 / scan.best_s:,.0f}", "")
    console.print(table)
    agree = out["irsim_agreement"]
    console.print(
        f"  same scene: {agree['beams_both_hit']} beams hit in both, {agree['beams_one_hit']} in "
        f"one only; |firefleet - IR-SIM| median {agree['median_abs_difference_m']:.1e} m, "
        f"max {agree['max_abs_difference_m']:.1e} m (IR-SIM's discs are polygons)"
    )
    return out


def bench_sonar(console: Console) -> dict[str, Any]:
    grid = load_map("warehouse")
    poses = place_robots(grid, N_SONAR, seed=4)
    n_steps = round(SONAR_S / DT_S)
    out: dict[str, Any] = {"map": grid.name, "grid": list(grid.shape), "robots": N_SONAR}
    table = Table(title=f"{N_SONAR:,} robots, 8-sensor ultrasonic ring, warehouse map")
    for col in ("ring rate", "rays per robot", "x real time"):
        table.add_column(col, justify="right")
    for rate, rays in ((15.0, 1), (15.0, 5), (1.0 / DT_S, 1)):
        sonar = UltrasonicParams(rate_hz=rate, rays_per_cone=rays)
        timing = best_of(firefleet_run(grid, poses, {"ultrasonic": sonar}, n_steps), 2)
        x = SONAR_S / timing.best_s
        out[f"x_real_time_at_{rate:.0f}_hz_{rays}_rays_per_cone"] = x
        table.add_row(f"{rate:.0f} Hz", f"{8 * rays}", f"{x:.1f}")
    sonar = UltrasonicParams()
    scan = best_of(
        lambda: ultrasonic_scan(
            grid, poses, sonar, robot_radius_m=RADIUS_M, rng=np.random.default_rng(0)
        ),
        5,
    )
    out["ultrasonic_scan_1000_robots_s"] = scan.best_s
    bare = best_of(firefleet_run(grid, poses, {}, n_steps), 2)
    out["x_real_time_without_sensors"] = SONAR_S / bare.best_s
    table.add_row("no sensors", "0", f"{SONAR_S / bare.best_s:.1f}")
    console.print(table)
    console.print(
        f"  one ultrasonic scan of {N_SONAR:,} robots, 5 rays per cone: {1e3 * scan.best_s:.1f} ms"
    )
    return out


def run(console: Console) -> TopicResult:
    """Measure both cases; rows, floors and every number."""
    logging.getLogger("irsim").setLevel(logging.ERROR)
    lid = bench_lidar(console)
    son = bench_sonar(console)
    rows = (
        Row(
            "ranging.lidar10.steps_per_s",
            lid["firefleet_steps_per_s"],
            "steps/s",
            label="10 robots, 90-beam lidar, 50 m building: world steps per second",
        ),
        Row(
            "ranging.lidar10.irsim_steps_per_s",
            lid["irsim_steps_per_s"],
            "steps/s",
            label="IR-SIM, same scene: steps per second",
        ),
        Row(
            "ranging.lidar10.speedup_vs_irsim",
            lid["ratio"],
            "x",
            label="10 robots, 90-beam lidar: firefleet / IR-SIM",
        ),
        Row(
            "ranging.sonar1000.x_real_time",
            son["x_real_time_at_15_hz_1_rays_per_cone"],
            "x real time",
            label="1,000 robots, 8-beam ultrasonic ring at 15 Hz, warehouse: x real time",
        ),
        Row(
            "ranging.sonar1000_cone5.x_real_time",
            son["x_real_time_at_15_hz_5_rays_per_cone"],
            "x real time",
            label="1,000 robots, 8 cones of 5 rays at 15 Hz, warehouse: x real time",
        ),
    )
    floors = (
        Floor.on(rows[2], ">=", FLOOR_RATIO),
        Floor.on(rows[3], ">=", FLOOR_X_REAL_TIME),
    )
    return TopicResult(
        rows,
        floors,
        {"lidar": lid, "ultrasonic": son, "irsim_quoted_steps_per_s": IRSIM_MEASURED_HERE},
    )


if __name__ == "__main__":
    t0 = time.perf_counter()
    result = run(Console())
    for f in result.floors:
        print(f"{'PASS' if f.passed else 'FAIL'} {f.name}: {f.measured:.1f} {f.op} {f.bound}")
    print(f"took {time.perf_counter() - t0:.0f} s")
