"""A visible-light camera's view of people and flames through smoke (Jin's law).

A robot without a thermal camera finds people and fires with its stereo pair's
visible-light camera. This module is that sensor's model of the scene, not a shortcut
from the world's truth: a target (a person, a flame) is seen when it lies in the
camera's field of view, within its range (1 to 10 m), in line of sight on the map (no wall cell
on the segment between them: the same exact ray casting as the range sensors), and
bright enough against its surround after the smoke along that line of sight.

The contrast of an object seen through smoke falls with the optical depth ``tau`` of
the path (Beer-Lambert, ``C = C0 exp(-tau)``); it is seen while the contrast stays
above a threshold, that is while ``tau <= ln(C0 / threshold)``. Jin's experiments
give this limit in uniform smoke as the visibility ``V = K / sigma`` [m]
(``sigma`` the extinction coefficient [1/m]): ``K = 3`` for a light-reflecting object
(a person, a wall) and ``K = 8`` for a light-emitting one (an exit sign, a flame). So
a target at range ``d`` is seen when ``tau(d) <= K``, which in uniform smoke is
``d <= K / sigma``. Written on the optical depth it holds in smoke that is not
uniform too.

Lighting: the building's emergency lighting is on (``lit=True``, the default: escape
routes and rooms lit to about 1 lx and more by luminaires on batteries after the
mains fail, as building codes require), so light-reflecting objects can be seen by
their contrast. ``lit=False`` is darkness: only light-emitting objects (flames) are
seen. Smoke's glare from a flame behind it, its light scattered back from the camera's
own lamp and the camera's exposure control are not modelled.

References
----------
T. Jin, "Visibility through fire smoke", Journal of Fire & Flammability 9, 1978,
135-155; T. Jin, "Visibility and human behavior in fire smoke", SFPE Handbook of Fire
Protection Engineering, 3rd ed., NFPA 2002, section 2 ch. 4 (``V = 2-4 / sigma`` for
reflecting signs, ``5-10 / sigma`` for light-emitting ones).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import BoolArray, FloatArray
from firefleet.errors import InputError, as_float_array, check_fields
from firefleet.sim._ranging_cast import cast_team, clearance_cells
from firefleet.sim._smoke_cast import SmokeField, optical_depth_segments
from firefleet.world import OccupancyGrid

__all__ = ["VisibleCameraParams", "VisibleView", "visible_view"]


@dataclass(frozen=True)
class VisibleCameraParams:
    """The visible-light camera that looks for people and flames.

    Attributes
    ----------
    hfov_rad : float
        Horizontal field of view [rad] (the stereo pair's, ``2 atan(640 / (2 x 600))``:
        56 deg, as :class:`firefleet.sim.ranging.StereoScanParams`).
    min_range_m, max_range_m : float
        Nearest and farthest range at which the detector names a target [m]: nearer
        than 1 m less than half a standing person fits in the frame (vertical field
        of view ``2 atan(240 / 600)``, 44 deg: 0.85 m of them at 1.05 m), as the
        thermal detector cannot name a person the frame cuts; beyond 10 m a 0.5 m wide
        person is under 30 px wide (600 px focal length).
    reflecting_k : float
        Jin's constant for a light-reflecting object (a person): 3.
    emitting_k : float
        Jin's constant for a light-emitting object (a flame): 8.
    lit : bool
        Emergency lighting on (module notes); false: dark, flames only.

    Examples
    --------
    >>> from firefleet.sim.visible import VisibleCameraParams
    >>> round(VisibleCameraParams().hfov_deg, 1)
    56.1
    """

    hfov_rad: float = 2.0 * math.atan(640.0 / (2.0 * 600.0))
    min_range_m: float = 1.0
    max_range_m: float = 10.0
    reflecting_k: float = 3.0
    emitting_k: float = 8.0
    lit: bool = True

    def __post_init__(self) -> None:
        check_fields(
            self,
            "visible camera",
            positive=("hfov_rad", "max_range_m", "reflecting_k", "emitting_k"),
            non_negative=("min_range_m",),
        )
        if not self.min_range_m < self.max_range_m:
            raise InputError(
                f"visible camera: min_range_m {self.min_range_m} must be below max_range_m "
                f"{self.max_range_m}"
            )
        if self.hfov_rad >= 2.0 * math.pi:
            raise InputError(f"visible camera: hfov_rad must be < 2 pi, got {self.hfov_rad}")

    @property
    def hfov_deg(self) -> float:
        """Horizontal field of view [deg]."""
        return math.degrees(self.hfov_rad)


@dataclass(frozen=True)
class VisibleView:
    """What each robot's camera sees of each target.

    Attributes
    ----------
    seen : ndarray of bool, shape (N, M)
        Robot ``i`` sees target ``j``.
    range_m : ndarray, shape (N, M)
        Distance from the robot's centre to the target [m].
    bearing_rad : ndarray, shape (N, M)
        Bearing of the target from the robot's heading, in (-pi, pi] [rad].
    depth : ndarray, shape (N, M)
        Optical depth of the smoke on the line of sight (``nan`` where not computed:
        outside the field of view or the range, or behind a wall).
    """

    seen: BoolArray
    range_m: FloatArray
    bearing_rad: FloatArray
    depth: FloatArray


def visible_view(
    grid: OccupancyGrid,
    poses: ArrayLike,
    targets_xy_m: ArrayLike,
    emitting: ArrayLike,
    params: VisibleCameraParams,
    *,
    smoke: SmokeField | None = None,
    clearance: np.ndarray | None = None,
) -> VisibleView:
    """Which targets each robot's visible-light camera sees (module notes: Jin's law).

    Parameters
    ----------
    grid : OccupancyGrid
        The map: occupied cells block the line of sight.
    poses : array_like, shape (N, 3)
        Camera poses x [m], y [m], theta [rad] (the camera looks along theta).
    targets_xy_m : array_like, shape (M, 2)
        People and flames [m].
    emitting : array_like of bool, shape (M,)
        True for a light-emitting target (a flame), false for a reflecting one.
    params : VisibleCameraParams
    smoke : SmokeField, optional
        The smoke between them (None: clear air).
    clearance : ndarray, shape (H, W), optional
        :func:`firefleet.sim._ranging_cast.clearance_cells` of the map, if the caller
        keeps it (faster line-of-sight casts on open maps; the same answer).

    Returns
    -------
    VisibleView

    Examples
    --------
    Uniform smoke of 0.5 1/m: a person (K = 3) is seen to ``3 / 0.5 = 6 m``, a flame
    (K = 8) to the camera's 10 m.

    >>> import numpy as np
    >>> from firefleet.sim._smoke_cast import SmokeField
    >>> from firefleet.sim.visible import VisibleCameraParams, visible_view
    >>> from firefleet.world import OccupancyGrid
    >>> free = np.zeros((40, 80), dtype=bool)
    >>> grid = OccupancyGrid(free, ~free, resolution_m=0.25)
    >>> smoke = SmokeField(grid, np.full((40, 80), 0.5))
    >>> people = [[6.9, 5.0], [7.1, 5.0], [10.0, 5.0]]
    >>> view = visible_view(grid, [[1.0, 5.0, 0.0]], people, [False, False, True],
    ...                     VisibleCameraParams(), smoke=smoke)
    >>> view.seen.tolist()
    [[True, False, True]]
    """
    p = as_float_array(poses, "poses", (None, 3))
    t = as_float_array(targets_xy_m, "targets_xy_m", (None, 2))
    glow = np.asarray(emitting, dtype=bool).reshape(-1)
    if glow.shape != (t.shape[0],):
        raise InputError(f"emitting: one flag per target ({t.shape[0]}), got {glow.shape}")
    n, m = p.shape[0], t.shape[0]
    d = t[None, :, :] - p[:, None, :2]  # (N, M, 2)
    rng_m = np.hypot(d[..., 0], d[..., 1])
    bearing = np.angle(np.exp(1j * (np.arctan2(d[..., 1], d[..., 0]) - p[:, 2:3])))
    k = np.where(glow, params.emitting_k, params.reflecting_k)
    lit = glow | params.lit
    cand = (np.abs(bearing) <= 0.5 * params.hfov_rad) & (rng_m <= params.max_range_m)
    cand &= rng_m >= params.min_range_m
    cand &= lit[None, :]
    depth = np.full((n, m), np.nan)
    seen = np.zeros((n, m), dtype=bool)
    if not cand.any():
        return VisibleView(seen, rng_m, bearing, depth)
    if clearance is None:
        clearance = clearance_cells(grid.occupied)
    ii, jj = np.nonzero(cand)
    wall = np.empty(ii.size)
    for a in np.unique(ii):  # each robot's rays to its candidates, on the map
        pick = ii == a
        far = float(rng_m[a, jj[pick]].max())
        ang = np.arctan2(d[a, jj[pick], 1], d[a, jj[pick], 0]) - p[a, 2]
        r, _ = cast_team(
            grid.occupied, grid.resolution_m, grid.origin_m, p[a : a + 1], ang, far, 0.0, clearance
        )
        wall[pick] = r[0]
    clear_los = wall >= rng_m[ii, jj] - 1e-9
    ii, jj = ii[clear_los], jj[clear_los]
    tau = np.zeros(ii.size)
    if smoke is not None:
        tau = optical_depth_segments(smoke, p[ii, :2], t[jj])
    depth[ii, jj] = tau
    seen[ii, jj] = tau <= k[jj]
    return VisibleView(seen, rng_m, bearing, depth)
