"""Benchmark: the formation law at swarm scale (issue 4), against textbook NumPy.

For teams of N = 10, 100, 1,000 and 5,000 robots, uniformly at random in a square of
side 10 sqrt(N) m (constant density) about a fixed leader (alpha = 3 m, attraction
capped at 10 N as in the built-in scenarios):

1. Steps per second of one formation step: the force of the law (the deliverable's
   eqs. 6-8, and the regular law with its k-d-tree contact force) plus the point-mass step
   of eq. 5 (``mass_damper_step``), best of several timed runs.
2. Peak memory of one step: the tracemalloc peak (NumPy allocations) and the process's
   peak resident set size after the run.
3. Peer: the Coulomb sum of eqs. 7-8 written the textbook way, with NumPy broadcasting
   over an (N, N, 2) array of differences (what one writes without blocking). Its time
   and tracemalloc peak are measured on the same positions, and its forces compared with
   ours; ratios are ours / peer.

4. Converging runs (issue 13): whole simulated runs (``firefleet.simulate``) of teams of
   20, 200 and 1,000 point-mass robots with the regular law from seeded random starts
   (the built-in ``formation-regular-20`` and ``-200``, and :func:`team_scenario` at
   1,000: a 150 m circle, polygon side 0.94 m, attraction stiffness 18 N/m on the
   circle), and the deliverable's law at 200 (k_r scaled with the side squared):
   radius error, spacing error, smallest gap between bodies, whether the claims hold
   (radius error <= 1 % of alpha, spacing error <= 2 deg, no contact), steps per second
   of the whole run (metrics excluded) and the sub-steps the stiffness bound asked for.

Floors, printed PASS/FAIL: the N = 1,000 run converges (its claims hold) at >= 500
steps/s (issue 13); at N = 5,000 under 1 GiB (tracemalloc peak of a step, and the
process's peak RSS; issue 4). The per-step rows (1.) time the force at random positions
(not a run). ``run`` returns every number; the exit status is 0 whatever the floors say.
"""

from __future__ import annotations

import math
import os
import resource
import sys
import time
import tracemalloc
from collections.abc import Callable
from typing import Any

if __name__ == "__main__":  # single-threaded BLAS, as bench/run.py sets it
    for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

import numpy as np
from numpy.typing import NDArray
from rich.console import Console
from rich.table import Table

from firefleet import compute_metrics, load_scenario, simulate
from firefleet.control.formation import FormationParams, coulomb_repulsion, formation_force
from firefleet.models.mass_damper import MassDamperParams, mass_damper_step
from firefleet.scenarios.schema import Scenario, parse_scenario

FloatArray = NDArray[np.float64]

TEAM_SIZES = (10, 100, 1_000, 5_000)
STEPS = {10: 2_000, 100: 1_000, 1_000: 100, 5_000: 10}
"""Formation steps per timed run (about 0.1 to 1 s each)."""
REPEATS = 3
"""Timed runs per size and law (the best counts), after one untimed step."""
PEER_MAX_N = 5_000
"""Largest team the peer runs at (its (N, N, 2) arrays: 400 MB at 5,000)."""

FLOOR_N, FLOOR_STEPS_PER_S = 1_000, 500.0
MEMORY_N, FLOOR_BYTES = 5_000, 1 << 30
DT_S = 0.01
PARAMS = FormationParams(alpha_m=3.0, attraction_limit_n=10.0)  # as the scenarios
RUN_REPEATS = 2
"""Timed runs per converging scenario (the best counts)."""


