"""A run's arrays as the dashboard draws them: layers found by name, not by kind.

The run page draws whatever a run recorded, so that a new task kind shows up without a
change here. An array is put on a layer by its name and shape (T samples, N robots):

=================================  ====================  ================================
name                               shape                 layer
=================================  ====================  ================================
``pose``                           (T, N, 3)             the robots (true poses)
any other ``*pose*``               (T, N, 3)             estimated poses (dashed)
``*_xy_m``                         (T, N, 2) or (T, 2)   points: desired, formation, leader
``*landmark*``                     (K, 2) or (T, K, 2)   landmarks
``*particle*``                     (T, P, 2+) or         the particle cloud
                                   (T, N, P, 2+)
``occupancy`` / ``map``            (H, W) or (T, H, W)   the map (``map_resolution_m``,
                                                         ``map_origin_m`` beside it)
``lidar_range_m``,                 (T, N, B) or (T, N)   range rays (``<name>`` with
``ultrasonic_range_m``                                   ``_angle_rad`` for the bearings)
``*thermal*``                      (T, H, W) or          the thermal frame (false colour)
                                   (T, N, H, W)
anything else                      (T, N) or (T, N, 2)   a time plot
=================================  ====================  ================================

Besides the recorded arrays, every run gets ``v_m_s`` and ``omega_rad_s`` from the true
poses (finite differences), and the scenario's static geometry (:mod:`.scene`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from firefleet._typing import FloatArray

__all__ = ["MAX_VALUES", "layers", "to_list"]

MAX_VALUES = 400_000
"""About the most numbers a run's poses send to the browser (more samples are thinned)."""

MAX_FRAMES = 60
"""Thermal frames sent at most."""

RANGE_NAMES = ("lidar_range_m", "ultrasonic_range_m")


def to_list(array: Any, decimals: int = 4) -> Any:
    """An array as nested lists for JSON, rounded, NaN and infinities as None.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.serve.replay import to_list
    >>> to_list(np.array([[1.234567, np.nan], [np.inf, 2.0]]), decimals=2)
    [[1.23, None], [None, 2.0]]
    """
    a = np.asarray(array, dtype=np.float64)
    a = np.round(a, decimals)
    if np.all(np.isfinite(a)):
        return a.tolist()
    out = a.astype(object)
    out[~np.isfinite(a)] = None
    return out.tolist()


