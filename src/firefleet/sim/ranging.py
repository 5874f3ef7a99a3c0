"""Range sensors on a building map: an ultrasonic ring, a planar lidar, a stereo range scan.

Every sensor casts exact rays on the :class:`~firefleet.world.OccupancyGrid` (cell by
cell, Amanatides and Woo's traversal, compiled with numba: :mod:`._ranging_cast`) from
the robot's centre, for the whole team at once (poses (N, 3), readings (N, K)).
Occupied cells block a ray; free and unknown cells, and the space off the map, do not.
The other robots are discs of ``robot_radius_m`` that block too; a robot never sees
itself. Ranges are measured from the robot's centre [m]; ``inf`` means no return
within the sensor's maximum range (or, for the ultrasonic ring, a lost echo).

- **Ultrasonic ring** (:class:`UltrasonicParams`, HC-SR04-like): ``count`` sensors
  evenly around the robot, each reporting the nearest return inside its cone, found
  with ``rays_per_cone`` rays spread evenly across the cone (edges included), so a wall
  whose normal lies outside the cone is ranged exactly along the cone's edge and one
  whose normal lies inside within a factor ``1 / cos(spacing / 2)``. Gaussian noise;
  a reading nearer than ``min_range_m`` reads ``min_range_m``; the echo is lost
  (reading ``inf``) with a probability that rises with the incidence angle ``i``
  between the returning ray and the normal of the face it hit (a smooth surface at
  grazing incidence reflects the ping away):
  ``p = p0 + (1 - p0) / (1 + exp(-(i - i50) / w))``.
- **Lidar** (:class:`LidarParams`): ``beams`` rays evenly over the field of view,
  Gaussian noise.
- **Stereo range scan** (:class:`StereoScanParams`): what ``firefleet stereo``
  produces (:func:`firefleet.perception.stereo.range_scan`): the horizontal distance to
  the nearest obstacle in each of ``sectors`` equal bearing sectors across the
  camera's field of view ``2 atan(W / (2 f))``, here the least of ``rays_per_sector``
  rays across each sector. Depth noise is the stereo pair's:
  ``sigma_Z = Z^2 sigma_d / (f B)`` on the depth ``Z = r cos(bearing)``.

References
----------
.. [1] J. Amanatides, A. Woo, "A fast voxel traversal algorithm for ray tracing",
   Eurographics 1987.
.. [2] Elec Freaks, "HC-SR04 ultrasonic ranging module" data sheet: 2 cm to 4 m,
   15 degree measuring angle, 60 ms measurement cycle.
.. [3] D. Gallup et al., "Variable baseline/resolution stereo", CVPR 2008 (stereo depth
   error grows with depth squared: ``dZ = Z^2 dd / (f B)``).
.. [4] J. W. Starr, B. Y. Lattimer, "Evaluation of navigation sensors in fire smoke
   environments", Fire Technology 50, 2014 (lidar and stereo vision degrade in dense
   smoke; a thermal camera and radar see through it).

**Smoke** (optional ``smoke=`` :class:`SmokeField`, default None: no smoke, the same
ranges bit for bit): the lidar and the stereo scan see by visible or near-infrared
light, which the smoke dims by Beer-Lambert's law along each ray
(:mod:`._smoke_cast`). A ray whose optical depth reaches the sensor's limit
(``SmokeField.lidar`` / ``.stereo``, :class:`SmokeOptics`: two-way transmittance at
least 0.01 for the lidar, one-way contrast ``exp(-tau) >= exp(-3)`` for the stereo
pair) before it reaches the wall is a dropout: it reads as a miss (``inf``), the rule
of this model (no spurious return from the smoke itself). The ultrasonic ring takes no
``smoke``: sound's wavelength (about 8 mm at 40 kHz) is long against soot particles
(under a micrometre), which scatter it negligibly.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError, as_float_array
from firefleet.sim._ranging_cast import cast_team, clearance_cells
from firefleet.sim._ranging_params import LidarParams, StereoScanParams, UltrasonicParams
from firefleet.sim._smoke_cast import SmokeField, SmokeOptics, smoke_reach_team
from firefleet.world import OccupancyGrid

__all__ = [
    "LidarParams",
    "RangeSensors",
    "SmokeField",
    "SmokeOptics",
    "StereoScanParams",
    "UltrasonicParams",
    "lidar_scan",
    "stereo_scan",
    "ultrasonic_scan",
]


def _poses(poses: ArrayLike) -> FloatArray:
    return as_float_array(poses, "poses", (None, 3))


def _radius(robot_radius_m: float) -> float:
    if not (math.isfinite(robot_radius_m) and robot_radius_m >= 0.0):
        raise InputError(f"robot_radius_m must be a finite number >= 0, got {robot_radius_m}")
    return float(robot_radius_m)


@dataclass(frozen=True, eq=False)
class _AtPose:
    """What :meth:`RangeSensors.read` looks at of the team's drive: its true poses."""

    pose: FloatArray


