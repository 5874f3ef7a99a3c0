"""Simulated thermal camera: what a robot-mounted Lepton sees of walls, fires and people.

A ray caster (deliverable section 2.7.1: FLIR Lepton, 80 x 60 pixels, 51 degree
horizontal field of view, NETD under 50 mK). The world is a floor (z = 0), an optional
ceiling, vertical walls (2-D segments extruded from the floor to ``wall_height_m``) and
objects: upright rectangles (fires, people) of a given width and height standing on
the floor, always facing the camera (a person or a pool fire looks about as wide from
every side). Each pixel is the mean band radiance (8-14 um) of ``supersample^2`` rays
through it, so objects that fill part of a pixel blend as a microbolometer blends them;
then optional optical blur, column fixed-pattern offsets, temporal noise (NETD),
clipping to the camera's scene range and quantisation to TLinear counts.

Ground truth for an object at ``(ox, oy)`` seen from pose ``(x, y, theta)``: bearing
``atan2(oy - y, ox - x) - theta`` (positive left), range ``hypot(ox - x, oy - y)``
(horizontal, to the object's centre line).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
import scipy.ndimage as ndi
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError, as_float_array, check_fields
from firefleet.perception.thermal import CameraModel, band_radiance, radiance_to_celsius
from firefleet.sim._thermal_grid import (
    GridThermalScene,
    grid_thermal_celsius,
    grid_thermal_frames,
)
from firefleet.world import OccupancyGrid

__all__ = [
    "GridThermalScene",
    "ThermalCameraParams",
    "ThermalScene",
    "render_thermal",
    "render_thermal_grid",
    "render_thermal_grid_depth",
]


_MAX_WORK = 6_000_000
"""Ray-primitive pairs handled at once (bounds the memory of one batch)."""


@dataclass(frozen=True)
class ThermalScene:
    """A world of known temperatures.

    Attributes
    ----------
    walls_m : ndarray, shape (M, 4)
        Wall segments ``x0, y0, x1, y1`` [m].
    wall_temp_c : ndarray, shape (M,)
        Wall temperatures [C].
    object_xy_m : ndarray, shape (K, 2)
        Object centres on the floor [m].
    object_size_m : ndarray, shape (K, 2)
        Object width and height [m].
    object_temp_c : ndarray, shape (K,)
        Object temperatures [C].
    wall_height_m : float
        Height of the walls [m].
    floor_c : float
        Floor temperature [C].
    ceiling_c : float or None
        Ceiling temperature [C], at ``wall_height_m``; ``None``: open sky above.
    sky_c : float
        Apparent temperature of whatever no ray hits [C] (a clear sky is cold).

    Examples
    --------
    >>> from firefleet.sim.sensors import ThermalScene
    >>> scene = ThermalScene(walls_m=[[0.0, -1.0, 0.0, 1.0]], wall_temp_c=[30.0])
    >>> scene.walls_m.shape, scene.object_xy_m.shape, scene.floor_c
    ((1, 4), (0, 2), 20.0)
    """

    walls_m: FloatArray = field(default_factory=lambda: np.zeros((0, 4)))
    wall_temp_c: FloatArray = field(default_factory=lambda: np.zeros(0))
    object_xy_m: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    object_size_m: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    object_temp_c: FloatArray = field(default_factory=lambda: np.zeros(0))
    wall_height_m: float = 2.5
    floor_c: float = 20.0
    ceiling_c: float | None = 22.0
    sky_c: float = -20.0

    def __post_init__(self) -> None:
        walls = as_float_array(self.walls_m, "scene.walls_m", (None, 4))
        m = walls.shape[0]
        objects = as_float_array(self.object_xy_m, "scene.object_xy_m", (None, 2))
        k = objects.shape[0]
        object.__setattr__(self, "walls_m", walls)
        object.__setattr__(
            self, "wall_temp_c", as_float_array(self.wall_temp_c, "scene.wall_temp_c", (m,))
        )
        object.__setattr__(self, "object_xy_m", objects)
        size = as_float_array(self.object_size_m, "scene.object_size_m", (k, 2))
        if np.any(size <= 0):
            raise InputError("scene.object_size_m must be > 0")
        object.__setattr__(self, "object_size_m", size)
        object.__setattr__(
            self, "object_temp_c", as_float_array(self.object_temp_c, "scene.object_temp_c", (k,))
        )
        check_fields(self, "scene", positive=("wall_height_m",))
        temps = [self.floor_c, self.sky_c, *self.wall_temp_c, *self.object_temp_c]
        if self.ceiling_c is not None:
            temps.append(self.ceiling_c)
        band_radiance(np.array(temps))  # raises on a temperature out of range


@dataclass(frozen=True)
class ThermalCameraParams:
    """The camera and its mount.

    Attributes
    ----------
    camera : CameraModel
        Optics (default: Lepton, 80 x 60, 51 degree HFOV).
    mount_height_m : float
        Height of the optical centre above the floor [m]; the axis is horizontal.
    netd_k : float
        Temporal noise, 1 sigma [K] (Lepton: < 0.05).
    column_fpn_k : float
        Column fixed-pattern offsets, 1 sigma [K], fixed by ``fpn_seed``.
    fpn_seed : int
        Seed of the column offsets (one camera, one pattern).
    psf_sigma_px : float
        Gaussian optical blur [px] applied in radiance (0: none).
    supersample : int
        Rays per pixel along each axis.
    min_c, max_c : float
        Scene range of the camera [C]: readings clip here (Lepton 3.5 low gain:
        up to about 400-450 C).
    resolution_k : float
        Quantisation step [K] (TLinear: 0.01); 0 for none.

    Examples
    --------
    >>> from firefleet.sim.sensors import ThermalCameraParams
    >>> params = ThermalCameraParams(column_fpn_k=0.0)
    >>> params.column_offsets_k.shape, float(abs(params.column_offsets_k).max())
    ((80,), 0.0)
    """

    camera: CameraModel = field(default_factory=CameraModel)
    mount_height_m: float = 0.5
    netd_k: float = 0.05
    column_fpn_k: float = 0.1
    fpn_seed: int = 0
    psf_sigma_px: float = 0.0
    supersample: int = 4
    min_c: float = -10.0
    max_c: float = 450.0
    resolution_k: float = 0.01

    def __post_init__(self) -> None:
        check_fields(
            self,
            "thermal_camera",
            positive=("mount_height_m", "supersample"),
            non_negative=("netd_k", "column_fpn_k", "psf_sigma_px", "resolution_k"),
        )
        if not self.min_c < self.max_c:
            raise InputError("thermal_camera.min_c must be below max_c")

    @property
    def column_offsets_k(self) -> FloatArray:
        """The camera's column offsets [K], shape (W,)."""
        return _column_offsets(self.fpn_seed, self.column_fpn_k, self.camera.width_px).copy()


