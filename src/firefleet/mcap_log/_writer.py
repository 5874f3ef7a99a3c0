"""Writing a run as MCAP with the Foxglove SDK (see the package notes for the topics)."""

from __future__ import annotations

import io
import math
from collections.abc import Mapping
from typing import Any

import foxglove
import numpy as np
from foxglove import channels as ch
from foxglove import messages as fm

__all__ = ["RANGE_NAMES", "mcap_bytes"]

RANGE_NAMES = ("lidar_range_m", "ultrasonic_range_m")
_LAYERED = {"t", "pose", "occupancy", "map", "map_resolution_m", "map_origin_m", *RANGE_NAMES}


def _stamp(t_s: float) -> fm.Timestamp:
    sec, nsec = divmod(round(t_s * 1e9), 1_000_000_000)
    return fm.Timestamp(sec=sec, nsec=nsec)


def _parts(x: float, y: float, theta: float) -> tuple[fm.Vector3, fm.Quaternion]:
    return (
        fm.Vector3(x=x, y=y, z=0.0),
        fm.Quaternion(x=0.0, y=0.0, z=math.sin(theta / 2), w=math.cos(theta / 2)),
    )


def _pose(x: float, y: float, theta: float) -> fm.Pose:
    position, orientation = _parts(x, y, theta)
    return fm.Pose(position=position, orientation=orientation)


def _scene(scene: Mapping[str, Any], log_time: int) -> fm.SceneUpdate:
    entities = []
    for i, path in enumerate(scene.get("paths", ())):
        line = fm.LinePrimitive(
            type=fm.LinePrimitiveLineType.LineStrip,
            thickness=0.03,
            points=[fm.Point3(x=float(p[0]), y=float(p[1]), z=0.0) for p in path],
            color=fm.Color(r=0.3, g=0.3, b=0.3, a=1.0),
        )
        entities.append(fm.SceneEntity(frame_id="world", id=f"path_{i + 1}", lines=[line]))
    for i, (x, y, r) in enumerate(scene.get("obstacles", ())):
        cylinder = fm.CylinderPrimitive(
            pose=_pose(float(x), float(y), 0.0),
            size=fm.Vector3(x=2 * r, y=2 * r, z=0.5),
            bottom_scale=1.0,
            top_scale=1.0,
            color=fm.Color(r=0.4, g=0.4, b=0.4, a=0.8),
        )
        entities.append(
            fm.SceneEntity(frame_id="world", id=f"obstacle_{i + 1}", cylinders=[cylinder])
        )
    return fm.SceneUpdate(entities=entities)


def _grid(cells: np.ndarray, resolution_m: float, origin_m: np.ndarray) -> fm.Grid:
    """The map as a Grid of uint8 occupancy (0..100); Grid's row 0 is at the origin (the
    bottom), the map's row 0 at the top, so the rows are flipped."""
    occupancy = np.asarray(cells, dtype=np.float64)
    if np.nanmax(occupancy, initial=0.0) <= 1.0:
        occupancy = occupancy * 100.0
    data = np.clip(np.nan_to_num(occupancy[::-1], nan=255.0), 0, 255).astype(np.uint8)
    return fm.Grid(
        frame_id="world",
        pose=_pose(float(origin_m[0]), float(origin_m[1]), 0.0),
        column_count=int(data.shape[1]),
        cell_size=fm.Vector2(x=resolution_m, y=resolution_m),
        row_stride=int(data.shape[1]),
        cell_stride=1,
        fields=[
            fm.PackedElementField(
                name="occupancy", offset=0, type=fm.PackedElementFieldNumericType.Uint8
            )
        ],
        data=data.tobytes(),
    )