_CLEARANCE: weakref.WeakKeyDictionary[OccupancyGrid, FloatArray] = weakref.WeakKeyDictionary()
"""Each grid's empty-space jumps (:func:`clearance_cells`), computed once per grid: a memo
of a pure function of an immutable map, dropped with the map."""


def _cast(
    grid: OccupancyGrid,
    poses: FloatArray,
    bearings: FloatArray,
    max_range_m: float,
    radius: float,
    smoke: SmokeField | None = None,
    optics: SmokeOptics | None = None,
) -> tuple[FloatArray, FloatArray]:
    clearance = _CLEARANCE.get(grid)
    if clearance is None:
        clearance = _CLEARANCE[grid] = clearance_cells(grid.occupied)
    r, cos_i = cast_team(
        grid.occupied,
        grid.resolution_m,
        grid.origin_m,
        poses,
        bearings,
        max_range_m,
        radius,
        clearance,
    )
    if smoke is not None and optics is not None:
        blind = smoke_reach_team(smoke, poses, bearings, max_range_m, optics)
        r = np.where(blind < r, np.inf, r)  # the smoke took the return: a dropout
    return r, cos_i


def lidar_scan(
    grid: OccupancyGrid,
    poses: ArrayLike,
    params: LidarParams,
    *,
    robot_radius_m: float,
    rng: np.random.Generator,
    smoke: SmokeField | None = None,
) -> FloatArray:
    """Lidar ranges of every robot: shape (N, B) [m], ``inf`` where nothing within range.

    Parameters
    ----------
    grid : OccupancyGrid
        The map (occupied cells block the beams).
    poses : array_like, shape (N, 3)
        True poses x [m], y [m], theta [rad].
    params : LidarParams
        Beam ``b`` points at ``theta + params.bearings_rad[b]``.
    robot_radius_m : float
        Radius of every robot's disc [m] (the others block the beams; 0: they do not).
    rng : numpy.random.Generator
        Draws the noise.
    smoke : SmokeField, optional
        Smoke dimming the beams (module notes); a beam it blinds before its return
        reads ``inf``. None: clear air.

    Returns
    -------
    ndarray, shape (N, B)
        Ranges from each robot's centre [m], noisy, in ``[0, max_range_m]``, or ``inf``.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.ranging import LidarParams, lidar_scan
    >>> from firefleet.world import OccupancyGrid
    >>> occupied = np.zeros((20, 20), dtype=bool)
    >>> occupied[:, 15] = True  # a wall at x = 1.5 m
    >>> grid = OccupancyGrid(occupied, ~occupied, resolution_m=0.1)
    >>> params = LidarParams(beams=4, noise_m=0.0)
    >>> lidar_scan(grid, [[0.5, 1.0, 0.0]], params, robot_radius_m=0.2,
    ...            rng=np.random.default_rng(0)).round(6).tolist()  # behind, right, ahead, left
    [[inf, inf, 1.0, inf]]
    """
    p = _poses(poses)
    r, _ = _cast(
        grid,
        p,
        params.bearings_rad,
        params.max_range_m,
        _radius(robot_radius_m),
        smoke,
        None if smoke is None else smoke.lidar,
    )
    if params.noise_m > 0.0:
        r = np.clip(r + params.noise_m * rng.standard_normal(r.shape), 0.0, params.max_range_m)
    return r