@functools.lru_cache(maxsize=16)
def _column_offsets(seed: int, sigma_k: float, width_px: int) -> FloatArray:
    """A camera's column offsets (drawn once per seed, spread and width)."""
    return np.random.default_rng(seed).normal(0.0, sigma_k, width_px)


def _hit_segments(
    origin: FloatArray,
    d: FloatArray,
    p0: FloatArray,
    p1: FloatArray,
    z_lo: FloatArray,
    z_hi: FloatArray,
    h: float,
) -> FloatArray:
    """Ray parameter of the hit on vertical rectangles (``inf`` for a miss).

    origin (N, 1, 2); d (N, R, 3); p0, p1 (N, K, 2); z_lo, z_hi (N, K). Returns (N, R, K).
    """
    e = p1 - p0  # (N, K, 2)
    dx, dy = d[..., 0:1], d[..., 1:2]  # (N, R, 1)
    ex, ey = e[:, None, :, 0], e[:, None, :, 1]  # (N, 1, K)
    wx = p0[:, None, :, 0] - origin[:, :, None, 0]
    wy = p0[:, None, :, 1] - origin[:, :, None, 1]
    den = dx * ey - dy * ex  # cross(d, e)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (wx * ey - wy * ex) / den
        u = (wx * dy - wy * dx) / den
    z = h + t * d[..., 2:3]
    ok = (t > 1e-9) & (u >= 0) & (u <= 1) & (z >= z_lo[:, None, :]) & (z <= z_hi[:, None, :])
    return np.where(ok, t, np.inf)