def team_scenario(n: int, law: str = "regular", *, seed: int = 1) -> Scenario:
    """N point-mass robots from random starts onto a circle whose polygon side is ~0.94 m.

    The recipe of ``formation-regular-200``: alpha = 0.47 m / sin(pi / N) rounded up to
    the metre; attraction gain 9 / alpha^2 (stiffness 2 a alpha^2 = 18 N/m on the
    circle, as eq. 6 on the 3 m circle); starts in a square of half-width alpha / 2
    (40 m from N = 1,000 on); 60 s, shape metrics over the last 5 s. The deliverable's
    law gets ``k_r = 10 (0.94 m / 3.53 m)^2`` (3.53 m: the 5-gon's side on the 3 m
    circle of ``formation-5``).
    """
    alpha = float(np.ceil(0.47 / np.sin(np.pi / n)))
    command: dict[str, Any] = {
        "kind": "formation",
        "law": law,
        "alpha_m": alpha,
        "attraction_gain": 9.0 / alpha**2,
        "scatter_m": max(5.0, alpha / 2.0) if n < 1_000 else 40.0,
        "formed_by_s": 55.0,
    }
    claims: list[dict[str, Any]] = [
        {"metric": "radius_error_max_m", "op": "<=", "value": 0.01 * alpha},
        {"metric": "spacing_error_max_deg", "op": "<=", "value": 2.0},
        {"metric": "min_clearance_m", "op": ">", "value": 0.0},
    ]
    if law == "deliverable":
        # the deliverable's law: all robots on the circle, an irregular polygon, and no
        # contact force (robots may touch on the way)
        command["k_r"] = 10.0 * (0.94 / 3.53) ** 2
        claims = claims[:1]
    return parse_scenario(
        {
            "name": f"formation-{law}-{n}",
            "title": f"{n} robots, {law} law",
            "duration_s": 60.0,
            "seed": seed,
            "poses": [[0.0, 0.0, 0.0]] * n,
            "command": command,
            "claims": claims,
        }
    )


def run_converging(scenario: Scenario, repeats: int = RUN_REPEATS) -> dict[str, Any]:
    """Time whole runs of ``scenario`` (best of ``repeats``), and judge the last one.

    Both the wall time and this process's CPU time are measured: the run is single
    threaded (BLAS threads set to 1), so on an idle machine they agree, and on a shared
    one the CPU time is the run's own cost (the wall time also counts the neighbours).
    """
    best = best_cpu = math.inf
    result = None
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        result = simulate(scenario)
        best = min(best, time.perf_counter() - t0)
        best_cpu = min(best_cpu, time.process_time() - c0)
    assert result is not None
    metrics = compute_metrics(result)
    claims = {c.metric: c.holds(metrics[c.metric]) for c in scenario.claims}
    cmd = scenario.command
    return {
        "scenario": scenario.name,
        "n_robots": scenario.n_robots,
        "law": getattr(cmd, "law", ""),
        "alpha_m": getattr(cmd, "alpha_m", math.nan),
        "radius_error_max_m": metrics["radius_error_max_m"],
        "spacing_error_max_deg": metrics["spacing_error_max_deg"],
        "min_clearance_m": metrics["min_clearance_m"],
        "claims": claims,
        "claims_hold": all(claims.values()),
        "steps_per_s": scenario.n_steps / best,
        "steps_per_cpu_s": scenario.n_steps / best_cpu,
        "max_substeps": int(np.max(result.extra["substeps"])),
        "mean_substeps": float(np.mean(result.extra["substeps"])),
    }


MASS = MassDamperParams()


def team(n: int) -> FloatArray:
    """Point-mass states (N, 4) at random, constant density (10 m x 10 m per robot)."""
    side = 10.0 * np.sqrt(n)
    rng = np.random.default_rng(n)
    xy = rng.uniform(-side / 2, side / 2, (n, 2))
    return np.concatenate([xy, np.zeros((n, 2))], axis=1)


def step(state: FloatArray, law: str) -> FloatArray:
    """One formation step of the runner's point-mass loop."""
    force = formation_force(state[:, :2], np.zeros(2), PARAMS, law=law)  # type: ignore[arg-type]
    return mass_damper_step(state, force, DT_S, MASS)


def peer_coulomb(pos: FloatArray, k_r: float = 10.0) -> FloatArray:
    """Eqs. 7-8 by broadcasting: (N, N, 2) differences, (N, N) distances."""
    diff = pos[:, None, :] - pos[None, :, :]
    r2 = (diff * diff).sum(axis=2)
    np.fill_diagonal(r2, np.inf)
    out: FloatArray = k_r * (diff / (r2 * np.sqrt(r2))[:, :, None]).sum(axis=1)
    return out


