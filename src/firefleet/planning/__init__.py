"""Planning: the paths robots follow and the schedule of their desired points."""

from firefleet.planning.paths import PolynomialPath, straight_line
from firefleet.planning.trajectory import Trajectory

__all__ = ["PolynomialPath", "Trajectory", "straight_line"]
