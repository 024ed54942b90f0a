"""Plans out of tmpnav: files for the robots' navigation stacks (nav2) and an executor that runs them."""