def best_of(fn: Callable[[], object], repeats: int) -> float:
    """Best wall time [s] of ``repeats`` calls, after one untimed call."""
    fn()
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return float(best)


def traced_peak_bytes(fn: Callable[[], object]) -> int:
    """Peak of the memory tracemalloc sees (NumPy's allocations) during one call."""
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        fn()
        return int(tracemalloc.get_traced_memory()[1])
    finally:
        tracemalloc.stop()


def max_rss_bytes() -> int:
    """Peak resident set size of this process so far (Linux reports kB)."""
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(rss if sys.platform == "darwin" else rss * 1024)


def run_laws(n: int) -> dict[str, Any]:
    """Steps/s of both laws and the peak memory of one regular-law step, for N robots."""
    state0 = team(n)
    steps = STEPS[n]
    out: dict[str, Any] = {"n_robots": n, "steps_per_run": steps}
    for law in ("deliverable", "regular"):

        def run(law: str = law) -> None:
            s = state0
            for _ in range(steps):
                s = step(s, law)

        best = best_of(run, REPEATS)
        out[f"{law}_steps_per_s"] = steps / best
        out[f"{law}_robot_steps_per_s"] = n * steps / best
    out["step_traced_peak_bytes"] = traced_peak_bytes(lambda: step(state0, "regular"))
    out["max_rss_after_bytes"] = max_rss_bytes()
    return out


def run_peer(n: int) -> dict[str, Any]:
    """Time, memory and agreement of the broadcast Coulomb sum against ours."""
    pos = team(n)[:, :2]
    ours_s = best_of(lambda: coulomb_repulsion(pos), REPEATS)
    peer_s = best_of(lambda: peer_coulomb(pos), REPEATS)
    ours_peak = traced_peak_bytes(lambda: coulomb_repulsion(pos))
    peer_peak = traced_peak_bytes(lambda: peer_coulomb(pos))
    a, b = coulomb_repulsion(pos), peer_coulomb(pos)
    return {
        "n_robots": n,
        "ours_coulomb_s": ours_s,
        "peer_coulomb_s": peer_s,
        "speed_ratio_ours_over_peer": peer_s / ours_s,
        "ours_traced_peak_bytes": ours_peak,
        "peer_traced_peak_bytes": peer_peak,
        "memory_ratio_ours_over_peer": ours_peak / peer_peak,
        "max_rel_force_difference": float(np.abs(a - b).max() / np.abs(b).max()),
        "max_rss_after_bytes": max_rss_bytes(),
    }


def _mb(x: float) -> str:
    return f"{x / 2**20:,.1f} MiB"


def _verdict(ok: bool) -> str:
    return "[bold green]PASS[/]" if ok else "[bold red]FAIL[/]"


