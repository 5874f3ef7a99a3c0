"""Reading a run's MCAP back into ``result.npz``'s arrays (for ``firefleet serve``)."""

from __future__ import annotations

import io
import json
import math
import re

import numpy as np
from mcap.reader import make_reader

from firefleet.mcap_log._proto import Fields, double, fields, message

__all__ = ["read_mcap"]


def _xy_theta(pose: Fields) -> tuple[float, float, float]:
    position, orientation = message(pose, 1), message(pose, 2)
    z, w = double(orientation, 3), double(orientation, 4)
    return double(position, 1), double(position, 2), 2.0 * math.atan2(z, w)


def read_mcap(data: bytes) -> dict[str, np.ndarray]:
    """A run's arrays from the bytes of its ``run.mcap`` (:func:`mcap_bytes`' topics).

    Reads the true and estimated poses, the points and the ``/signals``; the map,
    thermal frames and scans stay in the file (Foxglove shows them).

    Returns
    -------
    dict of str to ndarray
        ``t`` (T,) [s], ``pose`` (T, N, 3), and the other arrays by their names.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.mcap_log import mcap_bytes, read_mcap
    >>> t = np.array([0.0, 0.5]); pose = np.array([[[0.0, 1.0, 0.5]], [[1.0, 2.0, -3.0]]])
    >>> back = read_mcap(mcap_bytes({"t": t, "pose": pose, "y_err_m": np.ones((2, 1))}))
    >>> back["t"].tolist(), back["pose"].round(6).tolist()[1], back["y_err_m"].tolist()
    ([0.0, 0.5], [[1.0, 2.0, -3.0]], [[1.0], [1.0]])
    """
    poses: dict[str, dict[int, list[tuple[float, float, float]]]] = {}
    times: dict[int, list[int]] = {}
    points: dict[str, list[list[list[float]]]] = {}
    signals: list[dict[str, object]] = []
    robot_topic = re.compile(r"^/robot_(\d+)/(.+)$")
    for schema, channel, msg in make_reader(io.BytesIO(data)).iter_messages(log_time_order=True):
        name = schema.name if schema is not None else ""
        found = robot_topic.match(channel.topic)
        if name == "foxglove.PoseInFrame" and found:
            robot, array = int(found.group(1)) - 1, found.group(2)
            poses.setdefault(array, {}).setdefault(robot, []).append(
                _xy_theta(message(fields(msg.data), 3))
            )
            if array == "pose":
                times.setdefault(robot, []).append(msg.log_time)
        elif name == "foxglove.PosesInFrame" and channel.topic.startswith("/points/"):
            raw = fields(msg.data).get(3, [])
            xy = [list(_xy_theta(fields(p if isinstance(p, bytes) else b""))[:2]) for p in raw]
            points.setdefault(channel.topic.removeprefix("/points/"), []).append(xy)
        elif channel.topic == "/signals":
            signals.append(json.loads(msg.data))
    if "pose" not in poses:
        raise ValueError("run.mcap holds no /robot_<i>/pose messages")
    n = len(poses["pose"])
    out: dict[str, np.ndarray] = {"t": np.asarray(times[0], dtype=np.float64) / 1e9}
    for array, by_robot in poses.items():
        out[array] = np.stack([np.asarray(by_robot[i]) for i in range(n)], axis=1)
    for array, samples in points.items():
        out[array] = np.asarray(samples, dtype=np.float64)
    for key in signals[0] if signals else {}:
        out[key] = np.asarray([s[key] for s in signals], dtype=np.float64)
    return out
