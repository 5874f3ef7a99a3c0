"""Smoke in the mission's sensors, and the stereo-only team (issue 15, item 2).

Smoke dims the light every visible-light sensor sees by (Beer-Lambert, the smoke's
extinction along the ray): the lidar's beams and the stereo pair's range scan
(:mod:`firefleet.sim.ranging`, ``smoke=``) and, for a team without thermal cameras,
the camera that looks for people and flames (:mod:`firefleet.sim.visible`, Jin's law).
The ultrasonic ring (sound) and the thermal camera (long-wave infrared, 8-14 um, whose
wavelength is long against the soot particles) see through it. The sensors sit on a
ground robot, in the lower layer of the two-zone room fire that the people breathe
(:mod:`._mission_world`): the extinction they look through is ``LOWER_LAYER`` times the
smoke field's.

``command.perception`` picks the team's eyes: ``thermal`` (the default: the Lepton read
by the real detector) or ``stereo`` (no thermal camera: people and flames found by the
visible-light camera through the smoke, its stereo pair's smoke-dimmed range scan added
to the range sensors). ``command.stereo_team: true`` runs, besides the scenario's team,
the same world (map, fires, people, seed) with a stereo-only team, and reports its
``stereo_victims_found`` and ``stereo_fires_detected`` beside the team's own metrics
(the deliverable's reason for a thermal camera, measured).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from firefleet._typing import FloatArray
from firefleet.sim._ranging_cast import clearance_cells
from firefleet.sim._ranging_params import StereoScanParams
from firefleet.sim._smoke_cast import SmokeField
from firefleet.sim.visible import VisibleCameraParams, visible_view
from firefleet.world import BURNING, OccupancyGrid

__all__ = [
    "STEREO_METRIC_NAMES",
    "SmokeAt",
    "VisibleDetector",
    "stereo_scan_params",
    "stereo_team_metrics",
]

STEREO_METRIC_NAMES = ("stereo_victims_found", "stereo_victims_found_s", "stereo_fires_detected")
"""The stereo-only team's metrics (NaN without ``command.stereo_team``)."""


class SmokeAt:
    """``smoke(world_state) -> SmokeField``: the extinction the robots' sensors look
    through, ``layer`` times the world's smoke field (made once per world step).

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from firefleet.sim.kinds._mission_smoke import SmokeAt
    >>> from firefleet.world import OccupancyGrid
    >>> free = np.zeros((2, 2), dtype=bool)
    >>> at = SmokeAt(OccupancyGrid(free, ~free, resolution_m=0.25), layer=0.4)
    >>> at(SimpleNamespace(smoke_per_m=np.full((2, 2), 2.0))).extinction_per_m.tolist()
    [[0.8, 0.8], [0.8, 0.8]]
    """

    def __init__(self, field: OccupancyGrid, layer: float) -> None:
        self.field = field
        self.layer = float(layer)
        self._last: tuple[Any, SmokeField] | None = None

    def __call__(self, world: Any) -> SmokeField:
        smoke = world.smoke_per_m
        if self._last is not None and self._last[0] is smoke:
            return self._last[1]
        out = SmokeField(self.field, self.layer * np.maximum(np.asarray(smoke, dtype=float), 0.0))
        self._last = (smoke, out)
        return out


def stereo_scan_params(perception: str) -> StereoScanParams | None:
    """The stereo range scan a stereo-only robot navigates with (None for a thermal
    team, whose range sensors are the scenario's ``sensors:``)."""
    return StereoScanParams() if perception == "stereo" else None


