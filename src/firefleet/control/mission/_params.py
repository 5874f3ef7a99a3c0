"""The team's constants, what it observes at a tick, and the orders it gives."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.control.navigation import NavigationParams
from firefleet.errors import InputError, check_fields
from firefleet.world import SprayParams

__all__ = [
    "MODES",
    "Orders",
    "TacticsObservation",
    "TacticsParams",
    "refill_points",
    "team_refill_points",
]

MODES = ("explore", "confirm", "fight", "refill", "idle", "damaged")
"""What a robot is doing (``Orders.mode`` holds the index in this tuple)."""

EXPLORE, CONFIRM, FIGHT, REFILL, IDLE, DAMAGED = range(len(MODES))


@dataclass(frozen=True, eq=False)
class TacticsParams:
    """The constants of the team's behaviour.

    Attributes
    ----------
    standoff_m : float
        Distance kept from a fire's edge: the ring's radius is the fire's extent plus
        this [m].
    spray_range_m : float
        Farthest a nozzle reaches [m]: a robot sprays while its fire's nearest burning
        spot is this close and in line of sight.
    spray_half_angle_rad : float
        A robot sprays only once its heading is this close to the fire's bearing [rad].
    tank_l : float
        Tank capacity [L].
    flow_l_s : float
        Nozzle flow [L/s] (the kind drains the tank; the team reads ``tank_l`` back).
    refill_l_s : float
        Rate at which the kind refills a tank at the refill point [L/s].
    refill_xy_m : (x, y), sequence of (x, y), or None
        The refill point [m], or several (a floor's hose cabinets: an empty tank goes to
        the one nearest by travel); ``None``: the centroid of the team's start poses
        (moved to the nearest open cell).
    refill_radius_m : float
        A robot refills within this distance of the refill point [m].
    low_tank_frac : float
        Below this fraction of the tank a fire costs a robot ``low_tank_penalty_m`` more.
    low_tank_penalty_m : float
        That penalty, in metres of travel [m].
    confirm_radius_m : float
        A person detection confirms a victim only from a robot this close to it [m]
        (the issue's 2 m).
    confirm_repeats : int
        Detections from that close needed to confirm a victim.
    sensing_range_m : float
        How far the thermal camera covers the building (the coverage, the fires'
        "looked at and not there") [m].
    hfov_rad : float
        The thermal camera's horizontal field of view [rad] (the Lepton's 51 deg).
    sensing_near_m : float
        Nearest distance at which the camera covers the floor [m]: the detector names a
        person from 1.8 m on and not at 1.6 m (measured with the mission's renderer;
        :mod:`._coverage`), so a cell nearer is not searched.
    person_half_width_m : float
        The covered cone narrows by ``atan(person_half_width_m / d)`` on each side at
        distance ``d`` (a person cut by the frame's border is not named) [m].
    view_far_m : float
        An explorer looks at the uncovered floor from a cell between
        ``sensing_near_m + 0.25`` and this far from it [m].
    fire_merge_m : float
        A fire detection within this distance of a believed fire's spots joins it [m].
    victim_merge_m : float
        A person detection within this distance of a believed victim is that victim [m].
    fire_out_looks : int
        Thermal frames in a row that look at a believed fire's spot (in the cone, in
        range, in line of sight) without detecting fire before the spot is believed out.
    victim_out_looks : int
        Looks in a row that see no person where an unconfirmed victim is believed
        before it is dismissed as a false detection (until detected again).
    explore_frac : float
        While floor is left uncovered, at least this fraction of the working robots
        (rounded up) keeps exploring: the fires' demands are cut to leave them.
    explore_fire_m : float
        No explorer's target lies within this distance of a believed burning spot [m]
        (the fire's hot gas damages robots; the fire's own robots go there).
    fire_keepout_m : float
        Paths are priced higher within this distance of a burning spot [m].
    fire_cost : float
        Extra planning cost per metre there (the map's free cells cost 1 per metre).
    fire_block_m : float
        Paths cost ten times ``fire_cost`` more per metre within this distance of a
        burning spot, and slots must be reachable without crossing there [m] (0: none).
    reslot_s : float
        A fighter standing at its slot this long without a burning spot in reach and
        in sight gets a new slot [s].
    flame_c : float
        A fire detection whose peak reads this or more is flames [C]: the fighters aim
        at such spots when their fire has any. Flames (800 C) saturate the Lepton's
        high-gain range (about 450 C); the hot gas a fire pushes out of its room reads
        less. On mission-office seed 1 (the code before the ledger, ``_water``) the
        detections reading 440 C or more lay a median 0.5 m from the nearest burning
        cell, those reading 300-440 C a median 1.25 m (the hot gas at the door), those
        under 250 C 2 m: 430 C keeps the first and drops the others.
    soak_l_m2 : float
        Water per area after which the team believes a cell out and its fuel soaked
        [L/m^2] (its ledger, ``_water``): the world's ``SprayParams.critical_l_m2``
        (Drysdale 2011, an energy balance); the fighters aim at flames on cells below.
    front_m : float
        The fighters aim at the ledger's dry cells within this distance of the flames
        [m]: the burning cells and the fuel the front reaches next (1 cm/s: 100 s),
        which, soaked, no longer ignites (a firebreak; ``_water.front_aim``).
    flame_guard_m : float
        A robot (not one going to refill) does not drive on towards believed flames
        nearer than this, within 60 deg of its heading; it turns away (0: off) [m]
        (``_fight.flame_guard``: the air within 0.5 m of a burning cell is hotter than
        the rating).
    retreat_c : float
        A fighter in air this hot leaves its place: the place joins the team's hot
        places, which slots keep ``standoff_m`` from [C] (a robot's rating is higher).
    robot_per_fire_m : float
        A fire needs one robot more per this many metres of its extent's radius.
    fire_robots_min, fire_robots_max : int
        Robots a fire needs, at least and at most.
    replan_s : float
        Least time between two allocations [s]; a detection or a robot's change of
        state triggers one, and exploration is re-planned at least every
        ``explore_replan_s``.
    explore_replan_s : float
        Longest time between two exploration plans [s].
    coverage_period_s : float
        How often the coverage and the frontiers are updated [s].
    nav_period_s : float
        How often the navigation controller runs [s] (the commands hold in between).
    plan_cell_m : float
        Cell side of the coarse grid on which coverage, frontiers and travel distances
        are computed [m] (a whole number of map cells; at least one).
    travel_limit_m : float
        Farthest a robot's exploration travel distances are searched [m].
    probe_m : float
        An explorer looks at the uncovered floor within this distance of its frontier
        cell [m] (:func:`._coverage.viewpoints`).
    stall_s : float
        An explorer that comes no closer to its goal in this time gives it up [s].
    scan_omega_rad_s : float
        Turn rate of a robot that reached its frontier and looks around [rad/s].
    face_gain : float
        Proportional gain turning a robot towards what it faces [1/s].
    keep_bonus_m : float
        Hysteresis: a robot's current task costs it this much less [m].
    nav : NavigationParams
        The navigation controller's constants.
    person_wall_m : float
        A person detection placed nearer than this to a wall of the plan is the wall
        [m] (:mod:`._people`: a person's centre stands half a body's depth from it).
    confirm_watch_s : float
        A confirmer that has stood this long where it can confirm its victim without
        confirming gives the victim up [s] (:func:`._knowledge.watch_victims`).
    view_min_m2 : float
        Least uncovered floor a viewpoint must cover to be worth a trip [m^2]
        (:mod:`._views`): two coarse cells at the default 0.25 m.
    view_max_candidates : int
        Most candidate viewpoints in the view table (the lattice thins on larger maps;
        :func:`._views.view_table`).
    view_clear_m : float
        A viewpoint lies this much farther from the walls than the navigation's
        ``robot_radius_m + margin_m``, where the place is wide enough (in a narrower one,
        its middle) [m].
    hot_forget_s : float
        Slots keep ``standoff_m`` from a hot place for this long after a robot last
        found it hot [s] (:mod:`._hot`: the gas by a door cools once its flames are
        soaked; a place kept for good barred the fighters from the fire).
    scout_m : float
        A fighter with no flame to aim at, or no slot with a shot, looks at the floor
        within this distance of its fire's spots, through open floor [m] (:mod:`._scout`).
    scout_stale_s : float
        ... that no camera has had in view for this long [s].
    scout_view_m : float
        How far a camera's look counts as seeing the floor for the fire [m].
    scout_near_m, scout_far_m : float
        A scout stands this near to this far from the floor it looks at [m].
    probe_lag_s : float
        The air probe's time constant [s] (the kind's default PT100: 10 s): a robot
        retreats when its reading plus this times the reading's rise per second
        reaches ``retreat_c`` (:func:`._hot.probe_estimate`).
    hot_keepout_m : float
        Paths are priced ``hot_cost`` more per metre within this distance of a live hot
        place [m] (:mod:`._keepout`; 0: not at all).
    hot_cost : float
        That price per metre (the map's free cells cost 1 per metre).
    spare_fight : bool
        Robots with nothing left to explore join a burning fire past
        ``fire_robots_max`` (:mod:`._spare`; default off until measured on every
        built-in).
    fire_forget_s : float
        A fire no detection has joined for this long is forgotten, all its spots (a
        fire still burning is detected again when a camera comes by) [s]; ``inf``:
        never (:func:`._knowledge.update_knowledge`). Spots nobody can get in view
        otherwise bar the way for good: the maze, seed 2, its fire out at 138 s and
        its last spots behind a wall, no person found in 900 s; forgotten after 120 s,
        both found (450 and 536 s).
    """

    standoff_m: float = 1.5
    spray_range_m: float = 3.0
    spray_half_angle_rad: float = math.radians(15.0)
    tank_l: float = 20.0
    flow_l_s: float = 0.5
    refill_l_s: float = 2.0
    refill_xy_m: tuple[float, float] | tuple[tuple[float, float], ...] | None = None
    refill_radius_m: float = 1.0
    low_tank_frac: float = 0.25
    low_tank_penalty_m: float = 20.0
    confirm_radius_m: float = 2.0
    confirm_repeats: int = 2
    sensing_range_m: float = 4.0
    hfov_rad: float = math.radians(51.0)
    sensing_near_m: float = 2.0
    person_half_width_m: float = 0.3
    view_far_m: float = 3.0
    fire_merge_m: float = 1.0
    victim_merge_m: float = 1.0
    fire_out_looks: int = 9
    victim_out_looks: int = 18
    explore_frac: float = 0.3
    explore_fire_m: float = 3.0
    fire_keepout_m: float = 1.5
    fire_cost: float = 20.0
    fire_block_m: float = 0.75
    reslot_s: float = 4.0
    retreat_c: float = 200.0
    flame_c: float = 430.0
    flame_guard_m: float = 0.8
    soak_l_m2: float = SprayParams.critical_l_m2  # the world's water per area (Drysdale)
    front_m: float = 1.0
    robot_per_fire_m: float = 1.0
    fire_robots_min: int = 2
    fire_robots_max: int = 6
    replan_s: float = 1.0
    explore_replan_s: float = 3.0
    coverage_period_s: float = 0.25
    nav_period_s: float = 0.1
    plan_cell_m: float = 0.25
    travel_limit_m: float = 15.0
    probe_m: float = 0.75
    stall_s: float = 10.0
    scan_omega_rad_s: float = 1.0
    face_gain: float = 2.0
    keep_bonus_m: float = 2.0
    nav: NavigationParams = field(default_factory=NavigationParams)
    # people
    person_wall_m: float = 0.15
    confirm_watch_s: float = 15.0
    # explore
    view_min_m2: float = 0.125
    view_max_candidates: int = 12000
    view_clear_m: float = 0.2
    # fight
    hot_forget_s: float = 30.0
    scout_m: float = 3.0
    scout_stale_s: float = 30.0
    scout_view_m: float = 5.0
    scout_near_m: float = 1.5
    scout_far_m: float = 3.0
    probe_lag_s: float = 10.0
    # route
    hot_keepout_m: float = 1.0
    hot_cost: float = 20.0
    # untuned2
    spare_fight: bool = False
    fire_forget_s: float = 120.0

    def __post_init__(self) -> None:
        check_fields(
            self,
            "tactics",
            positive=(
                "standoff_m",
                "spray_range_m",
                "spray_half_angle_rad",
                "tank_l",
                "flow_l_s",
                "refill_l_s",
                "refill_radius_m",
                "confirm_radius_m",
                "sensing_range_m",
                "hfov_rad",
                "view_far_m",
                "fire_merge_m",
                "victim_merge_m",
                "robot_per_fire_m",
                "reslot_s",
                "retreat_c",
                "flame_c",
                "soak_l_m2",
                "front_m",
                "replan_s",
                "explore_replan_s",
                "coverage_period_s",
                "nav_period_s",
                "plan_cell_m",
                "travel_limit_m",
                "scan_omega_rad_s",
                "stall_s",
                "face_gain",
                "view_min_m2",
                "hot_forget_s",
                "scout_m",
                "scout_stale_s",
                "scout_view_m",
                "scout_near_m",
                "scout_far_m",
            ),
            non_negative=(
                "view_clear_m",
                "low_tank_frac",
                "low_tank_penalty_m",
                "keep_bonus_m",
                "probe_m",
                "sensing_near_m",
                "person_half_width_m",
                "explore_frac",
                "explore_fire_m",
                "fire_keepout_m",
                "fire_cost",
                "fire_block_m",
                "flame_guard_m",
                "probe_lag_s",
            ),
        )
        # people
        check_fields(
            self,
            "tactics",
            positive=("confirm_watch_s",),
            non_negative=("person_wall_m",),
        )
        # route
        check_fields(self, "tactics", non_negative=("hot_keepout_m", "hot_cost"))
        if not self.fire_forget_s > 0.0:  # inf allowed: never
            raise InputError(f"tactics.fire_forget_s must be > 0, got {self.fire_forget_s}")
        for name in (
            "confirm_repeats",
            "fire_out_looks",
            "victim_out_looks",
            "fire_robots_min",
            "view_max_candidates",
        ):
            if int(getattr(self, name)) < 1:
                raise InputError(f"tactics.{name} must be >= 1, got {getattr(self, name)}")
        if self.fire_robots_max < self.fire_robots_min:
            raise InputError(
                f"tactics.fire_robots_max must be >= fire_robots_min ({self.fire_robots_min}), "
                f"got {self.fire_robots_max}"
            )
        if self.refill_xy_m is not None:
            refill_points(self.refill_xy_m)


def refill_points(xy_m: object) -> FloatArray:
    """One point (x, y) or a sequence of them as an array (P, 2) [m], P >= 1, finite.

    Examples
    --------
    >>> refill_points((1.0, 2.0)).tolist(), refill_points([(1, 2), (3, 4)]).shape
    ([[1.0, 2.0]], (2, 2))
    """
    try:
        a = np.asarray(xy_m, dtype=float)
    except (TypeError, ValueError):
        a = np.zeros((0, 3))
    if a.ndim == 1 and a.shape == (2,):
        a = a[None]
    if a.ndim != 2 or a.shape[0] == 0 or a.shape[1] != 2 or not np.isfinite(a).all():
        raise InputError(
            f"tactics.refill_xy_m must be a finite (x, y) or a list of them, got {xy_m}"
        )
    return a


def team_refill_points(xy_m: object | None, poses_m: FloatArray) -> FloatArray:
    """The refill points [m] (P, 2) of a team starting at ``poses_m`` (N, 3): ``xy_m``
    (:func:`refill_points`; ``TacticsParams.refill_xy_m``), else the start poses'
    centroid (one point). The team fills its tanks there (``tactics_init``), and the
    world takes the same points (``sim.kinds.mission``).

    Examples
    --------
    >>> import numpy as np
    >>> team_refill_points(None, np.array([[1.0, 2.0, 0.0], [3.0, 4.0, 1.0]]))
    array([[2., 3.]])
    >>> team_refill_points((5.0, 6.0), np.zeros((2, 3)))
    array([[5., 6.]])
    """
    if xy_m is not None:
        return refill_points(xy_m)
    out: FloatArray = np.asarray(poses_m, dtype=float)[:, :2].mean(axis=0)[None]
    return out


@dataclass(frozen=True, eq=False)
class TacticsObservation:
    """What the team knows at a tick (with the ideal link: what every robot sent).

    Attributes
    ----------
    t_s : float
        Time [s].
    pose_m : ndarray, shape (N, 3)
        Estimated poses x [m], y [m], heading [rad].
    fire_xy_m : ndarray, shape (K, 2)
        This tick's fire detections in the map frame [m].
    fire_robot : ndarray of int, shape (K,)
        The robot that made each.
    person_xy_m : ndarray, shape (P, 2)
        This tick's person detections in the map frame [m].
    person_robot : ndarray of int, shape (P,)
        The robot that made each.
    ranges : mapping of str to (ranges (N, B), bearings (B,) or (N, B))
        Range readings as :class:`~firefleet.control.navigation.NavigationInputs` takes
        them.
    tank_l : ndarray, shape (N,)
        Agent left in each tank [L].
    damaged : ndarray of bool, shape (N,)
        Robots damaged (they stop for good).
    alive : ndarray of bool, shape (N,)
        Robots working (a robot not alive is treated as damaged).
    looked : ndarray of bool, shape (N,) or None
        Robots whose thermal frame was taken (and run through the detector) this tick;
        ``None``: every robot's. Only a look that sees no fire where a fire is believed
        counts against it.
    air_c : ndarray, shape (N,) or None
        Air temperature at each robot (its PT100) [C]; ``None``: not measured.
    fire_peak_c : ndarray, shape (K,) or None
        Each fire detection's peak reading [C]; ``None``: not given (every detection
        counts as flames; the fighters aim at flames only).
    """

    t_s: float
    pose_m: FloatArray
    fire_xy_m: FloatArray
    fire_robot: IntArray
    person_xy_m: FloatArray
    person_robot: IntArray
    ranges: Mapping[str, tuple[ArrayLike, ArrayLike]]
    tank_l: FloatArray
    damaged: BoolArray
    alive: BoolArray
    looked: BoolArray | None = None
    air_c: FloatArray | None = None
    fire_peak_c: FloatArray | None = None


@dataclass(frozen=True, eq=False)
class Orders:
    """What every robot is told to do this tick (batch-first).

    Attributes
    ----------
    v_m_s : ndarray, shape (N,)
        Linear velocity set point [m/s].
    omega_rad_s : ndarray, shape (N,)
        Angular velocity set point [rad/s].
    spray : ndarray of bool, shape (N,)
        Nozzle open.
    mode : ndarray of int8, shape (N,)
        Index in :data:`MODES`.
    goal_xy_m : ndarray, shape (N, 2)
        Where each robot is going [m] (NaN: nowhere).
    """

    v_m_s: FloatArray
    omega_rad_s: FloatArray
    spray: BoolArray
    mode: np.ndarray
    goal_xy_m: FloatArray
