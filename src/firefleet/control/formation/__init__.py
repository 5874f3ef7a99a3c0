"""Formation control about a virtual leader (deliverable section 2.3, eqs. 6-8).

Every robot is a point ``p_k`` (a point mass, eq. 5, or a differential-drive robot's
look-ahead point) and the virtual leader sits at ``c``, the centre of the formation.
Two laws are implemented, both decentralised: robot k uses only the leader's state and
the other robots' positions.

``"deliverable"`` (section 2.3.1, after Rezaee and Abdollahi 2014)::

    f_k = -a (p_k - c) (|p_k - c|^2 - alpha^2)                    attraction, eq. 6
          + k_r q_k sum_{i != k} q_i (p_k - p_i) / |p_k - p_i|^3    Coulomb, eqs. 7-8

The attraction pulls every robot onto the circle of radius alpha about the leader; the
repulsion (magnitude ``k_r q_k q_i / r^2``, eq. 7, along the line between the robots)
spreads them. Its radial part also pushes every robot a little outside the circle,
and its tangential part is weak near equilibrium, which is why the deliverable sees
"an irregular polygon with all the vertices lying on the circle".

``"regular"`` (beyond the deliverable)::

    f_k = attraction (eq. 6) + K_s r_k (g_k+ - g_k-) / 2 t_k + contact_k

where ``g_k+`` and ``g_k-`` are the angles about the leader from robot k to the next
robot counter-clockwise and from the previous one (its two *angular neighbours*),
``r_k`` its distance from the leader, ``t_k`` the unit tangent of the circle through it
and ``K_s`` the spacing stiffness [N/m]. On the circle this is minus the gradient of
``K_s alpha^2 / 4 sum_k g_k^2`` with respect to the arc position, whose minimum under
``sum g_k = 2 pi`` is the regular polygon (equal gaps), in the order the robots already
have: the nearest-neighbour circle formation of Wang, Xie and Cao (2013). The radial
equilibrium is exactly on the circle (nothing radial but the attraction). ``contact_k``,
a short-range repulsion on the gap between the robots' bodies (Khatib's FIRAS potential,
1986), keeps robots apart on their way to the circle; it is zero once the gaps exceed
``contact_range_m``, so it leaves the polygon untouched when the polygon's side leaves
that much room (the runner shortens the range for a crowded circle).

Why not the tangential part of the Coulomb force (this law's first version): the
force between neighbours a distance s apart has a stiffness ``2 k_r q^2 / s^3``; on
a circle ``s = 2 pi alpha / N`` so, for a fixed radius, the stiffness grows as N^3
(100 robots on a 10 m circle: some 400 N/m per robot, at the stability limit of a
10 ms step, see :func:`stiffness_bound`), the far robots' pushes nearly cancel, so
the spacing is slow where it is not unstable, and the sum costs O(N^2) per step. The
angular-neighbour law has the stiffness ``2 K_s`` whatever N, costs one sort
(O(N log N)) and converges for any team (its gaps diffuse: the largest gap error of
a random start falls like ``1 / sqrt(t)`` at least, the slowest, longest, mode as
``exp(-K_s (2 pi / N)^2 t / (2 (B + k_d)))``).

Obstacles (circles) repel with the same FIRAS force on the gap between a robot's body
and the obstacle (Rezaee and Abdollahi 2014 treat obstacles as repulsive too).

The Coulomb sums (the deliverable's law) are evaluated in row blocks of at most
``block_elems`` pairs, so the memory is O(N + block), not O(N^2): no N x N x k
temporaries at any team size. The short-range contact pairs come from a k-d tree
(O(N log N)).

Stiffness: :func:`stiffness_bound` bounds the largest eigenvalue of the force's
Jacobian [N/m] (Gershgorin's theorem on the pairwise terms). A force held over a step
``h`` on a point mass with damping ``c`` (eq. 5) is stable only below ``2 c / h`` (400
N/m for the deliverable's c = 2 N s/m and 10 ms), and the Coulomb force (``2 k_r q^2 /
r^3`` per pair) and the contact force (``~3 eta / g^4``) exceed it when two robots come
close; the runner (:mod:`firefleet.sim.formation`) divides such steps.

References
----------
H. Rezaee and F. Abdollahi, "A decentralized cooperative control scheme with obstacle
avoidance for a team of mobile robots", IEEE Trans. Industrial Electronics 61(1), 2014.
O. Khatib, "Real-time obstacle avoidance for manipulators and mobile robots",
Int. J. Robotics Research 5(1), 1986 (the FIRAS potential).
C. Wang, G. Xie and M. Cao, "Forming circle formations of anonymous mobile agents with
order preservation", IEEE Trans. Automatic Control 58(12), 2013 (angular neighbours).
R. Sepulchre, D. A. Paley and N. E. Leonard, "Stabilization of planar collective motion
with limited communication", IEEE Trans. Automatic Control 53(3), 2008 (splay, i.e.
evenly spaced, circular formations from local phase couplings).
"""

from firefleet.control.formation._combined import (
    formation_force,
    formation_force_and_stiffness,
    stiffness_bound,
)
from firefleet.control.formation._forces import (
    BLOCK_ELEMS,
    FormationParams,
    circle_attraction,
    contact_pairs,
    contact_repulsion,
    coulomb_repulsion,
    obstacle_repulsion,
    ring_spacing,
    tangential_part,
)

__all__ = [
    "BLOCK_ELEMS",
    "FormationParams",
    "circle_attraction",
    "contact_pairs",
    "contact_repulsion",
    "coulomb_repulsion",
    "formation_force",
    "formation_force_and_stiffness",
    "obstacle_repulsion",
    "ring_spacing",
    "stiffness_bound",
    "tangential_part",
]
