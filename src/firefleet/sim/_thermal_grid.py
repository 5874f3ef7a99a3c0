"""The thermal camera on a grid world: walls, flames, hot gas and people from the world's
fields (the mission's sensor; the segment scenes of :func:`render_thermal` are the
reference it is tested against).

The building is the grid's occupied cells extruded from the floor to ``wall_height_m``;
every open cell carries the temperature of the world's heat field, which its floor and
ceiling patches and the wall faces next to it show (the field is the temperature of the
hot gas layer and of the surfaces it heats: a single-zone simplification, stated); a
burning cell holds a flame ``flame_height_m`` tall at its field temperature (the flame
temperature), opaque; people are upright billboards facing the camera (by default a
person standing, 0.5 m x 1.7 m: the size prior of :func:`perception.thermal.detect`) at
body temperature. Smoke does not enter: the
Lepton's 8-14 um band passes smoke that blinds visible light (soot's extinction falls
with wavelength, roughly as 1/lambda: at 10 um it is about a twentieth of that at
0.5 um; Widmann 2003).

Each column of the image is one horizontal ray walked through the grid cell by cell
(Amanatides and Woo's traversal) to the first wall; each pixel of the column then
finds what it meets along that walk (floor or ceiling, a flame, a person, the wall).

References
----------
J. Amanatides and A. Woo, "A fast voxel traversal algorithm for ray tracing",
Eurographics 1987. J. F. Widmann, "Evaluation of the Planck mean absorption
coefficients for radiation transport through smoke", Combust. Sci. Technol. 175, 2003.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.errors import InputError, as_float_array, check_fields
from firefleet.perception.thermal._table import interp_sorted_slopes, table_slopes
from firefleet.world import BODY_C, OccupancyGrid

__all__ = ["GridThermalScene", "grid_thermal_celsius", "grid_thermal_frames"]

_INF = np.inf


@dataclass(frozen=True)
class GridThermalScene:
    """What a grid world shows a thermal camera, besides its fields.

    Attributes
    ----------
    wall_height_m : float
        Height of the walls and the ceiling [m].
    flame_height_m : float
        Height of the flame over a burning cell [m] (a room-contents fire: 0.5-1.5 m).
    person_size_m : (float, float)
        Width and height of a person's billboard [m] (standing: 0.5, 1.7, the
        detector's prior; a person lying down is about 1.7 x 0.4, which the detector's
        standing prior does not take for a person).
    person_c : float
        Apparent temperature of a person [C] (clothed skin: a little under the core's
        37 C; the default is the core temperature, the deliverable's figure).
    outside_c : float
        What a ray that leaves the grid meets [C].
    ceiling : bool
        Whether there is a ceiling (else rays above the walls meet ``outside_c``).
    layer_height_m : float
        Height of the interface between a room fire's hot upper layer and its cooler
        lower layer [m] (two-zone model): the floor and the walls below it show
        ``ambient_c + lower_fraction (T - ambient_c)`` of the field's temperature T.
    lower_fraction : float
        The lower layer's share of the field's temperature rise (1: one zone, the
        field everywhere).
    ambient_c : float
        Ambient temperature [C] of that rise.

    Examples
    --------
    >>> from firefleet.sim._thermal_grid import GridThermalScene
    >>> GridThermalScene().person_size_m
    (0.5, 1.7)
    """

    wall_height_m: float = 2.5
    flame_height_m: float = 1.0
    person_size_m: tuple[float, float] = (0.5, 1.7)
    person_c: float = BODY_C
    outside_c: float = 10.0
    ceiling: bool = True
    layer_height_m: float = 1.2
    lower_fraction: float = 1.0
    ambient_c: float = 20.0

    def __post_init__(self) -> None:
        check_fields(self, "thermal_scene", positive=("wall_height_m", "flame_height_m"))
        if len(self.person_size_m) != 2 or min(self.person_size_m) <= 0:
            raise InputError(
                f"thermal_scene.person_size_m: {self.person_size_m!r}, expected (width, height) > 0"
            )


@numba.njit(cache=True)
def _walk(
    x0: float,
    y0: float,
    ux: float,
    uy: float,
    occ: np.ndarray,
    temp: np.ndarray,
    burn: np.ndarray,
    res: float,
    s_out: np.ndarray,
    t_out: np.ndarray,
    b_out: np.ndarray,
) -> tuple[int, float, float]:  # pragma: no cover - compiled
    """Walk the unit horizontal direction (ux, uy) from (x0, y0) (grid frame: metres from
    the lower-left corner, rows from the bottom). Fills, per open cell crossed, its exit
    distance ``s_out`` [m], temperature and burning flag; returns the number of cells,
    the distance to the wall face (inf when the ray leaves the grid) and the wall's
    temperature (that of the last open cell)."""
    h, w = occ.shape
    ix = int(np.floor(x0 / res))
    iy = int(np.floor(y0 / res))
    step_x = 1 if ux > 0 else -1
    step_y = 1 if uy > 0 else -1
    if ux != 0.0:
        next_x = ((ix + (1 if ux > 0 else 0)) * res - x0) / ux
        dt_x = res / abs(ux)
    else:
        next_x = np.inf
        dt_x = np.inf
    if uy != 0.0:
        next_y = ((iy + (1 if uy > 0 else 0)) * res - y0) / uy
        dt_y = res / abs(uy)
    else:
        next_y = np.inf
        dt_y = np.inf
    n = 0
    last_t = temp[iy, ix] if 0 <= iy < h and 0 <= ix < w else 20.0
    cap = s_out.size
    while True:
        if ix < 0 or iy < 0 or ix >= w or iy >= h:
            return n, np.inf, last_t
        s_enter = 0.0 if n == 0 else s_out[n - 1]
        if occ[iy, ix]:
            return n, s_enter, last_t
        s_exit = min(next_x, next_y)
        if n >= cap:
            return n, np.inf, last_t
        s_out[n] = s_exit
        t_out[n] = temp[iy, ix]
        b_out[n] = burn[iy, ix]
        last_t = temp[iy, ix]
        n += 1
        if next_x < next_y:
            ix += step_x
            next_x += dt_x
        else:
            iy += step_y
            next_y += dt_y


@numba.njit(cache=True)
def _people_seen_from(
    x0: float, y0: float, people: np.ndarray, person_w: float, billboard: np.ndarray
) -> None:  # pragma: no cover - compiled
    """Each person's billboard (facing the camera at (x0, y0)) as :func:`_people_along`
    takes it, the same for every column of a frame: ``billboard[v]`` = (its right edge
    ``wx``, ``wy``, its width ``ex``, ``ey``, ``wx ey - wy ex``, 1 if it is at a
    distance from the camera, else 0)."""
    for v in range(people.shape[0]):
        px, py = people[v, 0] - x0, people[v, 1] - y0
        dist = np.sqrt(px * px + py * py)
        billboard[v, 5] = 0.0
        if dist < 1e-9:
            continue
        ex, ey = -py / dist * person_w, px / dist * person_w  # the billboard's width
        wx, wy = px - 0.5 * ex, py - 0.5 * ey  # its right edge
        billboard[v, 0], billboard[v, 1], billboard[v, 2], billboard[v, 3] = wx, wy, ex, ey
        billboard[v, 4] = wx * ey - wy * ex
        billboard[v, 5] = 1.0


@numba.njit(cache=True)
def _people_along(
    ux: float,
    uy: float,
    billboard: np.ndarray,
    s_people: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """Where the horizontal ray (ux, uy) from the camera meets each person's billboard
    (:func:`_people_seen_from`) [m], inf where it misses."""
    for v in range(billboard.shape[0]):
        s_people[v] = np.inf
        if billboard[v, 5] == 0.0:
            continue
        wx, wy, ex, ey = billboard[v, 0], billboard[v, 1], billboard[v, 2], billboard[v, 3]
        den = ux * ey - uy * ex
        if den == 0.0:
            continue
        s = billboard[v, 4] / den
        u = (wx * uy - wy * ux) / den
        if s > 1e-9 and 0.0 <= u <= 1.0:
            s_people[v] = s


@numba.njit(cache=True)
def _cast(
    poses: np.ndarray,
    occ: np.ndarray,
    temp: np.ndarray,
    burn: np.ndarray,
    res: float,
    people: np.ndarray,
    xn: np.ndarray,
    yn: np.ndarray,
    scene: np.ndarray,
    ceiling: bool,
    temps_out: np.ndarray,
    depth_out: np.ndarray,
) -> None:  # pragma: no cover - compiled
    """Apparent temperature of every ray and its depth along the optical axis [m]
    (inf where it leaves the grid) into ``temps_out`` and ``depth_out``, each of shape
    (N, len(xn), len(yn)) (column by column: a column's rays share one walk).

    ``scene``: mount height, wall height, flame height, person width, person height,
    person temperature, outside temperature, layer height, lower fraction, ambient.
    Each column is one horizontal walk to the first wall; each of its rays then meets
    the wall (below the hot layer: the lower layer's temperature), the floor or the
    ceiling in the cell it crosses there, the first flame column it passes through, or
    a person's billboard, whichever is nearest.
    """
    mount_h, wall_h, flame_h = scene[0], scene[1], scene[2]
    person_w, person_h, person_c = scene[3], scene[4], scene[5]
    outside_c, layer_h, lower, ambient = scene[6], scene[7], scene[8], scene[9]
    n_robots = poses.shape[0]
    n_rows = yn.size
    n_cols = xn.size
    cap = 4 * (occ.shape[0] + occ.shape[1]) + 8
    s_out = np.empty(cap)
    t_out = np.empty(cap)
    b_out = np.zeros(cap, dtype=np.bool_)
    fires = np.empty(cap, dtype=np.int64)
    n_people = people.shape[0]
    s_people = np.empty(n_people)
    seen = np.empty(n_people, dtype=np.int64)
    billboard = np.empty((n_people, 6))
    for k in range(n_robots):
        x0, y0, th = poses[k, 0], poses[k, 1], poses[k, 2]
        ct, st = np.cos(th), np.sin(th)
        _people_seen_from(x0, y0, people, person_w, billboard)
        for c in range(n_cols):
            dx = ct + xn[c] * st
            dy = st - xn[c] * ct
            length = np.sqrt(dx * dx + dy * dy)
            ux, uy = dx / length, dy / length
            n, s_wall, t_wall = _walk(x0, y0, ux, uy, occ, temp, burn, res, s_out, t_out, b_out)
            n_fires = 0
            for i in range(n):
                if b_out[i]:
                    fires[n_fires] = i
                    n_fires += 1
            _people_along(ux, uy, billboard, s_people)
            n_seen = 0  # the people whose billboard the column's plane meets, in order
            for v in range(n_people):
                if s_people[v] < np.inf:
                    seen[n_seen] = v
                    n_seen += 1
            lo = 0  # the floor or ceiling cell of the column's previous ray
            for r in range(n_rows):
                slope = -yn[r] / length  # height gained per horizontal metre
                best = s_wall
                best_t = t_wall if s_wall < np.inf else outside_c
                if s_wall < np.inf and mount_h + slope * s_wall < layer_h:
                    best_t = ambient + lower * (t_wall - ambient)  # below the hot layer
                # floor or ceiling, where the ray meets it
                s_plane = np.inf
                if slope < 0.0:
                    s_plane = mount_h / -slope
                elif slope > 0.0 and ceiling:
                    s_plane = (wall_h - mount_h) / slope
                if s_plane < best:
                    best = s_plane
                    # the cell holding that point: the first whose exit lies beyond it
                    # (neighbouring rays meet the floor in neighbouring cells)
                    lo = min(lo, n)
                    while lo > 0 and s_out[lo - 1] >= s_plane:
                        lo -= 1
                    while lo < n and s_out[lo] < s_plane:
                        lo += 1
                    best_t = t_out[lo] if lo < n else outside_c
                    if slope < 0.0 and lo < n:  # the floor, under the hot layer
                        best_t = ambient + lower * (best_t - ambient)
                elif s_wall == np.inf and best == np.inf:
                    best_t = outside_c
                # flames: the first burning cell whose column of flame the ray crosses
                for f in range(n_fires):
                    i = fires[f]
                    s0 = 0.0 if i == 0 else s_out[i - 1]
                    if s0 >= best:
                        break
                    z0 = mount_h + slope * s0
                    z1 = mount_h + slope * s_out[i]
                    if min(z0, z1) <= flame_h and max(z0, z1) >= 0.0:
                        s_hit = s0 if z0 <= flame_h else s0 + (flame_h - z0) / slope
                        if s_hit < best:
                            best = s_hit
                            best_t = t_out[i]
                        break
                for q in range(n_seen):
                    s = s_people[seen[q]]
                    if s < best:
                        z = mount_h + slope * s
                        if 0.0 <= z <= person_h:
                            best = s
                            best_t = person_c
                temps_out[k, c, r] = best_t
                depth_out[k, c, r] = best / length  # forward part of the unit ray: 1/length


@numba.njit(cache=True)
def _frames(
    temps: np.ndarray,
    depth: np.ndarray,
    sub: int,
    table_c: np.ndarray,
    table_rad: np.ndarray,
    slope_rad: np.ndarray,
    slope_c: np.ndarray,
    offsets: np.ndarray,
    noise: np.ndarray,
    camera: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, bool]:  # pragma: no cover - compiled
    """The camera's frames (N, H, W) [C] from the rays of :func:`_cast` (N, W s, H s),
    each pixel's central-ray depth [m] (NaN: nothing on the grid), and False if a
    temperature left the radiance table: per pixel the mean band radiance of its
    ``sub`` x ``sub`` rays (summed along each sub-row, then the sub-rows: NumPy's
    order), back to a temperature (``np.interp`` both ways, ``slope_rad`` and
    ``slope_c`` the tables' slopes: :func:`_tables`), plus the column offset and the
    noise, clipped to ``camera[0:2]`` and quantised to ``camera[2]``."""
    min_c, max_c, step_k = camera[0], camera[1], camera[2]
    t_lo, t_hi = table_c[0], table_c[-1]
    step_c = (t_hi - t_lo) / (table_c.size - 1)
    per_step = 1.0 / step_c
    n_robots, n_cols, n_rows = temps.shape
    h_px, w_px = n_rows // sub, n_cols // sub
    frames = np.empty((n_robots, h_px, w_px))
    centre = np.empty((n_robots, h_px, w_px))
    rad = np.empty((n_cols, n_rows))
    mid = sub // 2
    ok = True
    for k in range(n_robots):
        last_t = np.nan
        last_rad = np.nan
        for c in range(n_cols):
            for r in range(n_rows):
                t = temps[k, c, r]
                if t == last_t:  # neighbouring rays often meet the same cell
                    rad[c, r] = last_rad
                    continue
                if not t_lo <= t <= t_hi:
                    ok = False
                    t = min(max(t, t_lo), t_hi)
                j = int((t - t_lo) * per_step)
                last_t = temps[k, c, r]
                last_rad = interp_sorted_slopes(t, table_c, table_rad, slope_rad, j, j + 1)
                rad[c, r] = last_rad
        uni_t = np.nan
        uni_back = np.nan
        for j in range(w_px):  # a pixel column's rays lie together in memory
            for i in range(h_px):
                d = depth[k, j * sub + mid, i * sub + mid]
                centre[k, i, j] = d if np.isfinite(d) else np.nan
                if sub == 2:  # the default: the loops below, unrolled
                    c0, c1, r0, r1 = 2 * j, 2 * j + 1, 2 * i, 2 * i + 1
                    total = 0.0 + ((0.0 + rad[c0, r0]) + rad[c1, r0])
                    total += (0.0 + rad[c0, r1]) + rad[c1, r1]
                    t00, t10 = temps[k, c0, r0], temps[k, c1, r0]
                    t01, t11 = temps[k, c0, r1], temps[k, c1, r1]
                    coolest = min(min(min(t00, t10), t01), t11)
                    hottest = max(max(max(t00, t10), t01), t11)
                else:
                    total = 0.0
                    coolest = np.inf
                    hottest = -np.inf
                    for a in range(sub):
                        part = 0.0
                        for b in range(sub):
                            part += rad[j * sub + b, i * sub + a]
                            coolest = min(coolest, temps[k, j * sub + b, i * sub + a])
                            hottest = max(hottest, temps[k, j * sub + b, i * sub + a])
                        total += part
                # the mean radiance's temperature lies between the coolest ray's and
                # the hottest's
                if coolest == hottest and coolest == uni_t:  # the last uniform pixel's
                    t = uni_back
                else:
                    lo = int((min(max(coolest, t_lo), t_hi) - t_lo) * per_step)
                    hi = int((min(max(hottest, t_lo), t_hi) - t_lo) * per_step) + 1
                    t = interp_sorted_slopes(
                        total / (sub * sub), table_rad, table_c, slope_c, lo, hi
                    )
                    if coolest == hottest:  # its rays all meet one temperature
                        uni_t, uni_back = coolest, t
                t = t + offsets[j]
                t = t + noise[k, i, j]
                t = min(max(t, min_c), max_c)
                if step_k > 0:
                    t = np.rint(t / step_k) * step_k
                frames[k, i, j] = t
    return frames, centre, ok


@functools.lru_cache(maxsize=1)
def _tables() -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """The 8-14 um radiance table (temperatures [C], radiances) and its slopes both ways
    (:func:`~firefleet.perception.thermal._table.table_slopes`), made once."""
    from firefleet.perception.thermal._radiometry import _radiance_table

    table_c, table_rad = _radiance_table((8.0, 14.0))
    slope_rad, slope_c = table_slopes(table_c, table_rad), table_slopes(table_rad, table_c)
    slope_rad.flags.writeable = False
    slope_c.flags.writeable = False
    return table_c, table_rad, slope_rad, slope_c


def _scene_array(scene: GridThermalScene, mount_height_m: float) -> np.ndarray:
    """:func:`_cast`'s ``scene`` numbers."""
    return np.array(
        [
            mount_height_m,
            scene.wall_height_m,
            scene.flame_height_m,
            scene.person_size_m[0],
            scene.person_size_m[1],
            scene.person_c,
            scene.outside_c,
            scene.layer_height_m,
            scene.lower_fraction,
            scene.ambient_c,
        ],
        dtype=np.float64,
    )


def _cast_rays(
    poses: ArrayLike,
    grid: OccupancyGrid,
    temperature_c: ArrayLike,
    burning: ArrayLike,
    people_xy_m: ArrayLike,
    xn: FloatArray,
    yn: FloatArray,
    mount_height_m: float,
    scene: GridThermalScene,
) -> tuple[np.ndarray, np.ndarray]:
    """The rays of :func:`_cast`, (N, len(xn), len(yn)) each, from checked inputs."""
    local, occ, temp, burn, people = _grid_inputs(poses, grid, temperature_c, burning, people_xy_m)
    xs = np.ascontiguousarray(xn, dtype=np.float64)
    ys = np.ascontiguousarray(yn, dtype=np.float64)
    temps = np.empty((local.shape[0], xs.size, ys.size))
    depth = np.empty_like(temps)
    _cast(
        local,
        occ,
        temp,
        burn,
        grid.resolution_m,
        people,
        xs,
        ys,
        _scene_array(scene, float(mount_height_m)),
        scene.ceiling,
        temps,
        depth,
    )
    return temps, depth


def _grid_inputs(
    poses: ArrayLike,
    grid: OccupancyGrid,
    temperature_c: ArrayLike,
    burning: ArrayLike,
    people_xy_m: ArrayLike,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The renderers' inputs checked and in the grid frame (rows from the bottom):
    poses, occupancy, temperature, burning, people."""
    pose = as_float_array(poses, "poses", (None, 3))
    h, w = grid.shape
    temp = as_float_array(temperature_c, "temperature_c", (h, w))
    burn = np.asarray(burning, dtype=bool)
    if burn.shape != (h, w):
        raise InputError(f"burning: shape {burn.shape}, expected the grid's {(h, w)}")
    people = as_float_array(people_xy_m, "people_xy_m", (None, 2))
    ox, oy = grid.origin_m
    local = pose.copy()
    local[:, 0] -= ox
    local[:, 1] -= oy
    return (
        local,
        np.ascontiguousarray(grid.occupied[::-1]),
        np.ascontiguousarray(temp[::-1], dtype=np.float64),
        np.ascontiguousarray(burn[::-1]),
        np.ascontiguousarray(people - np.array([ox, oy])),
    )


def grid_thermal_frames(
    poses: ArrayLike,
    grid: OccupancyGrid,
    temperature_c: ArrayLike,
    burning: ArrayLike,
    people_xy_m: ArrayLike,
    xn: FloatArray,
    yn: FloatArray,
    supersample: int,
    mount_height_m: float,
    scene: GridThermalScene,
    camera: tuple[FloatArray, FloatArray, float, float, float],
) -> tuple[FloatArray, FloatArray]:
    """Every robot's camera frame [C] and central-ray depth [m] (NaN: nothing on the
    grid), each (N, len(yn) / s, len(xn) / s), in one compiled pass: the rays of
    :func:`grid_thermal_celsius`, each pixel's mean band radiance over its ``s`` x ``s``
    rays, and the camera (``camera``: column offsets (W,) [K], noise (N, H, W) [K],
    scene range min and max [C], quantisation step [K]; no optical blur).
    """
    temps, depth = _cast_rays(
        poses, grid, temperature_c, burning, people_xy_m, xn, yn, mount_height_m, scene
    )
    offsets, noise, min_c, max_c, step_k = camera
    table_c, table_rad, slope_rad, slope_c = _tables()
    frames, centre, ok = _frames(
        temps,
        depth,
        int(supersample),
        table_c,
        table_rad,
        slope_rad,
        slope_c,
        np.ascontiguousarray(offsets, dtype=np.float64),
        np.ascontiguousarray(noise, dtype=np.float64),
        np.array([min_c, max_c, step_k], dtype=np.float64),
    )
    if not ok:
        raise InputError(f"temperatures must be finite, in [{table_c[0]}, {table_c[-1]}] C")
    return frames, centre


def grid_thermal_celsius(
    poses: ArrayLike,
    grid: OccupancyGrid,
    temperature_c: ArrayLike,
    burning: ArrayLike,
    people_xy_m: ArrayLike,
    xn: FloatArray,
    yn: FloatArray,
    mount_height_m: float,
    scene: GridThermalScene,
) -> tuple[FloatArray, FloatArray]:
    """The temperature each ray ``(xn[c], yn[r])`` meets [C] and the depth of what it
    meets along the optical axis [m] (inf: nothing on the grid), each (N, R, C).

    Rays in the camera's normalised coordinates (x right, y down, axis horizontal along
    each robot's heading), from ``mount_height_m`` above the floor.
    """
    temps, depth = _cast_rays(
        poses, grid, temperature_c, burning, people_xy_m, xn, yn, mount_height_m, scene
    )
    return temps.transpose(0, 2, 1).copy(), depth.transpose(0, 2, 1).copy()
