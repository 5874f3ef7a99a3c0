"""The mission's world and sensors stages: fire, heat, smoke, victims and water on the
building's field grid; range sensors, thermal frames through the real detector, the air
temperature at each robot.

The world stage (:class:`MissionWorld`) steps every ``world_step_s`` (not every tick):
fires ignite at their ``start_s``, the fire automaton spreads (world.fire_step), heat and
smoke diffuse (world.diffuse_step), victims breathe (world.victim_step), the robots'
spray of the last orders acts (world.spray_step) and drains their tanks, robots standing
at the refill point fill theirs, and a robot in air hotter than its rating is damaged
(its motors get no voltage from then on). Robots (their PT100 at ~0.3 m) and people on
the floor breathe the lower layer of a two-zone room fire, cooler and cleaner than the
hot upper layer the heat and smoke fields stand for: their air is taken as ambient plus
``LOWER_LAYER`` of the field's rise (lower-layer rises of 20-50 % of the upper layer's
are typical of room fire tests; Quintiere, Principles of Fire Behavior, 2nd ed., 2016,
ch. 11). It also keeps the run's log for the metrics
(the fields about every ``record_s``, every detection, when each true victim was found):
bookkeeping of what happened, never read by the team.

The sensors stage (:class:`MissionSensors`) gives every tick the range readings
(firefleet.sim.ranging on the map; teammates are obstacles), the air temperature at
each robot (its PT100, :mod:`firefleet.models.pt100`: the probe's sheath lags the lower
layer's air at the robot with its time constant, stepped with the world; the MAX31865
converts at the world's step, 10 Hz, as the real one does in 52-62 ms) and, every
``1 / rate_hz``, each robot's thermal frame rendered from the heat
field, the flames and the people (firefleet.sim.sensors.render_thermal_grid_depth) and
read by :func:`firefleet.perception.thermal.detect`, the detector that reads real FLIR
frames, with a depth image registered to it (the deliverable's stereo rig; 3 % noise)
for the ranges. Detections leave as (robot, kind, bearing, range, peak): the decision
places them on the map with its own pose estimate.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from firefleet._typing import FloatArray
from firefleet.control.mission import TacticsParams
from firefleet.models.pt100 import Pt100Params, pt100_read, pt100_step
from firefleet.perception.thermal import DetectionParams, detect
from firefleet.sim._thermal_grid import GridThermalScene
from firefleet.sim.drive import DriveState
from firefleet.sim.loop import Messages, WorldState
from firefleet.world import (
    BURNING,
    HEAT,
    SMOKE,
    UNBURNT,
    FieldParams,
    FireParams,
    FireState,
    OccupancyGrid,
    SprayParams,
    VictimParams,
    VictimState,
    diffuse_step,
    fire_init,
    fire_step,
    spray_step,
    victim_step,
)

__all__ = ["DETECTION_DTYPE", "MissionSensors", "MissionWorld", "MissionWorldState"]

LOWER_LAYER = 0.4
"""Rise of the air near the floor as a fraction of the field's (module notes)."""

SCENE = GridThermalScene(lower_fraction=LOWER_LAYER, ambient_c=HEAT.ambient)
"""What the cameras see: the floor and the lower walls in the cooler lower layer."""

DETECTION = DetectionParams(flame_core_c=TacticsParams().flame_c)
"""The robots' detector: the default thresholds, and a fire region holding flames
(pixels at the team's ``TacticsParams.flame_c``, 430 C, or more: the Lepton's low gain
saturates at about 450 C; flames burn at 800 C) reported as its flame cores, each
placed by its own bearing and stereo depth. A
robot looking at a burning room's door sees the hot gas above ``fire_min_c`` over most
of its frame; one region over it all put the fire on the door's frame, 1.5-3.5 m short
of the flames behind it (mission-office seed 2 at 520 s)."""

FIRE, PERSON = 0, 1
"""Detection kinds as the sensors stage numbers them."""