def mcap_bytes(
    arrays: Mapping[str, np.ndarray],
    *,
    document: Mapping[str, Any] | None = None,
    scene: Mapping[str, Any] | None = None,
) -> bytes:
    """A run as the bytes of an MCAP file (Foxglove schemas, simulated timestamps).

    Parameters
    ----------
    arrays : mapping of str to ndarray
        The run's arrays by ``result.npz``'s names: ``t`` (T,) [s], ``pose`` (T, N, 3)
        [m, m, rad], and any of the layers of :mod:`firefleet.serve.replay`.
    document : mapping, optional
        The run's ``metrics.json``: its ``scenario`` and ``claims`` go to ``/events``.
    scene : mapping, optional
        Static geometry (:func:`firefleet.serve.scene.scene_of`) for ``/scene``.

    Returns
    -------
    bytes
        The MCAP file (zstd chunks, with a summary and statistics).

    Examples
    --------
    >>> import io
    >>> import numpy as np
    >>> from mcap.reader import make_reader
    >>> from firefleet.mcap_log import mcap_bytes
    >>> t = np.array([0.0, 0.5, 1.0]); pose = np.zeros((3, 2, 3))
    >>> summary = make_reader(io.BytesIO(mcap_bytes({"t": t, "pose": pose}))).get_summary()
    >>> sorted(c.topic for c in summary.channels.values())
    ['/events', '/robot_1/pose', '/robot_2/pose', '/tf']
    >>> summary.statistics.message_count, summary.statistics.message_end_time
    (10, 1000000000)
    """
    t = np.asarray(arrays["t"], dtype=np.float64)
    pose = np.asarray(arrays["pose"], dtype=np.float64)
    n_samples, n = pose.shape[:2]
    times = [round(float(s) * 1e9) for s in t]
    context = foxglove.Context()
    buffer = io.BytesIO()
    writer = foxglove.open_mcap(buffer, context=context)
    try:
        tf = ch.FrameTransformsChannel("/tf", context=context)
        poses = [ch.PoseInFrameChannel(f"/robot_{i + 1}/pose", context=context) for i in range(n)]
        estimates: dict[str, list[ch.PoseInFrameChannel]] = {}
        points: dict[str, ch.PosesInFrameChannel] = {}
        scans: dict[str, list[ch.LaserScanChannel]] = {}
        signals: list[str] = []
        thermal: tuple[str, list[ch.RawImageChannel]] | None = None
        for name, value in arrays.items():
            a = np.asarray(value)
            timed = a.ndim >= 1 and a.shape[0] == n_samples and a.dtype.kind in "fiub"
            if name in _LAYERED or not timed:
                continue
            if "thermal" in name and a.ndim in (3, 4):
                topics = [f"/robot_{i + 1}/thermal" for i in range(n if a.ndim == 4 else 1)]
                thermal = (name, [ch.RawImageChannel(tp, context=context) for tp in topics])
            elif "pose" in name and a.shape[1:] == (n, 3):
                estimates[name] = [
                    ch.PoseInFrameChannel(f"/robot_{i + 1}/{name}", context=context)
                    for i in range(n)
                ]
            elif name.endswith("_xy_m") and a.shape[-1] == 2 and a.ndim in (2, 3):
                points[name] = ch.PosesInFrameChannel(f"/points/{name}", context=context)
            else:
                signals.append(name)
        for name in RANGE_NAMES:
            if name in arrays:
                scans[name] = [
                    ch.LaserScanChannel(f"/robot_{i + 1}/{name}", context=context) for i in range(n)
                ]
        signal_channel = (
            foxglove.Channel(
                "/signals",
                schema={"type": "object", "title": "firefleet.Signals"},
                message_encoding="json",
                context=context,
            )
            if signals
            else None
        )
        events = ch.LogChannel("/events", context=context)
        name = str((document or {}).get("scenario", "run"))
        events.log(
            fm.Log(
                timestamp=_stamp(0.0),
                level=fm.LogLevel.Info,
                name=name,
                message=f"{name}: {n} robot(s), {t[-1]:g} s",
            ),
            log_time=0,
        )
        if scene:
            ch.SceneUpdateChannel("/scene", context=context).log(_scene(scene, 0), log_time=0)
        grid_name = next((g for g in ("occupancy", "map") if g in arrays), None)
        if grid_name is not None:
            cells = np.asarray(arrays[grid_name])
            cells = cells[-1] if cells.ndim == 3 else cells
            resolution = float(np.asarray(arrays.get("map_resolution_m", 0.05)).reshape(-1)[0])
            origin = np.asarray(arrays.get("map_origin_m", (0.0, 0.0)), dtype=np.float64).reshape(
                -1
            )
            ch.GridChannel("/map", context=context).log(
                _grid(cells, resolution, origin), log_time=0
            )
        for k in range(n_samples):
            stamp, log_time = _stamp(float(t[k])), times[k]
            frames = []
            for i in range(n):
                x, y, theta = (float(v) for v in pose[k, i])
                position, orientation = _parts(x, y, theta)
                p = fm.Pose(position=position, orientation=orientation)
                poses[i].log(
                    fm.PoseInFrame(timestamp=stamp, frame_id="world", pose=p), log_time=log_time
                )
                frames.append(
                    fm.FrameTransform(
                        timestamp=stamp,
                        parent_frame_id="world",
                        child_frame_id=f"robot_{i + 1}",
                        translation=position,
                        rotation=orientation,
                    )
                )
            tf.log(fm.FrameTransforms(transforms=frames), log_time=log_time)
            for est_name, est_channels in estimates.items():
                e = np.asarray(arrays[est_name])[k]
                for i in range(n):
                    est_channels[i].log(
                        fm.PoseInFrame(
                            timestamp=stamp, frame_id="world", pose=_pose(*(float(v) for v in e[i]))
                        ),
                        log_time=log_time,
                    )
            for pt_name, pt_channel in points.items():
                xy = np.asarray(arrays[pt_name])[k].reshape(-1, 2)
                pt_channel.log(
                    fm.PosesInFrame(
                        timestamp=stamp,
                        frame_id="world",
                        poses=[_pose(float(a), float(b), 0.0) for a, b in xy],
                    ),
                    log_time=log_time,
                )
            for scan_name, scan_channels in scans.items():
                r = np.asarray(arrays[scan_name], dtype=np.float64)[k].reshape(n, -1)
                beams = r.shape[1]
                angles = arrays.get(f"{scan_name.removesuffix('_range_m')}_angle_rad")
                span = (
                    (float(np.min(angles)), float(np.max(angles)))
                    if angles is not None
                    else ((0.0, 0.0) if beams == 1 else (-math.pi, math.pi * (1 - 2 / beams)))
                )
                for i in range(n):
                    scan_channels[i].log(
                        fm.LaserScan(
                            timestamp=stamp,
                            frame_id=f"robot_{i + 1}",
                            pose=_pose(0.0, 0.0, 0.0),
                            start_angle=span[0],
                            end_angle=span[1],
                            ranges=[float(v) for v in r[i]],
                        ),
                        log_time=log_time,
                    )
            if thermal is not None:
                frames_k = np.asarray(arrays[thermal[0]], dtype=np.float32)[k]
                frames_k = frames_k[None] if frames_k.ndim == 2 else frames_k
                for i, image_channel in enumerate(thermal[1]):
                    image = np.ascontiguousarray(frames_k[i])
                    image_channel.log(
                        fm.RawImage(
                            timestamp=stamp,
                            frame_id=f"robot_{i + 1}",
                            width=int(image.shape[1]),
                            height=int(image.shape[0]),
                            encoding="32FC1",
                            step=int(image.shape[1] * 4),
                            data=image.tobytes(),
                        ),
                        log_time=log_time,
                    )
            if signal_channel is not None:
                sample = {s: np.asarray(arrays[s])[k].tolist() for s in signals}
                signal_channel.log(_finite(sample), log_time=log_time)
        for claim in (document or {}).get("claims", []):
            passed = bool(claim.get("passed"))
            events.log(
                fm.Log(
                    timestamp=_stamp(float(t[-1])),
                    level=fm.LogLevel.Info if passed else fm.LogLevel.Error,
                    name=name,
                    message=f"claim {claim.get('name')}: expected {claim.get('expected')}, "
                    f"measured {claim.get('measured')}: {'passed' if passed else 'FAILED'}",
                ),
                log_time=times[-1],
            )
    finally:
        writer.close()
    return buffer.getvalue()


def _finite(value: Any) -> Any:
    """NaN and infinities as None (JSON has no such numbers)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, list):
        return [_finite(v) for v in value]
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    return value
