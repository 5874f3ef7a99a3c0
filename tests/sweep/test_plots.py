"""A sweep's figures: one per swept key (numbers or values typed as text), pass rates."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import yaml
from PIL import Image

from firefleet import load_scenario
from firefleet.report.sweep import sweep_figures
from firefleet.sweep import build_table, parse_set, points_of, run_batch, summarize


def test_figures_for_a_numeric_and_a_text_key(tmp_path: Path) -> None:
    (tmp_path / "two.yaml").write_text(yaml.safe_dump([[0.0, 0.0, 0.0], [1.0, 0.0, 90.0]]))
    base = load_scenario("motor-pid")
    axes = [
        parse_set("speed_pid.kp=2,2.5"),
        parse_set("poses=[[0, 0, 0]],@two.yaml", base=tmp_path),
    ]
    points = points_of(base, axes)
    rows = [row for p in points for row in run_batch(p.scenario, p.index, [0, 1])]
    table = build_table(points, rows, base.name)
    assert table.column("poses").to_pylist()[::2] == [
        "[[0, 0, 0]]",
        "@two.yaml",
        "[[0, 0, 0]]",
        "@two.yaml",
    ]
    figures = sweep_figures(table, summarize(table, points), base.claims)
    assert sorted(figures) == [
        "metrics_vs_poses.png",
        "metrics_vs_speed_pid.kp.png",
        "pass_rates.png",
        "pass_rates_vs_poses.png",
        "pass_rates_vs_speed_pid.kp.png",
    ]
    for name, data in figures.items():
        image = np.asarray(Image.open(io.BytesIO(data)).convert("L"))
        assert image.shape[0] > 300, name
        assert image.shape[1] > 600, name
        assert image.std() > 10, name  # something is drawn
