"""Benchmark: firefleet's Takagi-Sugeno engine against scikit-fuzzy's ControlSystemSimulation.

The controller has the shape of the deliverable's (section 2.6.2, Table 1): inputs
D_rp (5 membership functions), x_err (2), y_err (7) and alpha (5); outputs v and
omega; the 11 rules of Table 1 (y_err feeds the lambda correction, not these rules).
Its membership functions are written here (the shipped controller,
``control/data/path_following.fis``, comes with the path-following work; this file
may switch to it).

The peer is the equivalent Mamdani controller in scikit-fuzzy 0.5.0: the same input
membership functions and rules (AND = min on both sides, scikit-fuzzy's default),
each Sugeno constant replaced by a narrow triangle centred on it, centroid
defuzzification, universes of 1,001 points. scikit-fuzzy runs without its result
cache (every sample is new here anyway).

Measured (best of several timed runs after an untimed warm-up):

1. one sample at a time: firefleet ``evaluate(system, x)`` with x of shape (4,),
   scikit-fuzzy ``input[...] = ...; compute()``;
2. batches of 10,000: firefleet ``evaluate(system, X)`` with X (10,000, 4);
   scikit-fuzzy with array inputs of 10,000 (its array mode).

Also measured, without a peer: the compiled ``eval_one`` that the simulator's team loop
inlines per robot and tick, called in a compiled loop (the cost of one robot's fuzzy
decision inside the simulator).

Floors: firefleet one at a time at least 100x scikit-fuzzy one at a time; firefleet
in batches of 10,000 at least 10,000x scikit-fuzzy one at a time (the ratio to
scikit-fuzzy's own array mode is reported beside it); the public API one sample at a
time (``evaluate(system, x)``, x of shape (4,)) at least 300,000 evaluations per
second (the floor of the one-simulator issue; 77,000/s before the compiled path).
The two controllers are different inference methods (weighted average against
clipped-triangle centroid with max accumulation), so their outputs agree only
roughly: the distance is printed, not judged.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
import skfuzzy
from numpy.typing import NDArray
from rich.console import Console
from rich.table import Table
from skfuzzy import control as skctrl

from _harness import Floor, Row, TopicResult, best_of
from firefleet.control.fuzzy import (
    FuzzyInput,
    FuzzyOutput,
    MembershipFunction,
    Rule,
    SugenoOutputMf,
    SugenoSystem,
    evaluate,
)
from firefleet.control.fuzzy_kernel import FisTables, compile_system, eval_one

FloatArray = NDArray[np.float64]

FLOOR_SINGLE = 100.0
"""Floor: one-at-a-time speed-up over scikit-fuzzy one at a time."""
FLOOR_BATCH = 10_000.0
"""Floor: batch-of-10,000 throughput over scikit-fuzzy one at a time."""
FLOOR_SINGLE_PER_S = 300_000.0
"""Floor: public-API evaluations per second, one sample per call."""
KERNEL_SAMPLES = 200_000
"""Samples of the compiled eval_one loop per timed run."""
BATCH = 10_000
SINGLE_SAMPLES = 2_000
"""Samples of firefleet's one-at-a-time loop per timed run."""
PEER_SINGLE_SAMPLES = 200
"""Samples of scikit-fuzzy's one-at-a-time loop per timed run (about 3 ms each)."""
REPEATS = 5
PEER_REPEATS = 3
UNIVERSE_POINTS = 1_001
HALF_WIDTH = {"v": 0.005, "omega": 0.02}
"""Half-widths of the peer's output triangles [m/s, rad/s]: narrow beside the spacing."""

D_MAX, X_MAX, Y_MAX = 3.0, 1.0, 3.0
"""Input ranges: D_rp [0, 3] m, x_err [-1, 1] m, y_err [-3, 3] m, alpha [-pi, pi] rad."""

