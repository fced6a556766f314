"""planner — where to drive: edge costs, OMPL and lattice planners, routes, CLI."""