DETECTION_DTYPE = np.dtype(
    [
        ("t_s", "f8"),
        ("robot", "i4"),
        ("kind", "U6"),
        ("x_m", "f8"),
        ("y_m", "f8"),
        ("range_m", "f8"),
        ("peak_c", "f8"),
    ]
)
"""The ``detections`` array of a mission's result: each thermal detection on the map."""


def lower_layer(field_c: FloatArray, ambient_c: float) -> FloatArray:
    """Air temperature near the floor [C] under a field (upper-layer) temperature."""
    return np.asarray(ambient_c + LOWER_LAYER * (np.asarray(field_c, dtype=float) - ambient_c))


def _evolve(state: MissionWorldState, **changes: Any) -> MissionWorldState:
    """``dataclasses.replace`` without re-running the constructor (the loop's ticks
    between world steps change the time only; a hundred times a second)."""
    new = object.__new__(type(state))
    new.__dict__.update(state.__dict__)
    new.__dict__.update(changes)
    return new


def nearest_open(grid: OccupancyGrid, xy_m: FloatArray) -> tuple[int, int]:
    """The open cell of ``grid`` nearest to a point (the point's own when open)."""
    rc = grid.cell_of(np.asarray(xy_m, dtype=float))
    h, w = grid.shape
    r, c = int(np.clip(rc[0], 0, h - 1)), int(np.clip(rc[1], 0, w - 1))
    if not grid.occupied[r, c]:
        return r, c
    cells = np.argwhere(~grid.occupied)
    d = np.hypot(*(grid.center_of(cells) - np.asarray(xy_m)).T)
    best = cells[int(np.argmin(d))]
    return int(best[0]), int(best[1])


@dataclass(frozen=True)
class MissionWorldState(WorldState):
    """The world at a tick (besides the motors' load and the damaged robots' voltage).

    Attributes
    ----------
    t_s : float
        Time [s].
    fire : FireState
        On the field grid.
    temperature_c, smoke_per_m, wet_l_m2 : ndarray, shape (H, W)
        Heat [C], smoke optical density [1/m], water received [L/m^2].
    victims : VictimState
    damaged : ndarray of bool, shape (N,)
    tank_l : ndarray, shape (N,)
        Water left [L].
    spray, refill : ndarray of bool, shape (N,)
        The team's last orders: spraying, standing at the refill point.
    pose : ndarray, shape (N, 3)
        The robots' true poses when they were last ordered (the nozzles).
    next_s : float
        When the world steps next [s].
    started : ndarray of bool, shape (F,)
        Fires ignited so far.
    log : dict
        What happened, for the metrics (see :meth:`MissionWorld.final`).
    """

    t_s: float = 0.0
    fire: Any = None
    temperature_c: Any = None
    smoke_per_m: Any = None
    wet_l_m2: Any = None
    victims: Any = None
    damaged: Any = None
    tank_l: Any = None
    spray: Any = None
    refill: Any = None
    pose: Any = None
    next_s: float = 0.0
    started: Any = None
    log: Any = None
    probe_c: Any = None
    pt100_c: Any = None