def _thin(n_samples: int, per_sample: int) -> np.ndarray:
    """Sample indices kept: at most MAX_VALUES numbers, first and last always kept."""
    cap = max(2, min(4000, MAX_VALUES // max(per_sample, 1)))
    if n_samples <= cap:
        return np.arange(n_samples)
    return np.unique(np.linspace(0, n_samples - 1, cap).round().astype(np.int64))


def _speeds(t: FloatArray, pose: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Speed [m/s] and turn rate [rad/s] (T, N) from the poses, by finite differences
    (the turn rate NaN below 1 cm/s)."""
    if t.size < 2:
        zero = np.zeros(pose.shape[:2])
        return zero, zero
    dt_s = np.diff(t)[:, None]
    dt_s = np.where(dt_s > 0, dt_s, np.nan)
    step = np.diff(pose[:, :, :2], axis=0)
    v = np.hypot(step[..., 0], step[..., 1]) / dt_s
    dth = np.angle(np.exp(1j * np.diff(pose[:, :, 2], axis=0))) / dt_s
    dth[v < 0.01] = np.nan  # a heading barely moving (a point mass at rest) turns at random
    return np.vstack([v[:1], v]), np.vstack([dth[:1], dth])


def _map_layer(arrays: Mapping[str, np.ndarray]) -> dict[str, Any] | None:
    name = next((n for n in ("occupancy", "map") if n in arrays), None)
    if name is None:
        return None
    grid = np.asarray(arrays[name], dtype=np.float64)
    if grid.ndim == 3:
        grid = grid[-1]
    if grid.ndim != 2:
        return None
    resolution = float(np.asarray(arrays.get("map_resolution_m", 0.05)).reshape(-1)[0])
    origin = np.asarray(arrays.get("map_origin_m", (0.0, 0.0)), dtype=np.float64).reshape(-1)
    if grid.size > 1_000_000:  # a coarser copy for the browser
        k = math.ceil(math.sqrt(grid.size / 1_000_000))
        grid = grid[: grid.shape[0] // k * k, : grid.shape[1] // k * k]
        grid = grid.reshape(grid.shape[0] // k, k, grid.shape[1] // k, k).max(axis=(1, 3))
        resolution *= k
    if np.nanmax(grid, initial=0.0) > 1.0:  # 0..100 occupancy percentages
        grid = grid / 100.0
    return {
        "name": name,
        "cells": to_list(grid, 2),
        "resolution_m": resolution,
        "origin_m": to_list(origin[:2]),
    }


def _ranges(arrays: Mapping[str, np.ndarray], keep: np.ndarray, n: int) -> list[dict[str, Any]]:
    out = []
    for name in RANGE_NAMES:
        if name not in arrays:
            continue
        r = np.asarray(arrays[name], dtype=np.float64)
        if r.ndim == 2:
            r = r[:, :, None]
        if r.ndim != 3 or r.shape[1] != n:
            continue
        beams = r.shape[2]
        angles = arrays.get(f"{name.removesuffix('_range_m')}_angle_rad")
        if angles is None:
            bearing = (
                np.zeros(1) if beams == 1 else np.linspace(-np.pi, np.pi, beams, endpoint=False)
            )
        else:
            bearing = np.asarray(angles, dtype=np.float64).reshape(-1, beams)[0]
        out.append({"name": name, "angle_rad": to_list(bearing), "range_m": to_list(r[keep], 3)})
    return out


def layers(
    arrays: Mapping[str, np.ndarray], scene: Mapping[str, Any] | None = None
) -> dict[str, Any]:
    """The JSON document a run page draws, from the run's arrays (by ``result.npz`` names).

    Parameters
    ----------
    arrays : mapping of str to ndarray
        At least ``t`` (T,) [s] and ``pose`` (T, N, 3) [m, m, rad].
    scene : mapping, optional
        The scenario's static geometry (:func:`firefleet.serve.scene.scene_of`).

    Returns
    -------
    dict
        ``t``, ``pose``, ``estimates``, ``points``, ``landmarks``, ``particles``,
        ``map``, ``ranges``, ``thermal``, ``series`` (name to (T, N) or (T, N, 2) lists),
        ``scene``; samples thinned to about :data:`MAX_VALUES` numbers, the last kept.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.serve.replay import layers
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> pose = np.zeros((11, 1, 3)); pose[:, 0, 0] = 2.0 * t  # 2 m/s along x
    >>> doc = layers({"t": t, "pose": pose, "y_err_m": np.zeros((11, 1))})
    >>> doc["pose"][-1], sorted(doc["series"]), doc["series"]["v_m_s"][-1]
    ([[2.0, 0.0, 0.0]], ['omega_rad_s', 'v_m_s', 'y_err_m'], [2.0])
    """
    t = np.asarray(arrays["t"], dtype=np.float64)
    pose = np.asarray(arrays["pose"], dtype=np.float64)
    n_samples, n = pose.shape[0], pose.shape[1]
    keep = _thin(n_samples, n * 3)
    v, omega = _speeds(t, pose)
    doc: dict[str, Any] = {
        "t": to_list(t[keep]),
        "pose": to_list(pose[keep]),
        "estimates": {},
        "points": {},
        "landmarks": {},
        "particles": {},
        "map": _map_layer(arrays),
        "ranges": _ranges(arrays, keep, n),
        "thermal": None,
        "series": {"v_m_s": to_list(v[keep]), "omega_rad_s": to_list(omega[keep])},
        "scene": dict(scene or {}),
    }
    layered = {"t", "pose", "occupancy", "map", "map_resolution_m", "map_origin_m"}
    layered |= {n_ for n_ in RANGE_NAMES} | {f"{n_[:-8]}_angle_rad" for n_ in RANGE_NAMES}
    for name, value in arrays.items():
        a = np.asarray(value)
        if name in layered or a.dtype.kind not in "fiub":
            continue
        timed = a.ndim >= 1 and a.shape[0] == n_samples
        if "thermal" in name and timed and a.ndim in (3, 4):
            frames = np.unique(
                np.linspace(0, n_samples - 1, min(MAX_FRAMES, n_samples)).astype(int)
            )
            doc["thermal"] = {
                "name": name,
                "t": to_list(t[frames]),
                "frames": to_list(a[frames], 1),
            }
        elif "landmark" in name and a.shape[-1] >= 2 and a.ndim in (2, 3):
            doc["landmarks"][name] = to_list(a[..., :2] if a.ndim == 2 else a[-1, :, :2])
        elif "particle" in name and timed and a.ndim in (3, 4) and a.shape[-1] >= 2:
            step = keep[:: max(1, keep.size // 200)]
            doc["particles"][name] = {"t": to_list(t[step]), "xy": to_list(a[step][..., :2], 3)}
        elif "pose" in name and timed and a.shape[1:] == (n, 3):
            doc["estimates"][name] = to_list(a[keep])
        elif name.endswith("_xy_m") and timed and a.shape[-1] == 2 and a.ndim in (2, 3):
            doc["points"][name] = to_list(a[keep][:, None, :] if a.ndim == 2 else a[keep])
        elif timed and a.ndim in (2, 3) and a.shape[1] == n and (a.ndim == 2 or a.shape[2] <= 3):
            doc["series"][name] = to_list(a[keep])
    return doc