def ultrasonic_scan(
    grid: OccupancyGrid,
    poses: ArrayLike,
    params: UltrasonicParams,
    *,
    robot_radius_m: float,
    rng: np.random.Generator,
) -> FloatArray:
    """Ultrasonic ring readings of every robot: shape (N, K) [m], ``inf`` for no echo.

    Each sensor ``k`` looks along ``theta + params.bearings_rad[k]`` and reports the
    nearest return of the rays across its cone (``params.ray_offsets_rad``), plus
    Gaussian noise, at least ``min_range_m``, or ``inf`` when nothing lies within
    ``max_range_m`` or the echo was lost (probability
    ``params.dropout_probability(incidence)``, incidence of the returning ray).

    Parameters
    ----------
    grid : OccupancyGrid
    poses : array_like, shape (N, 3)
        True poses x [m], y [m], theta [rad].
    params : UltrasonicParams
    robot_radius_m : float
        Radius of every robot's disc [m].
    rng : numpy.random.Generator
        Draws the noise and the dropouts.

    Returns
    -------
    ndarray, shape (N, K)
        Ranges from each robot's centre [m].

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.ranging import UltrasonicParams, ultrasonic_scan
    >>> from firefleet.world import OccupancyGrid
    >>> occupied = np.zeros((20, 20), dtype=bool)
    >>> occupied[:, 15] = True  # a wall at x = 1.5 m
    >>> grid = OccupancyGrid(occupied, ~occupied, resolution_m=0.1)
    >>> params = UltrasonicParams(count=4, noise_m=0.0, dropout=0.0)
    >>> scan = ultrasonic_scan(grid, [[0.5, 1.0, 0.0]], params, robot_radius_m=0.2,
    ...                        rng=np.random.default_rng(0))
    >>> scan.round(6).tolist()  # ahead, left, behind, right
    [[1.0, inf, inf, inf]]
    """
    p = _poses(poses)
    n, k, m = p.shape[0], params.count, params.rays_per_cone
    rays = (params.bearings_rad[:, None] + params.ray_offsets_rad[None, :]).ravel()
    r, cos_i = _cast(grid, p, rays, params.max_range_m, _radius(robot_radius_m))
    r = r.reshape(n, k, m)
    cos_i = cos_i.reshape(n, k, m)
    nearest = np.argmin(r, axis=2)[..., None]
    rng_k = np.take_along_axis(r, nearest, axis=2)[..., 0]
    cos_k = np.take_along_axis(cos_i, nearest, axis=2)[..., 0]
    incidence = np.arccos(np.clip(cos_k, 0.0, 1.0))
    lost = rng.random((n, k)) < params.dropout_probability(incidence)
    noise = params.noise_m * rng.standard_normal((n, k))
    out = np.clip(rng_k + noise, params.min_range_m, params.max_range_m)
    out[lost | ~np.isfinite(rng_k)] = np.inf
    return out