INPUT_MFS: dict[str, list[tuple[str, str, tuple[float, ...]]]] = {
    # dense near the point, wide far away, overlapping (section 2.6.2.1)
    "D_rp": [
        ("VeryClose", "trimf", (0.0, 0.0, 0.1)),
        ("Close", "trimf", (0.05, 0.15, 0.3)),
        ("Medium", "trimf", (0.15, 0.35, 0.6)),
        ("Far", "trimf", (0.4, 1.0, 1.8)),
        ("VeryFar", "trapmf", (1.2, 2.2, 3.0, 3.0)),
    ],
    "x_err": [("Negative", "zmf", (-0.02, 0.0)), ("Positive", "smf", (0.0, 0.02))],
    "y_err": [
        ("nVeryFar", "trapmf", (-3.0, -3.0, -2.5, -1.5)),
        ("nFar", "trimf", (-2.5, -1.5, -0.6)),
        ("nClose", "trimf", (-1.2, -0.5, 0.0)),
        ("VeryClose", "gaussmf", (0.15, 0.0)),
        ("Close", "trimf", (0.0, 0.5, 1.2)),
        ("Far", "trimf", (0.6, 1.5, 2.5)),
        ("VeryFar", "trapmf", (1.5, 2.5, 3.0, 3.0)),
    ],
    "alpha": [
        ("BigNegative", "trapmf", (-np.pi, -np.pi, -1.5, -0.6)),
        ("mNeg", "trimf", (-1.2, -0.5, 0.0)),
        ("Small", "trimf", (-0.3, 0.0, 0.3)),
        ("mPos", "trimf", (0.0, 0.5, 1.2)),
        ("BigPositive", "trapmf", (0.6, 1.5, np.pi, np.pi)),
    ],
}
RANGES = {
    "D_rp": (0.0, D_MAX),
    "x_err": (-X_MAX, X_MAX),
    "y_err": (-Y_MAX, Y_MAX),
    "alpha": (-np.pi, np.pi),
}
OUTPUT_MFS: dict[str, list[tuple[str, float]]] = {
    "v": [
        ("Zero", 0.0),
        ("VeryVerySlow", 0.05),
        ("VerySlow", 0.1),
        ("Slow", 0.2),
        ("Fast", 0.4),
        ("VeryFast", 0.6),
    ],
    "omega": [
        ("BigNegative", -2.0),
        ("Negative", -0.8),
        ("Zero", 0.0),
        ("Positive", 0.8),
        ("BigPositive", 2.0),
    ],
}
OUTPUT_RANGES = {"v": (0.0, 0.6), "omega": (-2.0, 2.0)}
# Table 1: (D_rp, x_err, alpha) terms -> (v, omega); None = input not in the rule
TABLE_1: list[tuple[str | None, str, str | None, str, str]] = [
    ("VeryClose", "Positive", None, "VeryVerySlow", "Zero"),
    ("Close", "Positive", None, "VerySlow", "Zero"),
    ("Medium", "Positive", None, "Slow", "Zero"),
    ("Far", "Positive", None, "Fast", "Zero"),
    ("VeryFar", "Positive", None, "VeryFast", "Zero"),
    (None, "Positive", "BigNegative", "VeryVerySlow", "BigNegative"),
    (None, "Positive", "mNeg", "VeryVerySlow", "Negative"),
    (None, "Positive", "Small", "VeryVerySlow", "Zero"),
    (None, "Positive", "mPos", "VeryVerySlow", "Positive"),
    (None, "Positive", "BigPositive", "VeryVerySlow", "BigPositive"),
    (None, "Negative", None, "Zero", "Zero"),
]


def _index(variable: str, term: str | None) -> int:
    if term is None:
        return 0
    return [n for n, _, _ in INPUT_MFS[variable]].index(term) + 1


def our_system() -> SugenoSystem:
    """The Table-1-shaped controller as a firefleet Sugeno system (AND = min)."""
    inputs = tuple(
        FuzzyInput(
            name,
            RANGES[name],
            tuple(MembershipFunction(n, k, p) for n, k, p in mfs),  # type: ignore[arg-type]
        )
        for name, mfs in INPUT_MFS.items()
    )
    outputs = tuple(
        FuzzyOutput(
            name, OUTPUT_RANGES[name], tuple(SugenoOutputMf(n, "constant", (c,)) for n, c in mfs)
        )
        for name, mfs in OUTPUT_MFS.items()
    )
    v_names = [n for n, _ in OUTPUT_MFS["v"]]
    w_names = [n for n, _ in OUTPUT_MFS["omega"]]
    rules = tuple(
        Rule(
            (_index("D_rp", d), _index("x_err", x), 0, _index("alpha", a)),
            (v_names.index(v) + 1, w_names.index(w) + 1),
        )
        for d, x, a, v, w in TABLE_1
    )
    return SugenoSystem("table1_shape", inputs, outputs, rules, and_method="min")


