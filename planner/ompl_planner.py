"""Former home of plan_route and its helpers, kept as re-exports until every importer uses the new modules.

``plan_route``, ``shortest_route``, ``PLANNERS``, ``OMPL_PLANNERS`` live in
:mod:`planner.planning`, ``refine_route`` in :mod:`planner.refine`, ``PlannerSettings`` in
:mod:`planner.settings`, the OMPL problem in :mod:`planner.ompl`. Delete this module once
nothing imports it.
"""

from .planning import OMPL_PLANNERS, PLANNERS, plan_route, shortest_route
from .refine import refine_route
from .settings import PlannerSettings

__all__ = ["plan_route", "shortest_route", "refine_route", "PlannerSettings", "PLANNERS", "OMPL_PLANNERS"]
