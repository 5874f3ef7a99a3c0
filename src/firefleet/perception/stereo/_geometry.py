"""Depth, point clouds (PLY) and virtual range scans from disparity."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet._typing import Float32Array, FloatArray
from firefleet.errors import InputError, as_float_array
from firefleet.perception.stereo._images import (
    Image,
)


def depth_from_disparity(
    disparity: ArrayLike, *, focal_px: float, baseline_m: float, doffs_px: float = 0.0
) -> Float32Array:
    """Depth ``Z = f B / (d + d_offs)`` [m] from disparity [px].

    Parameters
    ----------
    disparity : array_like, shape (H, W)
        Disparity [px]; NaN where none.
    focal_px : float
        Focal length of the rectified cameras [px].
    baseline_m : float
        Baseline [m].
    doffs_px : float
        ``cx_right - cx_left`` of the rectified cameras [px] (Middlebury's ``doffs``).

    Returns
    -------
    ndarray of float32, shape (H, W)
        Depth [m]; NaN where the disparity is NaN or ``d + d_offs <= 0`` (at infinity).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import depth_from_disparity
    >>> disparity = np.array([[20.0, 0.0, np.nan]])
    >>> depth = depth_from_disparity(disparity, focal_px=600.0, baseline_m=0.1)
    >>> depth.tolist()  # f B / d: 600 * 0.1 / 20 = 3 m
    [[3.0, nan, nan]]
    """
    d = np.asarray(disparity, dtype=np.float32)
    if d.ndim != 2:
        raise InputError(f"disparity must have shape (H, W), got {d.shape}")
    for name, v in (("focal_px", focal_px), ("baseline_m", baseline_m)):
        if not (math.isfinite(v) and v > 0):
            raise InputError(f"{name} must be > 0, got {v}")
    if not math.isfinite(doffs_px):
        raise InputError(f"doffs_px must be finite, got {doffs_px}")
    den = d + np.float32(doffs_px)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.float32(focal_px * baseline_m) / den
    z[~(den > 0)] = np.nan
    return np.asarray(z, dtype=np.float32)


def point_cloud(
    disparity: ArrayLike,
    *,
    focal_px: float,
    baseline_m: float,
    cx_px: float,
    cy_px: float,
    doffs_px: float = 0.0,
    mask: ArrayLike | None = None,
    colors: ArrayLike | None = None,
) -> tuple[FloatArray, Image]:
    """3-D points of the left camera's pixels (section 2.7.2.1: one point per pixel).

    ``X = (x - cx) Z / f``, ``Y = (y - cy) Z / f``, ``Z`` from
    :func:`depth_from_disparity`, in the rectified left camera's frame (X right,
    Y down, Z forward) [m].

    Parameters
    ----------
    disparity : array_like, shape (H, W)
    mask : array_like of bool, shape (H, W), optional
        Pixels to keep (for example ``DisparityResult.measured``); NaN depths are
        always dropped.
    colors : ndarray of uint8, shape (H, W, 3) or (H, W), optional
        BGR (or grey) colours of the left image.

    Returns
    -------
    points : ndarray, shape (M, 3)
        [m].
    rgb : ndarray of uint8, shape (M, 3)
        Colours as RGB (grey 128 if none were given).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import point_cloud
    >>> disparity = np.full((3, 3), 20.0)
    >>> points, rgb = point_cloud(disparity, focal_px=600.0, baseline_m=0.1, cx_px=1.0, cy_px=1.0)
    >>> points.shape, points[4].round(6).tolist(), rgb[0].tolist()  # the centre pixel at 3 m
    ((9, 3), [0.0, 0.0, 3.0], [128, 128, 128])
    """
    z = depth_from_disparity(disparity, focal_px=focal_px, baseline_m=baseline_m, doffs_px=doffs_px)
    keep = ~np.isnan(z)
    if mask is not None:
        m = np.asarray(mask, dtype=bool)
        if m.shape != z.shape:
            raise InputError(f"mask must have shape {z.shape}, got {m.shape}")
        keep &= m
    ys, xs = np.nonzero(keep)
    zz = z[ys, xs].astype(np.float64)
    pts = np.column_stack([(xs - cx_px) * zz / focal_px, (ys - cy_px) * zz / focal_px, zz])
    if colors is None:
        rgb = np.full((len(ys), 3), 128, np.uint8)
    else:
        c = np.asarray(colors)
        if c.shape[:2] != z.shape or c.dtype != np.uint8:
            raise InputError(f"colors must be uint8 of shape {z.shape} (+ 3), got {c.shape}")
        sel = c[ys, xs]
        rgb = np.repeat(sel[:, None], 3, axis=1) if c.ndim == 2 else sel[:, ::-1]
    return pts, np.ascontiguousarray(rgb, dtype=np.uint8)


def ply_bytes(points: ArrayLike, colors: ArrayLike | None = None) -> bytes:
    """A binary little-endian PLY file of points with optional RGB colours.

    Vertex properties ``float x, y, z`` [m] and ``uchar red, green, blue``: the layout
    MeshLab, CloudCompare, Open3D and PCL read.

    Parameters
    ----------
    points : array_like, shape (M, 3)
    colors : array_like of uint8, shape (M, 3), optional
        RGB.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import ply_bytes
    >>> data = ply_bytes(np.zeros((2, 3)))
    >>> data.splitlines()[0], b"element vertex 2" in data
    (b'ply', True)
    """
    pts = as_float_array(points, "points", (None, 3))
    fields: list[tuple[str, str]] = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")]
    rgb = None
    if colors is not None:
        rgb = np.asarray(colors)
        if rgb.shape != pts.shape or rgb.dtype != np.uint8:
            raise InputError(f"colors must be uint8 of shape {pts.shape}, got {rgb.shape}")
        fields += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    rec = np.empty(len(pts), dtype=np.dtype(fields))
    for i, axis in enumerate("xyz"):
        rec[axis] = pts[:, i]
    if rgb is not None:
        for i, ch in enumerate(("red", "green", "blue")):
            rec[ch] = rgb[:, i]
    kinds = {"<f4": "float", "u1": "uchar"}
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment firefleet stereo point cloud, metres\n"
        f"element vertex {len(pts)}\n"
        + "".join(f"property {kinds[t]} {n}\n" for n, t in fields)
        + "end_header\n"
    )
    return header.encode("ascii") + rec.tobytes()


# ------------------------------------------------------------------ range scan


@dataclass(frozen=True, eq=False)
class RangeScan:
    """A virtual range scan: the nearest obstacle in each bearing sector.

    Attributes
    ----------
    bearing_rad : ndarray, shape (K,)
        Centre of each sector, from the optical axis, positive to the left [rad].
    edges_rad : ndarray, shape (K + 1,)
        Sector boundaries, increasing [rad].
    range_m : ndarray, shape (K,)
        Horizontal distance ``sqrt(X^2 + Z^2)`` to the nearest point in the sector
        [m]; ``inf`` where the sector holds no point.
    count : ndarray of int, shape (K,)
        Points in each sector.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import range_scan
    >>> scan = range_scan([[0.0, 0.0, 2.0]], n_sectors=4, fov_rad=np.pi / 2)
    >>> scan.bearing_rad.shape, scan.edges_rad.shape, scan.count.tolist()
    ((4,), (5,), [0, 0, 1, 0])
    """

    bearing_rad: FloatArray
    edges_rad: FloatArray
    range_m: FloatArray
    count: NDArray[np.int64]

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (``inf`` ranges become ``None`` through ``json_text``)."""
        return {
            "sectors": int(self.range_m.size),
            "bearing_rad": self.bearing_rad.tolist(),
            "edges_rad": self.edges_rad.tolist(),
            "range_m": self.range_m.tolist(),
            "points": self.count.tolist(),
        }