def peer_system() -> Any:
    """The equivalent Mamdani controller in scikit-fuzzy (a ControlSystem)."""
    shapes: dict[str, Callable[..., Any]] = {
        "trimf": lambda u, p: skfuzzy.trimf(u, list(p)),
        "trapmf": lambda u, p: skfuzzy.trapmf(u, list(p)),
        "gaussmf": lambda u, p: skfuzzy.gaussmf(u, p[1], p[0]),
        "smf": lambda u, p: skfuzzy.smf(u, p[0], p[1]),
        "zmf": lambda u, p: skfuzzy.zmf(u, p[0], p[1]),
    }
    ants = {}
    for name in ("D_rp", "x_err", "alpha"):  # y_err is in no rule of Table 1
        ant = skctrl.Antecedent(np.linspace(*RANGES[name], UNIVERSE_POINTS), name)
        for term, kind, params in INPUT_MFS[name]:
            ant[term] = shapes[kind](ant.universe, params)
        ants[name] = ant
    cons = {}
    for name, mfs in OUTPUT_MFS.items():
        lo, hi = OUTPUT_RANGES[name]
        h = HALF_WIDTH[name]
        con = skctrl.Consequent(np.linspace(lo - 2 * h, hi + 2 * h, UNIVERSE_POINTS), name)
        for term, c in mfs:
            con[term] = skfuzzy.trimf(con.universe, [c - h, c, c + h])
        cons[name] = con
    rules = []
    for d, x, a, v, w in TABLE_1:
        terms = [ants["x_err"][x]]
        if d is not None:
            terms.insert(0, ants["D_rp"][d])
        if a is not None:
            terms.append(ants["alpha"][a])
        antecedent = terms[0]
        for t in terms[1:]:
            antecedent = antecedent & t
        rules.append(skctrl.Rule(antecedent, (cons["v"][v], cons["omega"][w])))
    return skctrl.ControlSystem(rules)


def samples(n: int, seed: int) -> FloatArray:
    """Random inputs over the ranges, x_err mostly positive (robots behind their point)."""
    rng = np.random.default_rng(seed)
    return np.column_stack(
        [
            rng.uniform(0.0, D_MAX, n),
            rng.uniform(-0.2, X_MAX, n),
            rng.uniform(-Y_MAX, Y_MAX, n),
            rng.uniform(-np.pi, np.pi, n),
        ]
    )


def peer_one(sim: Any, x: FloatArray) -> tuple[float, float]:
    sim.input["D_rp"] = x[0]
    sim.input["x_err"] = x[1]
    sim.input["alpha"] = x[3]
    sim.compute()
    return float(sim.output["v"]), float(sim.output["omega"])


@numba.njit(cache=True)
def _kernel_loop(x: FloatArray, t: FisTables, out: FloatArray) -> None:  # pragma: no cover - jit
    """``eval_one`` on every row of ``x``, as the simulator's team loop calls it."""
    # the tables as local arrays, as the simulator passes them (not a tuple's fields)
    kind, par, inp, rng, rmf, rnot = (
        t.mf_kind,
        t.mf_params,
        t.mf_input,
        t.in_range,
        t.rule_mf,
        t.rule_not,
    )
    rw, ror, rout, coef, mid, flags = (
        t.rule_weight,
        t.rule_or,
        t.rule_out,
        t.out_coef,
        t.out_mid,
        t.flags,
    )
    work = np.empty(x.shape[1] + kind.shape[0] + 2 * out.shape[1])
    row = np.empty(x.shape[1])
    y = np.empty(out.shape[1])
    for k in range(x.shape[0]):
        for i in range(x.shape[1]):
            row[i] = x[k, i]
        eval_one(
            row,
            kind,
            par,
            inp,
            rng,
            rmf,
            rnot,
            rw,
            ror,
            rout,
            coef,
            mid,
            flags,
            y,
            work,
        )
        for j in range(out.shape[1]):
            out[k, j] = y[j]


