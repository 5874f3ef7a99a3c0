"""Rows and floors of the topic modules that still return a plain dict from ``run(console)``.

A topic that returns a :class:`_harness.TopicResult` needs nothing here. For the others,
one reader per topic turns its dict (the shape it returned at commit e41e726) into
harness rows, with the keys ``bench/baseline.json`` uses, and harness floors. When a
topic adopts the harness it keeps these keys and its reader goes.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from typing import Any

from _harness import Floor, Op, Row, TopicResult

__all__ = ["READERS", "parse_bound", "slug", "topic_result"]


def slug(text: str) -> str:
    """``"Motorcycle 741 x 500"`` -> ``"motorcycle_741x500"`` (a row-key segment)."""
    text = re.sub(r"(\d)\s*x\s*(\d)", r"\1x\2", text.lower())
    return re.sub(r"[^a-z0-9]+", "_", text).strip("_")


_BOUND = re.compile(r"^\s*(>=|<=|<|>)?\s*([-+]?[\d,]*\.?\d+(?:e[-+]?\d+)?)\s*(.*?)\s*$")


def parse_bound(text: str) -> tuple[Op | None, float, str]:
    """``">= 30 %"`` -> ``(">=", 30.0, "%")``; ``"6.28 s"`` -> ``(None, 6.28, "s")``."""
    m = _BOUND.match(text)
    if m is None:
        raise ValueError(f"not a number with an optional comparison and unit: {text!r}")
    op: Op | None = m.group(1)  # type: ignore[assignment]
    return op, float(m.group(2).replace(",", "")), m.group(3)


def _text_floors(floors: list[dict[str, Any]]) -> list[Floor]:
    """Floors written as text (``"required": ">= 30 %"``, ``"measured": "32.3 %"``).

    ``"required": "no worse"`` with ``"measured": "0.264 vs 0.690 m"`` is ours <= theirs;
    any other wording keeps the topic's own verdict (measured 1 if it passed, else 0).
    """
    out = []
    for f in floors:
        try:
            op, bound, unit = parse_bound(f["required"])
            _, measured, _ = parse_bound(f["measured"])
            out.append(Floor(f["name"], measured, bound, unit, op or ">="))
            continue
        except ValueError:
            pass
        ours, _, theirs = str(f["measured"]).partition(" vs ")
        if f["required"] == "no worse" and theirs:
            _, a, _ = parse_bound(ours)
            _, b, unit = parse_bound(theirs)
            out.append(Floor(f["name"], a, b, unit, "<="))
        else:
            name = f"{f['name']} ({f['required']}: {f['measured']})"
            out.append(Floor(name, float(bool(f["pass"])), 1.0, "pass", ">="))
    return out


def path_following(d: Mapping[str, Any]) -> TopicResult:
    """bench/path_following.py: x real time of the 3-robot scenario and of 1,000 robots."""
    keys = (
        "path_following.coop_different_paths.x_real_time",
        "path_following.robots1000.x_real_time",
    )
    rows, floors = [], []
    for key, r in zip(keys, d["rows"], strict=True):
        row = Row(key, r["x_real_time"], "x real time", label=f"{r['case']}: x real time")
        rows.append(row)
        floors.append(Floor.on(row, ">=", r["floor_x_real_time"]))
    return TopicResult(tuple(rows), tuple(floors), d)


def fuzzy(d: Mapping[str, Any]) -> TopicResult:
    """bench/fuzzy.py: evaluations per second one at a time and in batches."""
    rows = (
        Row(
            "fuzzy.single.evals_per_s",
            d["ours_single_evals_per_s"],
            "evals/s",
            label="fuzzy controller one at a time (public API): evaluations per second",
        ),
        Row(
            "fuzzy.batch10000.evals_per_s",
            d["ours_batch_evals_per_s"],
            "evals/s",
            label="fuzzy controller, batches of 10,000: evaluations per second",
        ),
    )
    floors = tuple(Floor(f["name"], f["measured"], f["required"], "x") for f in d["floors"])
    return TopicResult(rows, floors, d)


def formation(d: Mapping[str, Any]) -> TopicResult:
    """bench/formation.py: formation steps per second by N, the Coulomb sum, memory."""
    rows = []
    for law in d["laws"]:
        n = law["n_robots"]
        for name in ("deliverable", "regular"):
            rows.append(
                Row(
                    f"formation.{name}.n{n}.steps_per_s",
                    law[f"{name}_steps_per_s"],
                    "steps/s",
                    label=f"formation step, {name} law, N = {n:,}",
                )
            )
        rows.append(
            Row(
                f"formation.step.n{n}.traced_peak_mb",
                law["step_traced_peak_bytes"] / 1e6,
                "MB",
                higher_is_better=False,
                kind="memory",
            )
        )
    for p in d["peer"]:
        n = p["n_robots"]
        rows.append(
            Row(
                f"formation.coulomb.n{n}.ours_s",
                p["ours_coulomb_s"],
                "s",
                higher_is_better=False,
                label=f"Coulomb sum, N = {n:,}",
            )
        )
    fl = d["floors"]
    floors = (
        Floor(
            "N = 1,000, regular law, a whole run that converges: steps per CPU second",
            # a run whose claims fail does not count, however fast
            fl["converging_steps_per_s_at_1000"]["measured"]
            if fl["converging_steps_per_s_at_1000"]["claims_hold"]
            else 0.0,
            fl["converging_steps_per_s_at_1000"]["floor"],
            "steps/s",
        ),
        Floor(
            "N = 5,000, traced peak of a step",
            fl["traced_peak_bytes_at_5000"]["measured"] / 2**20,
            fl["traced_peak_bytes_at_5000"]["ceiling"] / 2**20,
            "MiB",
            "<",
        ),
        Floor(
            "N = 5,000, process peak RSS (before the peer runs)",
            fl["max_rss_bytes_after_5000"]["measured"] / 2**20,
            fl["max_rss_bytes_after_5000"]["ceiling"] / 2**20,
            "MiB",
            "<",
        ),
    )
    return TopicResult(tuple(rows), floors, d)


def thermal(d: Mapping[str, Any]) -> TopicResult:
    """bench/thermal.py: seconds per frame through the detection pipeline, by frame size."""
    rows = tuple(
        Row(
            f"thermal.pipeline.{slug(size)}.s_per_frame",
            s["ours_s_per_frame"],
            "s",
            higher_is_better=False,
            label=f"thermal pipeline, {size} frame",
        )
        for size, s in d["sizes"].items()
    )
    f = d["floor"]
    floor = Floor(
        "80 x 60 frame through the whole pipeline", f["measured_s"], f["required_s"], "s", "<"
    )
    return TopicResult(rows, (floor,), d)


def stereo(d: Mapping[str, Any]) -> TopicResult:
    """bench/stereo.py: frames per second of compute_disparity by image and thread count."""
    rows = []
    for size, s in d["sizes"].items():
        for threads, sp in s["speed"].items():
            rows.append(
                Row(
                    f"stereo.{slug(size)}.fps_{slug(threads)}",
                    sp["ours_fps"],
                    "fps",
                    label=f"compute_disparity, {size}, {threads.replace('_', ' ')}",
                )
            )
    return TopicResult(tuple(rows), tuple(_text_floors(d["floors"])), d)


def slam(d: Mapping[str, Any]) -> TopicResult:
    """bench/slam.py: Victoria Park run time per configuration, FastSLAM 1.0 steps/s."""
    rows = []
    for c in d["victoria_park"].get("configs", []):  # none when the data set is absent
        rows.append(
            Row(
                f"slam.victoria_park.{slug(c['name'])}_p{c['particles']}.best_run_s",
                min(r["run_time_s"] for r in c["runs"]),
                "s",
                higher_is_better=False,
                label=f"Victoria Park, {c['name']}, {c['particles']} particles: fastest seed",
            )
        )
    for s in d["scaling"]:
        key = f"slam.scaling.p{s['particles']}_l{s['landmarks']}"
        rows.append(Row(f"{key}.steps_per_s", s["steps_per_s"], "steps/s"))
        rows.append(
            Row(
                f"{key}.step_peak_mb",
                s["step_peak_mb"],
                "MB",
                higher_is_better=False,
                kind="memory",
            )
        )
    return TopicResult(tuple(rows), tuple(_text_floors(d["floors"])), d)


READERS: dict[str, Callable[[Mapping[str, Any]], TopicResult]] = {
    "path_following": path_following,
    "fuzzy": fuzzy,
    "formation": formation,
    "thermal": thermal,
    "stereo": stereo,
    "slam": slam,
}
"""Topic name -> reader of the dict its ``run(console)`` returns."""


def topic_result(name: str, returned: object) -> TopicResult:
    """A topic's return value as a :class:`TopicResult` (read by ``READERS`` if a dict)."""
    if isinstance(returned, TopicResult):
        return returned
    if isinstance(returned, Mapping) and name in READERS:
        return READERS[name](returned)
    raise TypeError(f"bench/{name}.py returned {type(returned).__name__}, not a TopicResult")
