"""A small kinematic world for the tactics tests (tests only).

Unicycle robots obey (v, omega) exactly (:func:`firefleet.models.unicycle_step`); a
robot's thermal camera detects every burning point and person within range, inside its
51 deg cone and in line of sight on the map (sampled every 2.5 cm: independent of the
team's coarse grid); a spraying robot drains its tank at the flow rate and puts water
on the burning points in reach in front of it; a point goes out once it got
``water_l`` litres. Tanks refill at the refill rate while the team says ``refilling``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from firefleet.control.mission import (
    Orders,
    TacticsObservation,
    TacticsParams,
    TacticsState,
    tactics_init,
    tactics_step,
)
from firefleet.models import unicycle_step
from firefleet.world import OccupancyGrid


def sight(grid: OccupancyGrid, a: np.ndarray, b: np.ndarray, step_m: float = 0.025) -> np.ndarray:
    """Line of sight (M,) between points a and b (M, 2) on the map's fine cells; the
    cells of both ends are not checked."""
    a = np.asarray(a, float).reshape(-1, 2)
    b = np.asarray(b, float).reshape(-1, 2)
    if len(a) == 0:
        return np.zeros(0, bool)
    length = np.hypot(*(b - a).T)
    k = int(np.ceil(length.max() / step_m)) + 2
    s = np.linspace(0.0, 1.0, k)
    pts = a[:, None] + s[None, :, None] * (b - a)[:, None]
    hit = grid.occupied_at(pts)
    ends = (s[None] * length[:, None] < 0.1) | (s[None] * length[:, None] > length[:, None] - 0.1)
    out: np.ndarray = ~np.any(hit & ~ends, axis=1)
    return out


def seen(
    grid: OccupancyGrid, pose: np.ndarray, pts: np.ndarray, range_m: float, hfov_rad: float
) -> tuple[np.ndarray, np.ndarray]:
    """(robot, point) index pairs of points each robot's camera sees."""
    if len(pts) == 0 or len(pose) == 0:
        return np.zeros(0, int), np.zeros(0, int)
    dx = pts[None, :, 0] - pose[:, None, 0]
    dy = pts[None, :, 1] - pose[:, None, 1]
    off = np.abs((np.arctan2(dy, dx) - pose[:, None, 2] + np.pi) % (2 * np.pi) - np.pi)
    cand = (np.hypot(dx, dy) <= range_m) & (off <= hfov_rad / 2)
    r, p = np.nonzero(cand)
    ok = sight(grid, pose[r, :2], pts[p])
    return r[ok], p[ok]


def fire_obs(pose: np.ndarray, fire_xy: np.ndarray, t_s: float = 0.0) -> TacticsObservation:
    """The observation of a team at ``pose`` (N, 3) whose robot 0 sees flames at
    ``fire_xy`` (K, 2), no person, every tank full (20 L), nobody damaged."""
    n = len(pose)
    return TacticsObservation(
        t_s=t_s,
        pose_m=pose,
        fire_xy_m=fire_xy,
        fire_robot=np.zeros(len(fire_xy), int),
        person_xy_m=np.zeros((0, 2)),
        person_robot=np.zeros(0, int),
        ranges={},
        tank_l=np.full(n, 20.0),
        damaged=np.zeros(n, bool),
        alive=np.ones(n, bool),
    )


@dataclass
class World:
    """The harness's truth and the team."""

    grid: OccupancyGrid
    params: TacticsParams
    pose: np.ndarray
    fire_xy: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    people_xy: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    water_l: float = 2.0
    damaged: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    t_s: float = 0.0
    dt_s: float = 0.1

    def __post_init__(self) -> None:
        n = len(self.pose)
        self.tank = np.full(n, self.params.tank_l)
        self.burning = np.ones(len(self.fire_xy), bool)
        self.wet = np.zeros(len(self.fire_xy))
        if len(self.damaged) != n:
            self.damaged = np.zeros(n, bool)
        self.state: TacticsState = tactics_init(self.grid, self.pose, self.params)
        self.orders: Orders | None = None
        self.log: list[dict[str, np.ndarray]] = []

    def step(self) -> None:
        p = self.params
        fr, fp = seen(
            self.grid, self.pose, self.fire_xy[self.burning], p.sensing_range_m, p.hfov_rad
        )
        pr, pp = seen(self.grid, self.pose, self.people_xy, p.sensing_range_m, p.hfov_rad)
        ok_f = ~self.damaged[fr]
        ok_p = ~self.damaged[pr]
        obs = TacticsObservation(
            t_s=self.t_s,
            pose_m=self.pose.copy(),
            fire_xy_m=self.fire_xy[self.burning][fp[ok_f]],
            fire_robot=fr[ok_f],
            person_xy_m=self.people_xy[pp[ok_p]],
            person_robot=pr[ok_p],
            ranges={},
            tank_l=self.tank.copy(),
            damaged=self.damaged.copy(),
            alive=np.ones(len(self.pose), bool),
        )
        self.state, o = tactics_step(self.state, obs, p, self.dt_s)
        self.orders = o
        v = np.where(self.damaged, 0.0, o.v_m_s)
        w = np.where(self.damaged, 0.0, o.omega_rad_s)
        spray = o.spray & (self.tank > 0) & ~self.damaged
        if spray.any() and self.burning.any():
            idx = np.flatnonzero(self.burning)
            _, q = seen(
                self.grid,
                self.pose[spray],
                self.fire_xy[idx],
                p.spray_range_m,
                2 * p.spray_half_angle_rad + 0.2,
            )
            np.add.at(self.wet, idx[q], p.flow_l_s * self.dt_s)
            self.burning &= self.wet < self.water_l
        self.tank = np.maximum(self.tank - spray * p.flow_l_s * self.dt_s, 0.0)
        self.tank = np.minimum(
            self.tank + self.state.refilling * p.refill_l_s * self.dt_s, p.tank_l
        )
        self.log.append(
            {
                "pose": self.pose.copy(),
                "mode": o.mode.copy(),
                "tank": self.tank.copy(),
                "spray": spray,
            }
        )
        self.pose = unicycle_step(self.pose, v, w, self.dt_s)
        self.t_s = round(self.t_s + self.dt_s, 9)

    def run(self, duration_s: float, until: object = None) -> None:
        for _ in range(round(duration_s / self.dt_s)):
            self.step()
            if until is not None and until(self):  # type: ignore[operator]
                return