def stereo_scan(
    grid: OccupancyGrid,
    poses: ArrayLike,
    params: StereoScanParams,
    *,
    robot_radius_m: float,
    rng: np.random.Generator,
    smoke: SmokeField | None = None,
) -> FloatArray:
    """The stereo pair's range scan of every robot: shape (N, S) [m], ``inf`` if empty.

    Sector ``s`` spans ``params.edges_rad[s:s + 2]`` from the heading; its reading is
    the least range of its rays, its depth ``Z = r cos(bearing)`` disturbed by the
    stereo noise ``N(0, (Z^2 sigma_d / (f B))^2)``, at least ``min_range_m``, or ``inf``
    beyond ``max_range_m``.

    Parameters
    ----------
    grid : OccupancyGrid
    poses : array_like, shape (N, 3)
        True poses x [m], y [m], theta [rad] (the camera looks along theta).
    params : StereoScanParams
    robot_radius_m : float
        Radius of every robot's disc [m].
    rng : numpy.random.Generator
        Draws the depth noise.
    smoke : SmokeField, optional
        Smoke dimming the scene (module notes); a ray it blinds before the obstacle
        returns nothing, and a sector all of whose rays are blind reads ``inf``.
        None: clear air.

    Returns
    -------
    ndarray, shape (N, S)
        Horizontal ranges from each robot's centre [m].

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.sim.ranging import StereoScanParams, stereo_scan
    >>> from firefleet.world import OccupancyGrid
    >>> occupied = np.zeros((40, 40), dtype=bool)
    >>> occupied[:, 30] = True  # a wall at x = 3 m
    >>> grid = OccupancyGrid(occupied, ~occupied, resolution_m=0.1)
    >>> params = StereoScanParams(sectors=4, disparity_noise_px=0.0)
    >>> stereo_scan(grid, [[1.0, 2.0, 0.0]], params, robot_radius_m=0.2,
    ...             rng=np.random.default_rng(0)).round(3).tolist()  # 2 / cos(14 deg) outside
    [[2.062, 2.0, 2.0, 2.062]]
    """
    p = _poses(poses)
    n, s, m = p.shape[0], params.sectors, params.rays_per_sector
    bearings = params.ray_bearings_rad()
    r, _ = _cast(
        grid,
        p,
        bearings.ravel(),
        params.max_range_m,
        _radius(robot_radius_m),
        smoke,
        None if smoke is None else smoke.stereo,
    )
    r = r.reshape(n, s, m)
    nearest = np.argmin(r, axis=2)[..., None]
    rng_s = np.take_along_axis(r, nearest, axis=2)[..., 0]
    cos_b = np.cos(np.take_along_axis(np.broadcast_to(bearings, r.shape), nearest, axis=2)[..., 0])
    depth = np.where(np.isfinite(rng_s), rng_s * cos_b, 0.0)
    depth = depth + params.depth_sigma_m(depth) * rng.standard_normal((n, s))
    out = np.clip(depth / cos_b, params.min_range_m, None)
    out[~np.isfinite(rng_s) | (out > params.max_range_m)] = np.inf
    return np.asarray(out)