def render_thermal(
    scene: ThermalScene,
    poses: ArrayLike,
    params: ThermalCameraParams | None = None,
    *,
    rng: np.random.Generator,
) -> FloatArray:
    """Frames [C] that the camera on each robot sees.

    Parameters
    ----------
    scene : ThermalScene
        The world.
    poses : array_like, shape (N, 3)
        Robot poses ``x [m], y [m], theta [rad]``; the camera looks along theta.
    params : ThermalCameraParams
        Camera, mount and noise (default: a Lepton at 0.5 m).
    rng : numpy.random.Generator, keyword-only
        Source of the temporal noise.

    Returns
    -------
    ndarray, shape (N, H, W)
        Apparent temperatures [C] as the camera reports them.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.sensors import ThermalCameraParams, ThermalScene, render_thermal
    >>> box = [[-5, -5, 5, -5], [5, -5, 5, 5], [5, 5, -5, 5], [-5, 5, -5, -5]]
    >>> scene = ThermalScene(walls_m=box, wall_temp_c=[25.0] * 4, floor_c=25.0, ceiling_c=25.0)
    >>> quiet = ThermalCameraParams(netd_k=0.0, column_fpn_k=0.0, resolution_k=0.0)
    >>> frames = render_thermal(scene, [[0.0, 0.0, 0.0]], quiet, rng=np.random.default_rng(0))
    >>> frames.shape, round(float(frames.min()), 6), round(float(frames.max()), 6)
    ((1, 60, 80), 25.0, 25.0)
    """
    prm = ThermalCameraParams() if params is None else params
    pose = as_float_array(poses, "poses", (None, 3))
    cam = prm.camera
    s = prm.supersample
    h_px, w_px = cam.height_px, cam.width_px
    sub = (np.arange(s) + 0.5) / s - 0.5
    rows = (np.arange(h_px)[:, None] + sub[None, :]).reshape(-1)
    cols = (np.arange(w_px)[:, None] + sub[None, :]).reshape(-1)
    rr, cc = np.meshgrid(rows, cols, indexing="ij")  # (H s, W s)
    xn, yn = cam.normalized(rr.reshape(-1), cc.reshape(-1))
    n_rays = xn.size
    n_prims = scene.walls_m.shape[0] + scene.object_xy_m.shape[0]
    chunk = max(1, _MAX_WORK // max(n_rays * max(n_prims, 1), 1))
    out = np.empty((pose.shape[0], h_px, w_px))
    for start in range(0, pose.shape[0], chunk):
        block = pose[start : start + chunk]
        out[start : start + chunk] = (
            _render_radiance(scene, block, xn, yn, prm)
            .reshape(-1, h_px, s, w_px, s)
            .mean(axis=(2, 4))
        )
    return _camera_output(out, prm, rng)


def _camera_output(
    radiance: FloatArray, prm: ThermalCameraParams, rng: np.random.Generator
) -> FloatArray:
    """The camera's reading [C] of pixel radiances (N, H, W): optical blur, column
    offsets, temporal noise, the scene range's clip and the TLinear quantisation."""
    out = radiance
    if prm.psf_sigma_px > 0:
        out = ndi.gaussian_filter(
            out, sigma=(0, prm.psf_sigma_px, prm.psf_sigma_px), mode="nearest"
        )
    temp = radiance_to_celsius(out)
    temp = temp + prm.column_offsets_k[None, None, :]
    if prm.netd_k > 0:
        temp = temp + rng.normal(0.0, prm.netd_k, temp.shape)
    temp = np.clip(temp, prm.min_c, prm.max_c)
    if prm.resolution_k > 0:
        temp = np.round(temp / prm.resolution_k) * prm.resolution_k
    return np.asarray(temp, dtype=np.float64)


@functools.lru_cache(maxsize=16)
def _ray_grid(prm: ThermalCameraParams) -> tuple[FloatArray, FloatArray]:
    """Normalised coordinates of the ``supersample^2`` rays of every pixel: ``xn`` of the
    (W s) sub-columns and ``yn`` of the (H s) sub-rows (an undistorted camera); made once
    per camera (every frame of a run casts the same rays; not to be written to)."""
    cam = prm.camera
    s = prm.supersample
    sub = (np.arange(s) + 0.5) / s - 0.5
    rows = (np.arange(cam.height_px)[:, None] + sub[None, :]).reshape(-1)
    cols = (np.arange(cam.width_px)[:, None] + sub[None, :]).reshape(-1)
    xn, _ = cam.normalized(np.zeros_like(cols), cols)
    _, yn = cam.normalized(rows, np.zeros_like(rows))
    return xn, yn


def render_thermal_grid(
    poses: ArrayLike,
    grid: OccupancyGrid,
    temperature_c: ArrayLike,
    burning: ArrayLike,
    people_xy_m: ArrayLike,
    params: ThermalCameraParams | None = None,
    *,
    rng: np.random.Generator,
    scene: GridThermalScene | None = None,
) -> FloatArray:
    """Frames [C] that the camera on each robot sees of a grid world and its heat field.

    The grid's occupied cells are walls; every open cell shows the heat field's
    temperature on its floor, its ceiling and the wall faces next to it; burning cells
    hold flames; people lie on the floor at body temperature (see
    :class:`~firefleet.sim._thermal_grid.GridThermalScene`). Smoke is not an input: the
    8-14 um band passes it. Then the camera of :func:`render_thermal` (blur, column
    offsets, NETD, clip, quantisation).

    Parameters
    ----------
    poses : array_like, shape (N, 3)
        Robot poses ``x [m], y [m], theta [rad]``; the camera looks along theta.
    grid : OccupancyGrid
        The building (any resolution: the mission's field grid is 0.25 m).
    temperature_c : array_like, shape (H, W)
        The heat field [C] on ``grid``.
    burning : array_like of bool, shape (H, W)
        Burning cells.
    people_xy_m : array_like, shape (V, 2)
        People on the floor [m].
    params : ThermalCameraParams
        Camera, mount and noise (default: a Lepton at 0.5 m); an undistorted camera.
    rng : numpy.random.Generator, keyword-only
        Source of the temporal noise.
    scene : GridThermalScene, keyword-only
        Wall, flame and person sizes.

    Returns
    -------
    ndarray, shape (N, H_px, W_px)
        Apparent temperatures [C] as the camera reports them.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.sensors import ThermalCameraParams, render_thermal_grid
    >>> from firefleet.world import OccupancyGrid
    >>> walls = np.zeros((20, 20), dtype=bool)
    >>> walls[[0, -1], :] = walls[:, [0, -1]] = True
    >>> room = OccupancyGrid(walls, ~walls, resolution_m=0.25)
    >>> quiet = ThermalCameraParams(netd_k=0.0, column_fpn_k=0.0, resolution_k=0.0)
    >>> frames = render_thermal_grid(
    ...     [[2.5, 2.5, 0.0]], room, np.full((20, 20), 25.0), np.zeros((20, 20), bool),
    ...     np.zeros((0, 2)), quiet, rng=np.random.default_rng(0))
    >>> frames.shape, round(float(frames.min()), 6), round(float(frames.max()), 6)
    ((1, 60, 80), 25.0, 25.0)
    """
    frames, _ = render_thermal_grid_depth(
        poses, grid, temperature_c, burning, people_xy_m, params, rng=rng, scene=scene
    )
    return frames


def render_thermal_grid_depth(
    poses: ArrayLike,
    grid: OccupancyGrid,
    temperature_c: ArrayLike,
    burning: ArrayLike,
    people_xy_m: ArrayLike,
    params: ThermalCameraParams | None = None,
    *,
    rng: np.random.Generator,
    scene: GridThermalScene | None = None,
) -> tuple[FloatArray, FloatArray]:
    """:func:`render_thermal_grid`'s frames and, registered to them, each pixel's depth
    along the optical axis [m] (its central ray's; NaN where nothing is on the grid):
    what a stereo rig aligned with the thermal camera measures, noise-free (the caller
    adds its noise).

    Returns
    -------
    frames : ndarray, shape (N, H_px, W_px)
    depth_m : ndarray, shape (N, H_px, W_px)
    """
    prm = ThermalCameraParams() if params is None else params
    if prm.camera.distorted:
        raise InputError("thermal_camera.camera: the grid renderer takes an undistorted camera")
    xn, yn = _ray_grid(prm)
    s = prm.supersample
    h_px, w_px = prm.camera.height_px, prm.camera.width_px
    grid_scene = GridThermalScene() if scene is None else scene
    if prm.psf_sigma_px == 0:  # the whole camera in one compiled pass
        n = as_float_array(poses, "poses", (None, 3)).shape[0]
        noise = (
            rng.normal(0.0, prm.netd_k, (n, h_px, w_px))
            if prm.netd_k > 0
            else np.zeros((n, h_px, w_px))
        )
        return grid_thermal_frames(
            poses,
            grid,
            temperature_c,
            burning,
            people_xy_m,
            xn,
            yn,
            s,
            prm.mount_height_m,
            grid_scene,
            (prm.column_offsets_k, noise, prm.min_c, prm.max_c, prm.resolution_k),
        )
    temps, depth = grid_thermal_celsius(
        poses, grid, temperature_c, burning, people_xy_m, xn, yn, prm.mount_height_m, grid_scene
    )
    n = temps.shape[0]
    radiance = band_radiance(temps).reshape(n, h_px, s, w_px, s).mean(axis=(2, 4))
    centre = depth.reshape(n, h_px, s, w_px, s)[:, :, s // 2, :, s // 2]
    return _camera_output(radiance, prm, rng), np.where(np.isfinite(centre), centre, np.nan)


def _render_radiance(
    scene: ThermalScene, pose: FloatArray, xn: FloatArray, yn: FloatArray, prm: ThermalCameraParams
) -> FloatArray:
    """Band radiance of every ray for a block of poses, shape (N, R)."""
    h = prm.mount_height_m
    n = pose.shape[0]
    ct, st = np.cos(pose[:, 2:3]), np.sin(pose[:, 2:3])  # (N, 1)
    # camera frame (x right, y down, z forward) to world: forward (c, s, 0), right (s, -c, 0)
    d = np.stack(
        [ct + xn[None, :] * st, st - xn[None, :] * ct, np.broadcast_to(-yn, (n, xn.size))], axis=-1
    )  # (N, R, 3)
    origin = pose[:, None, :2]  # (N, 1, 2)
    best_t = np.full(d.shape[:2], np.inf)
    best_temp = np.full(d.shape[:2], scene.sky_c)
    dz = d[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        t_floor = np.where(dz < 0, -h / dz, np.inf)
        t_ceil = (
            np.where(dz > 0, (scene.wall_height_m - h) / dz, np.inf)
            if scene.ceiling_c is not None
            else np.full_like(dz, np.inf)
        )
    for t_plane, temp in ((t_floor, scene.floor_c), (t_ceil, scene.ceiling_c)):
        closer = t_plane < best_t
        best_t = np.where(closer, t_plane, best_t)
        best_temp = np.where(closer, temp if temp is not None else scene.sky_c, best_temp)
    prims: list[tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]] = []
    m = scene.walls_m.shape[0]
    if m:
        w = np.broadcast_to(scene.walls_m, (n, m, 4))
        prims.append(
            (
                w[..., :2],
                w[..., 2:],
                np.zeros((n, m)),
                np.full((n, m), scene.wall_height_m),
                np.broadcast_to(scene.wall_temp_c, (n, m)),
            )
        )
    k = scene.object_xy_m.shape[0]
    if k:
        centre = np.broadcast_to(scene.object_xy_m, (n, k, 2))
        view = centre - pose[:, None, :2]
        dist = np.linalg.norm(view, axis=-1, keepdims=True)
        perp = np.stack([-view[..., 1], view[..., 0]], axis=-1) / np.maximum(dist, 1e-9)
        half = 0.5 * scene.object_size_m[None, :, 0:1] * perp
        prims.append(
            (
                centre - half,
                centre + half,
                np.zeros((n, k)),
                np.broadcast_to(scene.object_size_m[:, 1], (n, k)),
                np.broadcast_to(scene.object_temp_c, (n, k)),
            )
        )
    for p0, p1, z_lo, z_hi, temps in prims:
        t = _hit_segments(origin, d, p0, p1, z_lo, z_hi, h)  # (N, R, K)
        j = np.argmin(t, axis=-1)
        t_min = np.take_along_axis(t, j[..., None], axis=-1)[..., 0]
        closer = t_min < best_t
        best_t = np.where(closer, t_min, best_t)
        best_temp = np.where(closer, np.take_along_axis(temps, j, axis=-1), best_temp)
    return band_radiance(best_temp)