def range_scan(
    points: ArrayLike,
    *,
    n_sectors: int = 32,
    fov_rad: float,
    height_band_m: tuple[float, float] | None = None,
    max_range_m: float = math.inf,
    min_points: int = 1,
    min_share: float = 0.0,
) -> RangeScan:
    """The nearest obstacle distance in each of K bearing sectors (a virtual laser scan).

    Parameters
    ----------
    points : array_like, shape (M, 3)
        Points in the camera frame (X right, Y down, Z forward) [m].
    n_sectors : int
        K, sectors of equal width across the field of view.
    fov_rad : float
        Horizontal field of view, centred on the optical axis [rad]; for a pinhole
        camera ``2 atan(W / (2 f))``.
    height_band_m : tuple of float, optional
        ``(low, high)`` heights above the camera centre [m] (``-Y``) of the points that
        count as obstacles (for example from just above the floor to the robot's top).
    max_range_m : float
        Points farther than this are ignored [m].
    min_points : int
        A sector reports its ``min_points``-th nearest point (1: the nearest), so a
        few stray points do not make a phantom obstacle.
    min_share : float
        Or, if more, its ``ceil(min_share * n)``-th nearest of its ``n`` points (a
        cluster of bad matches scales with the points seen).

    Returns
    -------
    RangeScan

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.perception.stereo import range_scan
    >>> points = [[0.0, 0.0, 2.0], [0.1, 0.0, 3.0]]  # x right, y down, z ahead [m]
    >>> scan = range_scan(points, n_sectors=2, fov_rad=np.pi / 2)
    >>> scan.range_m.round(4).tolist(), scan.count.tolist()
    ([3.0017, 2.0], [1, 1])
    """
    pts = as_float_array(points, "points", (None, 3))
    if n_sectors < 1:
        raise InputError(f"n_sectors must be >= 1, got {n_sectors}")
    if not (0 < fov_rad < 2 * math.pi):
        raise InputError(f"fov_rad must be in (0, 2 pi), got {fov_rad}")
    if min_points < 1:
        raise InputError(f"min_points must be >= 1, got {min_points}")
    if not 0.0 <= min_share < 1.0:
        raise InputError(f"min_share must be in [0, 1), got {min_share}")
    edges = np.linspace(-fov_rad / 2, fov_rad / 2, n_sectors + 1)
    bearing = np.arctan2(-pts[:, 0], pts[:, 2])
    rng = np.hypot(pts[:, 0], pts[:, 2])
    keep = (pts[:, 2] > 0) & (rng <= max_range_m) & (bearing >= edges[0]) & (bearing < edges[-1])
    if height_band_m is not None:
        low, high = height_band_m
        if not low < high:
            raise InputError(f"height_band_m must be (low, high) with low < high, got {low, high}")
        up = -pts[:, 1]
        keep &= (up >= low) & (up <= high)
    sector = np.clip(np.searchsorted(edges, bearing[keep], side="right") - 1, 0, n_sectors - 1)
    r = rng[keep]
    order = np.lexsort((r, sector))
    sector, r = sector[order], r[order]
    count = np.bincount(sector, minlength=n_sectors).astype(np.int64)
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    ranges = np.full(n_sectors, np.inf)
    kth = np.maximum(min_points, np.ceil(min_share * count).astype(np.int64))
    has = count >= kth
    ranges[has] = r[start[has] + kth[has] - 1]
    return RangeScan(
        bearing_rad=0.5 * (edges[:-1] + edges[1:]), edges_rad=edges, range_m=ranges, count=count
    )
