"""OMPL for energy routes: the problem (space, validity, start/goal), the energy objective, planners by name.

- :mod:`.problem` — :class:`EnergyProblem`, validity from the compiled cell walk, seeding;
- :mod:`.objective` — :class:`EnergyObjective`, the directed drive-energy objective;
- :mod:`.planners` — the registry of planners (name -> factory and tuning) and one solve.

The public entry point is :func:`planner.plan_route`.
"""

from .objective import EnergyObjective
from .planners import OMPL_PLANNER_SPECS, OMPL_PLANNERS, OmplPlannerSpec, make_planner, solve
from .problem import EnergyProblem, seed_ompl

__all__ = [
    "EnergyObjective",
    "EnergyProblem",
    "OmplPlannerSpec",
    "OMPL_PLANNER_SPECS",
    "OMPL_PLANNERS",
    "make_planner",
    "solve",
    "seed_ompl",
]