def verdict(ok: bool) -> str:
    return "[bold green]PASS[/]" if ok else "[bold red]FAIL[/]"


def run(console: Console) -> TopicResult:
    """Measure, print the tables, return the rows, the floors and every number."""
    system = our_system()
    control_system = peer_system()
    single_x = samples(SINGLE_SAMPLES, 1)
    peer_x = samples(PEER_SINGLE_SAMPLES, 2)
    batch_x = samples(BATCH, 3)
    single_rows = list(single_x)

    console.print(f"  firefleet one at a time ({SINGLE_SAMPLES} samples x {REPEATS}) ...")

    def ours_single() -> None:
        for row in single_rows:
            evaluate(system, row)

    ours_single_s = best_of(ours_single, REPEATS).best_s / SINGLE_SAMPLES
    console.print(f"  firefleet batches of {BATCH:,} ({REPEATS} runs) ...")
    ours_batch_s = best_of(lambda: evaluate(system, batch_x), REPEATS).best_s / BATCH
    console.print(f"  firefleet compiled eval_one loop ({KERNEL_SAMPLES:,} samples) ...")
    tables = compile_system(system)
    kernel_x = samples(KERNEL_SAMPLES, 4)
    kernel_out = np.empty((KERNEL_SAMPLES, len(system.outputs)))
    kernel_s = best_of(lambda: _kernel_loop(kernel_x, tables, kernel_out), REPEATS).best_s
    kernel_s /= KERNEL_SAMPLES
    kernel_ok = bool(np.array_equal(kernel_out[:BATCH], evaluate(system, kernel_x[:BATCH])))

    console.print(
        f"  scikit-fuzzy one at a time ({PEER_SINGLE_SAMPLES} samples x {PEER_REPEATS}) ..."
    )
    sim = skctrl.ControlSystemSimulation(control_system, cache=False)
    peer_rows = list(peer_x)

    def peer_single() -> None:
        for row in peer_rows:
            peer_one(sim, row)

    peer_single_s = best_of(peer_single, PEER_REPEATS).best_s / PEER_SINGLE_SAMPLES

    console.print(f"  scikit-fuzzy array mode, {BATCH:,} samples (one timed run) ...")

    def peer_batch(x: FloatArray) -> tuple[FloatArray, FloatArray]:
        # a new simulation per call: scikit-fuzzy warns when array shapes change
        arr_sim = skctrl.ControlSystemSimulation(control_system, cache=False)
        arr_sim.input["D_rp"] = x[:, 0]
        arr_sim.input["x_err"] = x[:, 1]
        arr_sim.input["alpha"] = x[:, 3]
        arr_sim.compute()
        return np.asarray(arr_sim.output["v"]), np.asarray(arr_sim.output["omega"])

    peer_batch(batch_x[:50])  # warm-up
    t0 = time.perf_counter()
    peer_v, peer_w = peer_batch(batch_x)
    peer_batch_s = (time.perf_counter() - t0) / BATCH

    ours = evaluate(system, batch_x)
    diff_v = np.abs(ours[:, 0] - peer_v)
    diff_w = np.abs(ours[:, 1] - peer_w)
    single_ok = np.allclose(
        np.array([evaluate(system, r) for r in batch_x[:200]]), ours[:200], rtol=0, atol=1e-12
    )

    ratio_single = peer_single_s / ours_single_s
    ratio_batch = peer_single_s / ours_batch_s
    ratio_batch_vs_array = peer_batch_s / ours_batch_s
    table = Table(title="Fuzzy inference: evaluations per second (Table-1-shaped controller)")
    table.add_column("contestant")
    table.add_column("mode")
    table.add_column("evaluations/s", justify="right")
    table.add_column("us per evaluation", justify="right")
    for who, mode, sec in (
        ("firefleet (Sugeno)", "one at a time", ours_single_s),
        ("firefleet (Sugeno)", f"batches of {BATCH:,}", ours_batch_s),
        ("firefleet (Sugeno)", "eval_one in a compiled loop", kernel_s),
        ("scikit-fuzzy (Mamdani)", "one at a time", peer_single_s),
        ("scikit-fuzzy (Mamdani)", f"array of {BATCH:,}", peer_batch_s),
    ):
        table.add_row(who, mode, f"{1 / sec:,.0f}", f"{sec * 1e6:,.3f}")
    console.print(table)
    rows = (
        Row(
            "fuzzy.single.evals_per_s",
            1 / ours_single_s,
            "evals/s",
            label="fuzzy controller one at a time (public API): evaluations per second",
        ),
        Row(
            "fuzzy.batch10000.evals_per_s",
            1 / ours_batch_s,
            "evals/s",
            label=f"fuzzy controller, batches of {BATCH:,}: evaluations per second",
        ),
        Row(
            "fuzzy.kernel.evals_per_s",
            1 / kernel_s,
            "evals/s",
            label="fuzzy eval_one in a compiled loop (as the simulator calls it): evaluations/s",
        ),
    )
    floors = (
        Floor("one at a time: scikit-fuzzy time / firefleet time", ratio_single, FLOOR_SINGLE, "x"),
        Floor(
            f"batches of {BATCH:,}: scikit-fuzzy (one at a time) / firefleet, per sample",
            ratio_batch,
            FLOOR_BATCH,
            "x",
        ),
        Floor.on(rows[0], ">=", FLOOR_SINGLE_PER_S),
    )
    ftable = Table(title="Fuzzy floors (a measurement: exit status 0 either way)")
    for col in ("floor", "required", "measured", "verdict"):
        ftable.add_column(col, justify="right" if col in ("required", "measured") else "left")
    for f in floors:
        ftable.add_row(
            f.name,
            f"{f.op} {f.bound:,.0f} {f.unit}",
            f"{f.measured:,.0f} {f.unit}",
            verdict(f.passed),
        )
    console.print(ftable)
    console.print(
        f"  batch vs scikit-fuzzy's own array mode: {ratio_batch_vs_array:,.0f}x per sample "
        "(no floor; its array mode defuzzifies sample by sample in Python)."
    )
    console.print(
        f"  outputs, firefleet Sugeno vs scikit-fuzzy Mamdani on {BATCH:,} samples: "
        f"|dv| median {np.median(diff_v):.3g}, max {diff_v.max():.3g} m/s; |domega| median "
        f"{np.median(diff_w):.3g}, max {diff_w.max():.3g} rad/s (different inference "
        "methods, not expected to agree exactly); firefleet's single and batch paths agree "
        f"to 1e-12: {single_ok}; eval_one equals evaluate bit for bit: {kernel_ok}."
    )
    details = {
        "controller": {"inputs": {k: len(v) for k, v in INPUT_MFS.items()}, "rules": len(TABLE_1)},
        "ours_single_s_per_eval": ours_single_s,
        "ours_batch_s_per_eval": ours_batch_s,
        "peer_single_s_per_eval": peer_single_s,
        "peer_array_s_per_eval": peer_batch_s,
        "ours_single_evals_per_s": 1 / ours_single_s,
        "ours_batch_evals_per_s": 1 / ours_batch_s,
        "ours_kernel_s_per_eval": kernel_s,
        "ours_kernel_evals_per_s": 1 / kernel_s,
        "kernel_equals_evaluate": kernel_ok,
        "peer_single_evals_per_s": 1 / peer_single_s,
        "peer_array_evals_per_s": 1 / peer_batch_s,
        "speedup_single": ratio_single,
        "speedup_batch_vs_peer_single": ratio_batch,
        "speedup_batch_vs_peer_array": ratio_batch_vs_array,
        "output_diff_v_median": float(np.median(diff_v)),
        "output_diff_v_max": float(diff_v.max()),
        "output_diff_omega_median": float(np.median(diff_w)),
        "output_diff_omega_max": float(diff_w.max()),
        "single_equals_batch": bool(single_ok),
        "versions": {"numpy": np.__version__, "scikit-fuzzy": skfuzzy.__version__},
    }
    return TopicResult(rows, floors, details)


if __name__ == "__main__":
    threads = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
    if os.name == "posix" and not any(v in os.environ for v in threads):
        # single-threaded BLAS, as bench/run.py sets; only effective before numpy loads
        env = {**os.environ, **dict.fromkeys(threads, "1")}
        os.execve(sys.executable, [sys.executable, *sys.argv], env)
    run(Console(width=None if sys.stdout.isatty() else 130))
