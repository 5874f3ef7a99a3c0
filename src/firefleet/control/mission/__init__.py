"""The firefighting team's brain: exploration, allocation, the ring around a fire, refill.

The ``mission`` task kind calls, every tick (batch-first, N robots)::

    params = TacticsParams()                          # frozen; nav: NavigationParams
    state = tactics_init(grid, poses (N, 3), params)
    state, orders = tactics_step(state, obs, params, dt_s)

with ``obs = TacticsObservation(t_s, pose_m (N, 3), fire_xy_m (K, 2), fire_robot (K,),
person_xy_m (P, 2), person_robot (P,), ranges, tank_l (N,), damaged (N,), alive (N,),
looked (N,) | None)`` and ``orders = Orders(v_m_s, omega_rad_s, spray, mode, goal_xy_m)``
(``mode`` indexes :data:`MODES`). The state exposes ``covered`` (H, W) on the map grid,
``fires_xy_m`` (F, 2), ``fire_extent_m`` (F,), ``victims_xy_m`` (V, 2),
``victims_confirmed`` (V,), ``victims_confirmed_s`` (V,), ``assignment`` (N,),
``refilling`` (N,) (the kind fills these tanks at ``refill_l_s``) and ``messages_sent``.

What the team knows. The floor plan is known (the plans a fire brigade carries); the
fires, the smoke and the people are not. With the ideal link every robot receives what
all sent at the last tick, so the team keeps one knowledge, the union of all robots'
detections (:mod:`._knowledge`: fires as clusters of burning spots that keep their
extent, victims confirmed by repeated detections from within 2 m), and one coverage:
the cells a thermal camera's cone (51 deg, ``sensing_range_m``, line of sight) has seen,
on a coarse grid (:mod:`._coverage`). "Explored" is that coverage.

What the team does (:mod:`._plan`):

- *allocation*: the believed fires (each needing robots by its extent) and the victims
  not yet confirmed go to robots by an optimal assignment (Kuhn 1955,
  ``scipy.optimize.linear_sum_assignment``) of travel distances on the map (plus a
  penalty for a low tank, minus a bonus for keeping one's task), re-solved when a
  detection or a robot's state changes (no more often than ``replan_s``);
- *exploration*: the robots left free go to frontiers of the coverage (Yamauchi 1997)
  chosen with Burgard et al.'s (2005) utility, never two on one frontier;
- *fighting* (:mod:`._ring`, :mod:`._fight`): a fire's robots take slots on a ring of
  radius extent + ``standoff_m`` at the regular formation law's spacing (the fire as the
  virtual leader: ``control.formation``'s law relaxed to its equilibrium), assigned by
  the Hungarian method. A slot must be open, reachable (on the costmap that blocks the
  burning spots' surroundings) and have a shot: a burning spot between
  ``fire_block_m + 0.25`` and ``spray_range_m - 0.5`` away in line of sight; the
  polygon turns to make the most slots so, a slot still without moves along its ray,
  else to the nearest cell with a shot clear of the other slots. An arrived fighter
  turns to the nearest burning spot in reach and in sight and sprays (a spot sprayed
  out is soon seen not burning and dropped, so the aim sweeps on); one that stands
  ``reslot_s`` without a shot gets a new slot;
- *refill*: an empty tank sends its robot to a spot by the refill point (so does a
  tank below ``low_tank_frac`` of a robot off the fires while a fire burns); full
  again, it rejoins the allocation (its fire, if it still burns);
- *damage*: a damaged or dead robot stops, is dropped, and the team re-plans;
- *safety*: paths cost ``fire_cost`` more per metre within ``fire_keepout_m`` of a
  burning spot (A* goes round a fire where it can); a victim looked at
  ``victim_out_looks`` times without a person detection is dismissed as a false one
  (hot gas at a door) until seen again; while floor is unsearched ``explore_frac`` of
  the team keeps exploring (a fire's demand is cut to leave them); a robot that comes
  no closer to its goal in ``stall_s`` gives it up (explorer) or settles (fighter).

The kind's side of the contract: pass ``looked`` (which robots' thermal frames were
read this tick: only they count against a believed fire or victim), drain each tank
by ``flow_l_s`` while ``orders.spray``, and fill it by ``refill_l_s`` while
``state.refilling``.

Cost: the navigation controller (its DWA above all) is most of a tick's cost; a
lighter window (``DwaParams(n_v=5, n_omega=9, n_steps=8)``) is four times cheaper, and
on a 100 m floor ``plan_cell_m=0.5`` keeps the coarse grid at 40,000 cells.

Motion is the ``navigate`` kind's: :mod:`firefleet.control.navigation` (A* on the
inflated map, the fuzzy follower, give way, DWA on the sensed ranges), run every
``nav_period_s``, with :func:`~firefleet.control.navigation.navigation_retarget` when a
robot's goal changes. Cost per tick: coverage at ``coverage_period_s``, planning on
events, navigation at ``nav_period_s``; the ticks in between hold the last orders.

References
----------
B. Yamauchi, "A frontier-based approach for autonomous exploration", IEEE CIRA 1997.
W. Burgard, M. Moors, C. Stachniss, F. E. Schneider, "Coordinated multi-robot
exploration", IEEE Transactions on Robotics 21(3), 2005, 376-386.
H. W. Kuhn, "The Hungarian method for the assignment problem", Naval Research Logistics
Quarterly 2, 1955.
C. Wang, G. Xie and M. Cao, "Forming circle formations of anonymous mobile agents with
order preservation", IEEE Trans. Automatic Control 58(12), 2013.
"""

from firefleet.control.mission._coverage import CoarseMap
from firefleet.control.mission._knowledge import Knowledge
from firefleet.control.mission._params import MODES, Orders, TacticsObservation, TacticsParams
from firefleet.control.mission._ring import regular_ring
from firefleet.control.mission._step import tactics_step
from firefleet.control.mission._team import TacticsState, tactics_init

__all__ = [
    "MODES",
    "CoarseMap",
    "Knowledge",
    "Orders",
    "TacticsObservation",
    "TacticsParams",
    "TacticsState",
    "regular_ring",
    "tactics_init",
    "tactics_step",
]
