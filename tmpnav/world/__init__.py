"""Stage 2: the world: occupancy grid, clearance, line of sight, ROS map import, checks."""

from tmpnav.world.build import World, build
from tmpnav.world.checks import check
from tmpnav.world.rosmap import MapImageError

__all__ = ["MapImageError", "World", "build", "check"]