@dataclass(frozen=True, eq=False)
class MissionWorld:
    """The mission's world stage (module notes).

    Attributes
    ----------
    field : OccupancyGrid
        The field grid (the map coarsened to ``world.field_cell_m``).
    fuel : ndarray, shape (H, W)
        Relative fuel load per field cell (0 for walls).
    fire_cells : ndarray of int, shape (F, 2)
        Each fire's first cell; ``fire_start_s`` (F,) when it ignites [s].
    victim_cells : ndarray of int, shape (V, 2)
        The field cell each victim breathes in; ``victim_xy_m`` (V, 2) where they are.
    refill_xy_m : ndarray, shape (P, 2)
        Where tanks fill [m] (a standpipe or hose cabinets): a robot the team says is
        refilling fills only if its true position lies within ``refill_reach_m`` of one
        (the team's word is checked against the truth, as the spray is; a robot whose
        pose estimate has drifted a metre and more from the truth stands short and
        gets nothing). None: anywhere (no check).
    """

    field: OccupancyGrid
    fuel: FloatArray
    fire_cells: np.ndarray
    fire_start_s: FloatArray
    victim_xy_m: FloatArray
    victim_cells: np.ndarray
    tank_l: float
    refill_l_s: float
    rating_c: float
    world_step_s: float
    record_s: float
    seed: int
    fire_params: FireParams = dataclasses.field(default_factory=FireParams)
    spray_params: SprayParams = dataclasses.field(default_factory=SprayParams)
    victim_params: VictimParams = dataclasses.field(default_factory=VictimParams)
    smoke_params: FieldParams = SMOKE  # world.fuel.smoke_yield scales its source
    found_radius_m: float = 2.0
    pt100: Pt100Params = dataclasses.field(default_factory=Pt100Params)
    contacts: Any = None  # _mission_contacts.ContactCheck: the robots' contacts every tick
    refill_xy_m: FloatArray | None = None
    refill_reach_m: float = 1.5  # the team stands within 1 m of a point by its estimate

    def at_refill(self, pose: FloatArray) -> np.ndarray:
        """Whether each robot's true position (N, 3) lies within ``refill_reach_m`` of
        a refill point (NaN poses: no; no points set: every robot)."""
        p = np.asarray(pose, dtype=float).reshape(-1, 3)
        if self.refill_xy_m is None:
            return np.ones(len(p), dtype=bool)
        q = np.asarray(self.refill_xy_m, dtype=float).reshape(-1, 2)
        d = np.hypot(p[:, None, 0] - q[None, :, 0], p[:, None, 1] - q[None, :, 1])
        out: np.ndarray = (d <= self.refill_reach_m).any(axis=1)
        return out

    def init(self, n_robots: int) -> MissionWorldState:
        """The world before the first tick: nothing burning yet, ambient air."""
        shape = self.field.shape
        no_fire = np.zeros(shape, dtype=bool)
        v = self.victim_xy_m.shape[0]
        log: dict[str, Any] = {
            "rng": np.random.default_rng(np.random.SeedSequence([self.seed, 15])),
            "snap_t": [],
            "fire_state": [],
            "temperature_c": [],
            "smoke_per_m": [],
            "wet_l_m2": [],
            "detections": [],
            "victims_found_s": np.full(v, np.nan),
            "all_out_s": np.nan,
            "explored_pct": 0.0,
            "next_record_s": 0.0,
            "water_used_l": np.zeros(n_robots),
        }
        if self.contacts is not None:
            log.update(self.contacts.init(n_robots))
        return MissionWorldState(
            load_torque_n_m=np.zeros((n_robots, 2)),
            voltage_scale=None,
            fire=fire_init(self.fuel, no_fire, self.fire_params),
            temperature_c=np.where(self.field.occupied, HEAT.ambient, HEAT.ambient),
            smoke_per_m=np.zeros(shape),
            wet_l_m2=np.zeros(shape),
            victims=VictimState(position_m=self.victim_xy_m, dose=np.zeros(v)),
            damaged=np.zeros(n_robots, dtype=bool),
            tank_l=np.full(n_robots, self.tank_l),
            spray=np.zeros(n_robots, dtype=bool),
            refill=np.zeros(n_robots, dtype=bool),
            pose=np.full((n_robots, 3), np.nan),
            next_s=0.0,
            started=np.zeros(self.fire_start_s.size, dtype=bool),
            log=log,
            probe_c=np.full(n_robots, HEAT.ambient),
            pt100_c=pt100_read(np.full(n_robots, HEAT.ambient), self.pt100),
        )

    def _snapshot(self, state: MissionWorldState, t_s: float) -> None:
        log = state.log
        if t_s < log["next_record_s"] - 1e-9:
            return
        log["snap_t"].append(t_s)
        log["fire_state"].append(state.fire.state.astype(np.int8))
        # 0.01 C (below the camera's NETD) and smoke to 0.01 /m in float16: the floor the
        # fire has not touched compresses to nothing in result.npz (mission-large, 1200 s
        # of 400 x 400 cells: temperature 768 -> 123 MB, smoke 768 -> 65 MB)
        log["temperature_c"].append(np.round(state.temperature_c, 2).astype(np.float32))
        log["smoke_per_m"].append(np.round(state.smoke_per_m, 2).astype(np.float16))
        # the water on the floor, to 0.01 L/m^2: where the sprays went (float16, like smoke)
        log["wet_l_m2"].append(np.round(state.wet_l_m2, 2).astype(np.float16))
        log["next_record_s"] = log["next_record_s"] + self.record_s

    def quiet_ticks(self, state: MissionWorldState, k: int, dt_s: float, limit: int) -> int:
        """How many of the ticks ``k, k + 1, ...`` (at most ``limit``) come before the next
        world step: :meth:`step` only moves the time (the loop's quiet stretches)."""
        m = 0
        while m < limit and (k + m) * dt_s < state.next_s - 1e-9:
            m += 1
        return m

    def step(self, state: MissionWorldState, t_s: float) -> MissionWorldState:
        """The world at ``t_s`` (it changes every ``world_step_s``)."""
        if t_s < state.next_s - 1e-9:
            return _evolve(state, t_s=t_s)
        dt = self.world_step_s
        fire = state.fire
        started = state.started
        due = (~started) & (self.fire_start_s <= t_s + 1e-9)
        if due.any():
            st = fire.state.copy()
            left = fire.burn_left_s.copy()
            for r, c in self.fire_cells[due]:
                if st[r, c] == UNBURNT and fire.fuel[r, c] > 0:
                    st[r, c] = BURNING
                    left[r, c] = self.fire_params.burn_s_per_fuel * fire.fuel[r, c]
            fire = FireState(state=st, burn_left_s=left, fuel=fire.fuel)
            started = started | due
        log = state.log
        fire = fire_step(fire, self.fire_params, dt, self.field.resolution_m, rng=log["rng"])
        temp, wet, tank = state.temperature_c, state.wet_l_m2, state.tank_l
        spraying = state.spray & ~state.damaged & (tank > 0.0)
        if spraying.any():
            fire, temp, wet, used = spray_step(
                fire, temp, wet, state.pose, spraying, self.field, self.spray_params, dt
            )
            used = np.minimum(used, tank)
            tank = tank - used
            log["water_used_l"] = log["water_used_l"] + used
        tank = np.where(
            state.refill & ~state.damaged & self.at_refill(state.pose),
            np.minimum(tank + self.refill_l_s * dt, self.tank_l),
            tank,
        )
        open_cells = ~self.field.occupied
        burning = fire.state == BURNING
        temp = diffuse_step(temp, open_cells, burning, HEAT, dt, self.field.resolution_m)
        smoke = diffuse_step(
            state.smoke_per_m, open_cells, burning, self.smoke_params, dt, self.field.resolution_m
        )
        vr, vc = self.victim_cells[:, 0], self.victim_cells[:, 1]
        victims = victim_step(
            state.victims,
            lower_layer(temp[vr, vc], HEAT.ambient),
            LOWER_LAYER * smoke[vr, vc],
            self.victim_params,
            dt,
        )
        damaged = state.damaged
        probe = state.probe_c
        if np.isfinite(state.pose[:, 0]).any():
            rc = self.field.cell_of(np.nan_to_num(state.pose[:, :2]))
            h, w = self.field.shape
            air = lower_layer(
                temp[np.clip(rc[:, 0], 0, h - 1), np.clip(rc[:, 1], 0, w - 1)], HEAT.ambient
            )
            placed = np.isfinite(state.pose[:, 0])
            damaged = damaged | (placed & (air > self.rating_c))
            probe = pt100_step(probe, np.where(placed, air, probe), self.pt100, dt)
        if started.all() and not burning.any() and np.isnan(log["all_out_s"]):
            log["all_out_s"] = t_s
        new = dataclasses.replace(
            state,
            t_s=t_s,
            fire=fire,
            temperature_c=temp,
            smoke_per_m=smoke,
            wet_l_m2=wet,
            victims=victims,
            damaged=damaged,
            tank_l=tank,
            voltage_scale=np.where(damaged, 0.0, 1.0) if damaged.any() else None,
            next_s=state.next_s + dt,
            probe_c=probe,
            pt100_c=pt100_read(probe, self.pt100),  # a conversion every world step
            started=started,
        )
        self._snapshot(new, t_s)
        return new

    def act(
        self, state: MissionWorldState, actions: Messages, pose: FloatArray
    ) -> MissionWorldState:
        """Take the team's orders (spray, refill) and its log entries (detections on the
        map, confirmed victims, coverage) at the robots' true poses."""
        log = state.log
        found = np.asarray(actions.get("victims_confirmed_xy_m", np.zeros((0, 2))))
        if found.size and self.victim_xy_m.size:
            d = np.hypot(*(self.victim_xy_m[:, None, :] - found[None, :, :]).transpose(2, 0, 1))
            hit = (d <= self.found_radius_m).any(axis=1) & np.isnan(log["victims_found_s"])
            log["victims_found_s"][hit] = state.t_s
        det = actions.get("detections")
        if det is not None and len(det):
            log["detections"].append(np.asarray(det))
        if "explored_pct" in actions:
            log["explored_pct"] = float(np.asarray(actions["explored_pct"]))
        return _evolve(
            state,
            spray=np.asarray(actions.get("spray", state.spray), dtype=bool),
            refill=np.asarray(actions.get("refill", state.refill), dtype=bool),
            pose=np.array(pose, dtype=float),
        )

    def final(self, state: MissionWorldState) -> Messages:
        """The log: ``field_t_s`` (T'), ``fire_state`` (T', H, W) int8, ``temperature_c``
        (T', H, W) float32, ``smoke_per_m`` [1/m] and ``wet_l_m2`` (the water sprayed on
        each cell) [L/m^2] float16, ``detections`` (structured), per victim
        ``victims_found_s`` and ``victim_dose``, per robot ``damaged``, ``water_used_l``,
        and ``all_out_s``, ``explored_pct``, the fuel and the fires' cells; with
        ``contacts``, the robots' points near walls and who touched another robot
        (:class:`~firefleet.sim.kinds._mission_contacts.ContactCheck`)."""
        log = state.log
        self._snapshot(dataclasses.replace(state), state.t_s)
        rows = np.concatenate(log["detections"]) if log["detections"] else np.zeros((0, 7))
        det = np.zeros(rows.shape[0], dtype=DETECTION_DTYPE)
        if rows.shape[0]:
            det["t_s"], det["robot"] = rows[:, 0], rows[:, 1].astype(int)
            det["kind"] = np.where(rows[:, 2] == FIRE, "fire", "person")
            det["x_m"], det["y_m"], det["range_m"], det["peak_c"] = rows[:, 3:7].T
        return {
            "field_t_s": np.asarray(log["snap_t"], dtype=float),
            "fire_state": np.asarray(log["fire_state"], dtype=np.int8),
            "temperature_c": np.asarray(log["temperature_c"], dtype=np.float32),
            "smoke_per_m": np.asarray(log["smoke_per_m"], dtype=np.float16),
            "wet_l_m2": np.asarray(log["wet_l_m2"], dtype=np.float16),
            "detections": det,
            "victims_found_s": log["victims_found_s"].copy(),
            "victim_dose": state.victims.dose.copy(),
            "damaged": state.damaged.astype(float),
            "water_used_l": log["water_used_l"].copy(),
            "all_out_s": np.array([log["all_out_s"]]),
            "explored_pct": np.array([log["explored_pct"]]),
            "fire_started": state.started.astype(float),
            "fuel": self.fuel.astype(np.float32),
            **(self.contacts.final(log) if self.contacts is not None else {}),
        }