def run(console: Console) -> dict[str, Any]:
    """Measure, print rich tables with the floors, and return every number."""
    console.rule("formation control (issue 4)")
    laws = []
    for n in TEAM_SIZES:
        console.print(f"  N = {n:>5,}: {REPEATS} timed runs of {STEPS[n]} steps per law ...")
        laws.append(run_laws(n))
    table = Table(title="formation step (force + eq. 5 point-mass step), single thread")
    for col in ("N", "deliverable steps/s", "regular steps/s", "robot-steps/s (regular)"):
        table.add_column(col, justify="right")
    table.add_column("traced peak / step", justify="right")
    for r in laws:
        table.add_row(
            f"{r['n_robots']:,}",
            f"{r['deliverable_steps_per_s']:,.1f}",
            f"{r['regular_steps_per_s']:,.1f}",
            f"{r['regular_robot_steps_per_s']:,.0f}",
            _mb(r["step_traced_peak_bytes"]),
        )
    console.print(table)

    peers = []
    for n in TEAM_SIZES:
        if n <= PEER_MAX_N:
            console.print(f"  peer (broadcast N x N x 2) at N = {n:,} ...")
            peers.append(run_peer(n))
    table = Table(title="Coulomb sum of eqs. 7-8: blocked (ours) vs broadcast NumPy (peer)")
    for col in ("N", "ours", "peer", "speed ours/peer", "ours peak", "peer peak", "max rel diff"):
        table.add_column(col, justify="right")
    for p in peers:
        table.add_row(
            f"{p['n_robots']:,}",
            f"{1e3 * p['ours_coulomb_s']:.3f} ms",
            f"{1e3 * p['peer_coulomb_s']:.3f} ms",
            f"{p['speed_ratio_ours_over_peer']:.2f}x",
            _mb(p["ours_traced_peak_bytes"]),
            _mb(p["peer_traced_peak_bytes"]),
            f"{p['max_rel_force_difference']:.1e}",
        )
    console.print(table)

    console.print("  whole runs: formation-regular-20, -200, 1,000 robots; deliverable 200")
    runs = [
        run_converging(load_scenario("formation-regular-20")),
        run_converging(load_scenario("formation-regular-200")),
        run_converging(team_scenario(FLOOR_N)),
        run_converging(team_scenario(200, "deliverable"), repeats=1),
    ]
    table = Table(
        title="whole runs from random starts (simulate; metrics not timed)",
        caption="radius error (mm), spacing error (deg), min gap between bodies (m); steps per "
        "wall second and per CPU second; deliverable: radius claim only (no contact force)",
    )
    for col in ("N", "law", "alpha", "radius", "spacing", "gap", "claims", "steps/s", "/cpu s"):
        table.add_column(col, justify="right")
    for r in runs:
        failed = [k for k, ok in r["claims"].items() if not ok]
        table.add_row(
            f"{r['n_robots']:,}",
            r["law"][:3],
            f"{r['alpha_m']:g} m",
            f"{1e3 * r['radius_error_max_m']:.2g}",
            f"{r['spacing_error_max_deg']:.2g}",
            f"{r['min_clearance_m']:.3f}",
            "FAIL" if failed else "hold",
            f"{r['steps_per_s']:,.0f}",
            f"{r['steps_per_cpu_s']:,.0f}",
        )
    console.print(table)

    big = runs[2]
    rate = big["steps_per_cpu_s"]
    by_n = {r["n_robots"]: r for r in laws}
    traced = by_n[MEMORY_N]["step_traced_peak_bytes"]
    rss = by_n[MEMORY_N]["max_rss_after_bytes"]
    floors = {
        "converging_steps_per_s_at_1000": {
            "measured": rate,
            "floor": FLOOR_STEPS_PER_S,
            "claims_hold": big["claims_hold"],
        },
        "traced_peak_bytes_at_5000": {"measured": traced, "ceiling": FLOOR_BYTES},
        "max_rss_bytes_after_5000": {"measured": rss, "ceiling": FLOOR_BYTES},
    }
    table = Table(title="floors (issues 4 and 13)")
    for col in ("floor", "measured", "bound", "result"):
        table.add_column(col)
    table.add_row(
        "N = 1,000, regular law, whole run",
        f"{rate:,.0f} steps/CPU s ({big['steps_per_s']:,.0f}/wall s), claims "
        + ("hold" if big["claims_hold"] else "fail"),
        f">= {FLOOR_STEPS_PER_S:g}, claims hold",
        _verdict(rate >= FLOOR_STEPS_PER_S and big["claims_hold"]),
    )
    table.add_row(
        "N = 5,000, traced peak of a step", _mb(traced), "< 1 GiB", _verdict(traced < FLOOR_BYTES)
    )
    table.add_row(
        "N = 5,000, process peak RSS (before the peer runs)",
        _mb(rss),
        "< 1 GiB",
        _verdict(rss < FLOOR_BYTES),
    )
    console.print(table)
    return {"laws": laws, "peer": peers, "runs": runs, "floors": floors}


if __name__ == "__main__":
    run(Console())
