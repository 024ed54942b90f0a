"""Plans out of tmpnav: waypoint files for the robots' navigation stacks (nav2)."""
