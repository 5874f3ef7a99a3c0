"""False-colour thermal frames with their detections drawn and labelled."""

from __future__ import annotations

import io
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from firefleet.errors import InputError
from firefleet.perception.thermal import FrameDetections

__all__ = ["detection_png", "figure_names"]


def figure_names(frames: Sequence[str | Path]) -> list[str]:
    """The picture's file name of each frame: ``<stem>.png``, distinct for every frame.

    Frames that share a stem (``x.npy`` and ``x.png``) get their type in the name
    (``x_npy.png``, ``x_png.png``), so one picture never overwrites another.

    Raises
    ------
    InputError
        If two frames share a file name (``a/x.npy`` and ``b/x.npy``: their entries in
        ``detections.json`` could not be told apart), or names still collide.

    Examples
    --------
    >>> figure_names(["x.npy", "x.png", "y.npy"])
    ['x_npy.png', 'x_png.png', 'y.png']
    """
    paths = [Path(f) for f in frames]
    by_name: dict[str, list[Path]] = {}
    for p in paths:
        by_name.setdefault(p.name, []).append(p)
    for name, same in by_name.items():
        if len(same) > 1:
            raise InputError(
                f"frames {', '.join(map(str, same))} share the file name {name}: rename one "
                "(outputs are named after the frame)"
            )
    stems = Counter(p.stem for p in paths)
    names = [
        f"{p.stem}_{p.suffix.lstrip('.').lower()}.png" if stems[p.stem] > 1 else f"{p.stem}.png"
        for p in paths
    ]
    clash = [n for n, k in Counter(names).items() if k > 1]
    if clash:
        raise InputError(
            f"frames would write the same picture {clash[0]}: rename one of "
            + ", ".join(str(p) for p, n in zip(paths, names, strict=True) if n == clash[0])
        )
    return names


_COLOURS = {"fire": "#ff2a2a", "person": "#2aff6a", "warm": "#35c8ff"}


def detection_png(frame_c: NDArray[np.float64], result: FrameDetections, *, title: str) -> bytes:
    """PNG of a frame (inferno colour map, colour bar in C) with each detection boxed.

    ``frame_c`` is (H, W) in degrees Celsius; ``title`` heads the figure.

    Labels give the kind, the peak temperature and the range where known.
    """
    import matplotlib  # only when a figure is made

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import PowerNorm
    from matplotlib.patches import Rectangle

    h, w = frame_c.shape
    width_in = 7.0
    fig, ax = plt.subplots(figsize=(width_in, width_in * h / w * 0.95 + 0.6))
    lo, hi = float(np.min(frame_c)), float(np.max(frame_c))
    # a fire hundreds of kelvin above the room would leave people and walls one colour:
    # a square-root scale keeps both visible when the span exceeds 50 K
    norm = PowerNorm(gamma=0.5, vmin=lo, vmax=hi) if hi - lo > 50.0 else None
    image = ax.imshow(frame_c, cmap="inferno", interpolation="nearest", norm=norm)
    fig.colorbar(image, ax=ax, label="temperature (C)", fraction=0.046, pad=0.03)
    for det in result.detections:
        r0, c0, r1, c1 = det.bbox_rc
        colour = _COLOURS[det.kind]
        ax.add_patch(
            Rectangle((c0 - 0.5, r0 - 0.5), c1 - c0, r1 - r0, fill=False, ec=colour, lw=1.8)
        )
        label = f"{det.kind} {det.peak_c:.1f} C"
        if det.range_m is not None:
            label += f", {det.range_m:.1f} m"
        ax.text(
            c0 - 0.5,
            r0 - 0.5,
            label,
            color="black",
            fontsize=8,
            va="bottom",
            ha="left",
            bbox={"facecolor": colour, "edgecolor": "none", "pad": 1.5, "alpha": 0.9},
            clip_on=True,
        )
    alarm = "FIRE ALARM" if result.fire_alarm else "no fire"
    ax.set_title(f"{title}: {len(result.detections)} detection(s), {alarm}", fontsize=10)
    ax.set_xlabel("column (px)")
    ax.set_ylabel("row (px)")
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return buffer.getvalue()