class RangeSensors:
    """The loop's range sensor stage (:class:`firefleet.sim.loop.Sensors`).

    ``read(world, drive)`` returns, for the sensors configured, ``"ultrasonic_range_m"``
    (N, K), ``"lidar_range_m"`` (N, B) and ``"stereo_scan_m"`` (N, S) of the true poses
    ``drive.pose``. Each sensor scans at its own ``rate_hz``: at the first tick, then
    whenever its period has passed (tick ``k`` scans if ``floor(k dt f)`` moved on), and
    the readings hold between scans, as a real sensor's last reading does. A rate at or
    above the loop's ``1 / dt_s`` scans every tick. The stage counts the ticks it read:
    use one stage per run.

    Parameters
    ----------
    grid : OccupancyGrid
    robot_radius_m : float
        Radius of every robot's disc [m] (the others block the beams).
    ultrasonic, lidar, stereo : params or None
        The sensors fitted (None: absent).
    dt_s : float
        The loop's tick [s].
    rng : numpy.random.Generator
        Draws every sensor's noise.
    smoke : callable, optional
        ``smoke(world) -> SmokeField or None``: the smoke the lidar and the stereo scan
        look through at this tick (module notes); None: clear air.

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from firefleet.sim.ranging import LidarParams, RangeSensors
    >>> from firefleet.world import OccupancyGrid
    >>> occupied = np.zeros((20, 20), dtype=bool)
    >>> occupied[:, 15] = True
    >>> grid = OccupancyGrid(occupied, ~occupied, resolution_m=0.1)
    >>> stage = RangeSensors(grid, 0.2, lidar=LidarParams(beams=4, noise_m=0.0),
    ...                      rng=np.random.default_rng(0))
    >>> drive = SimpleNamespace(pose=np.array([[0.5, 1.0, 0.0]]))
    >>> stage.read(None, drive)["lidar_range_m"].round(6).tolist()
    [[inf, inf, 1.0, inf]]
    """

    def __init__(
        self,
        grid: OccupancyGrid,
        robot_radius_m: float,
        ultrasonic: UltrasonicParams | None = None,
        lidar: LidarParams | None = None,
        stereo: StereoScanParams | None = None,
        *,
        dt_s: float = 0.01,
        rng: np.random.Generator,
        smoke: Callable[[Any], SmokeField | None] | None = None,
    ) -> None:
        if not (math.isfinite(dt_s) and dt_s > 0.0):
            raise InputError(f"dt_s must be > 0, got {dt_s}")
        self.grid = grid
        self.robot_radius_m = _radius(robot_radius_m)
        self.dt_s = float(dt_s)
        self.rng = rng
        self.smoke = smoke
        self.sensors: dict[str, Any] = {}
        if ultrasonic is not None:
            self.sensors["ultrasonic_range_m"] = ultrasonic
        if lidar is not None:
            self.sensors["lidar_range_m"] = lidar
        if stereo is not None:
            self.sensors["stereo_scan_m"] = stereo
        self._tick = 0
        self._last: dict[str, FloatArray] = {}

    def _due(self, params: Any) -> bool:
        k = self._tick
        f = params.rate_hz * self.dt_s
        return k == 0 or f >= 1.0 or math.floor(k * f + 1e-9) != math.floor((k - 1) * f + 1e-9)

    def quiet_ticks(self, limit: int, scans: bool = False) -> int:
        """How many of the next ticks (at most ``limit``) scan nothing: :meth:`read` would
        give the held readings; :meth:`skip` counts them instead (the loop's quiet
        stretches). ``scans``: the scans due among them count too (for a decision that
        does not read the ranges at its quiet ticks): :meth:`skip` then makes them."""
        if scans:
            return limit if all(n in self._last for n in self.sensors) else 0
        tick, m = self._tick, 0
        try:
            while m < limit:
                self._tick = tick + m
                if any(self._due(p) or n not in self._last for n, p in self.sensors.items()):
                    break
                m += 1
        finally:
            self._tick = tick
        return m

    def skip(self, m: int, world: Any = None, poses: FloatArray | None = None) -> None:
        """Count ``m`` ticks that scanned nothing (:meth:`quiet_ticks`); with the true
        poses (m, N, 3) of each, make the scans due among them as :meth:`read` would
        (the same noise draws in the same order)."""
        if poses is None:
            self._tick += m
            return
        for j in range(m):
            if any(self._due(p) for p in self.sensors.values()):
                self.read(world, _AtPose(poses[j]))
            else:
                self._tick += 1

    def read(self, world: Any, drive: Any) -> dict[str, FloatArray]:
        """Readings by name at this tick (held from the last scan between scans)."""
        scans: dict[str, Callable[..., FloatArray]] = {
            "ultrasonic_range_m": ultrasonic_scan,
            "lidar_range_m": lidar_scan,
            "stereo_scan_m": stereo_scan,
        }
        due = [n for n, p in self.sensors.items() if self._due(p) or n not in self._last]
        dimmed = self.smoke is not None and any(n != "ultrasonic_range_m" for n in due)
        smoke = self.smoke(world) if self.smoke is not None and dimmed else None
        for name in due:  # in the order the sensors were fitted: the noise draws too
            seen = {} if smoke is None or name == "ultrasonic_range_m" else {"smoke": smoke}
            self._last[name] = scans[name](
                self.grid,
                drive.pose,
                self.sensors[name],
                robot_radius_m=self.robot_radius_m,
                rng=self.rng,
                **seen,
            )
        self._tick += 1
        return dict(self._last)