@dataclass(frozen=True, eq=False)
class MissionSensors:
    """The mission's sensors stage (module notes).

    Attributes
    ----------
    world : MissionWorld
    ranging : sensors stage or None
        The range sensors (firefleet.sim.ranging.RangeSensors) on the map.
    camera : ThermalCameraParams
    every : int
        Ticks between thermal frames.
    dt_s : float
        The tick [s].
    rng : numpy.random.Generator
        Thermal noise and the depth noise.
    scans_in_stretch : bool
        Whether the range scans due in a quiet stretch are made there (:meth:`skip`),
        the stretch going on: for a decision that reads the ranges only at ticks that
        are never quiet (the mission's: at its navigation ticks).
    """

    world: MissionWorld
    ranging: Any
    camera: Any
    every: int
    dt_s: float
    rng: np.random.Generator
    depth_noise: float = 0.03
    visible: Any = None  # a stereo-only team's camera (_mission_smoke.VisibleDetector)
    scans_in_stretch: bool = False  # the range scans inside the quiet stretches (skip)

    def quiet_ticks(self, world: MissionWorldState, k: int, dt_s: float, limit: int) -> int:
        """How many of the ticks ``k, k + 1, ...`` (at most ``limit``) read nothing new: no
        thermal frame, no range scan due (the loop's quiet stretches; :meth:`skip`)."""
        m = 0
        while m < limit and (k + m) % self.every != 0:
            m += 1
        if m and self.ranging is not None:
            m = min(m, self.ranging.quiet_ticks(m, self.scans_in_stretch))
        return m

    def quiet_readings(self, readings: Messages) -> Messages:
        """What :meth:`read` gives at a quiet tick (:meth:`quiet_ticks`) after the tick
        that read ``readings``: the same ranges (held between scans), air, tanks and
        damage (the world steps at no quiet tick), no look and no detection."""
        n = np.shape(readings["looked"])[0]
        return {**readings, "looked": np.zeros(n), "thermal_detections": np.zeros((0, 5))}

    def skip(self, world: MissionWorldState, poses: FloatArray) -> None:
        """What :meth:`read` does at quiet ticks with the true poses (m, N, 3) of each:
        the range sensors count the ticks (``scans_in_stretch``: and scan at those due,
        from those poses), the contact test notes each tick's poses."""
        if self.ranging is not None:
            self.ranging.skip(poses.shape[0], world, poses if self.scans_in_stretch else None)
        if self.world.contacts is not None:
            self.world.contacts.check_ticks(world.log, poses)

    def read(self, world: MissionWorldState, drive: DriveState) -> Messages:
        """Readings at this tick, by name (module notes)."""
        out: dict[str, FloatArray] = {}
        if self.ranging is not None:
            out.update(self.ranging.read(world, drive))
        pose = drive.pose
        if self.world.contacts is not None:  # at every tick: the poses are kept at 10 Hz
            self.world.contacts.check(world.log, pose)
        out["air_c"] = world.pt100_c  # the PT100's last conversion (module notes)
        out["tank_l"] = np.asarray(world.tank_l, dtype=float)
        out["damaged"] = world.damaged.astype(float)
        k = round(world.t_s / self.dt_s)
        looked = k % self.every == 0
        out["looked"] = np.full(pose.shape[0], float(looked))
        if not looked:
            out["thermal_detections"] = np.zeros((0, 5))
            return out
        if self.visible is not None:  # no thermal camera: the visible one, through smoke
            out["thermal_detections"] = self.visible.read(world, drive.pose, world.damaged)
            return out
        from firefleet.sim.sensors import render_thermal_grid_depth

        frames, depth = render_thermal_grid_depth(
            drive.pose,
            self.world.field,
            world.temperature_c,
            world.fire.state == BURNING,
            self.world.victim_xy_m,
            self.camera,
            rng=self.rng,
            scene=SCENE,
        )
        noise = self.rng.standard_normal(depth.shape)  # depth * (1 + sigma z), in place
        noise *= self.depth_noise
        noise += 1.0
        noise *= depth
        depth = noise
        rows: list[list[float]] = []
        for i in range(frames.shape[0]):
            if world.damaged[i]:
                continue
            for d in detect(frames[i], depth_m=depth[i], params=DETECTION).detections:
                if d.kind not in ("fire", "person") or d.range_m is None:
                    continue
                kind = FIRE if d.kind == "fire" else PERSON
                rows.append([float(i), float(kind), d.bearing_rad, float(d.range_m), d.peak_c])
        out["thermal_detections"] = np.array(rows, dtype=float).reshape(-1, 5)
        return out