class VisibleDetector:
    """A stereo-only team's people and fire detections (the sensors stage calls
    :meth:`read` at the camera's frame rate in place of the thermal pipeline).

    People are light-reflecting targets at their positions; each burning field cell
    is a light-emitting one (a flame), and the flames a robot sees of one burning
    region (8-connected) are reported as one fire at their mean position, as the
    thermal detector reports one hot blob. Ranges carry the stereo pair's depth noise
    (``depth_noise`` relative, as the thermal path's registered depth).

    Parameters
    ----------
    grid : OccupancyGrid
        The map (line of sight).
    smoke : SmokeAt
    victims_xy_m : ndarray, shape (V, 2)
    params : VisibleCameraParams
    rng : numpy.random.Generator
        The range noise.
    """

    def __init__(
        self,
        grid: OccupancyGrid,
        smoke: SmokeAt,
        victims_xy_m: FloatArray,
        params: VisibleCameraParams,
        *,
        rng: np.random.Generator,
        depth_noise: float = 0.03,
    ) -> None:
        self.grid = grid
        self.smoke = smoke
        self.victims_xy_m = np.asarray(victims_xy_m, dtype=float).reshape(-1, 2)
        self.params = params
        self.rng = rng
        self.depth_noise = depth_noise
        self.clearance = clearance_cells(grid.occupied)

    def read(self, world: Any, pose: FloatArray, damaged: Any) -> FloatArray:
        """Detections (K, 5): robot, kind (0 fire, 1 person), bearing [rad], range [m],
        peak [C]: a visible camera measures no temperature, so NaN for a person and
        ``inf`` for a fire (what it sees of a fire is flames, light-emitting: the
        tactics' ``peak >= flame_c`` test for flames holds)."""
        import scipy.ndimage as ndi

        field = self.smoke.field
        burning = np.asarray(world.fire.state) == BURNING
        cells = np.argwhere(burning)
        flames = field.center_of(cells) if len(cells) else np.zeros((0, 2))
        labels = np.zeros(0, dtype=int)
        if len(cells):
            lab, _ = ndi.label(burning, structure=np.ones((3, 3)))
            labels = lab[cells[:, 0], cells[:, 1]]
        targets = np.concatenate([self.victims_xy_m, flames])
        glow = np.r_[np.zeros(len(self.victims_xy_m), bool), np.ones(len(flames), bool)]
        view = visible_view(
            self.grid,
            pose,
            targets,
            glow,
            self.params,
            smoke=self.smoke(world),
            clearance=self.clearance,
        )
        rows: list[list[float]] = []
        v = len(self.victims_xy_m)
        for i in range(pose.shape[0]):
            if bool(np.asarray(damaged)[i]):
                continue
            for j in np.flatnonzero(view.seen[i, :v]):
                rows.append(
                    [float(i), 1.0, float(view.bearing_rad[i, j]), view.range_m[i, j], math.nan]
                )
            seen_f = np.flatnonzero(view.seen[i, v:])
            for lab_k in np.unique(labels[seen_f]):
                pick = seen_f[labels[seen_f] == lab_k]
                xy = flames[pick].mean(axis=0)
                dx, dy = xy - pose[i, :2]
                bearing = math.remainder(math.atan2(dy, dx) - pose[i, 2], math.tau)
                rows.append([float(i), 0.0, bearing, math.hypot(dx, dy), math.inf])
        out = np.array(rows, dtype=float).reshape(-1, 5)
        if len(out):
            out[:, 3] *= 1.0 + self.depth_noise * self.rng.standard_normal(len(out))
        return out


def stereo_team_metrics(scenario: Any, metrics: Any) -> dict[str, Any]:
    """The stereo-only team's metrics in the scenario's world (module notes), or NaN
    when the scenario does not ask for it (``command.stereo_team``).

    ``metrics(result)`` computes a mission run's metrics (the kind's).
    """
    from firefleet.sim.engine import simulate

    cmd = scenario.command
    if not getattr(cmd, "stereo_team", False) or not cmd.robots:
        return {
            "stereo_victims_found": math.nan,
            "stereo_victims_found_s": [],
            "stereo_fires_detected": math.nan,
        }
    stereo = dataclasses.replace(
        scenario, command=dataclasses.replace(cmd, perception="stereo", stereo_team=False)
    )
    got = metrics(simulate(stereo, record_every=max(1, round(cmd.record_s / scenario.dt_s))))
    return {
        "stereo_victims_found": got["victims_found"],
        "stereo_victims_found_s": got["victims_found_s"],
        "stereo_fires_detected": got["fires_detected"],
    }
