"""planner — where to drive: edge costs, OMPL and lattice planners, routes, CLI."""

from .edge_cost import DEFAULT_MAX_SLOPE_RAD, EnergyCost, warm_up_kernels
from .lattice import Lattice, LatticePath, string_pull
from .ompl_planner import OMPL_PLANNERS, PLANNERS, PlannerSettings, plan_route, refine_route, shortest_route
from .route import ROUTE_STATUSES, Route, evaluate_route

__all__ = [
    "EnergyCost",
    "DEFAULT_MAX_SLOPE_RAD",
    "warm_up_kernels",
    "Lattice",
    "LatticePath",
    "string_pull",
    "plan_route",
    "refine_route",
    "shortest_route",
    "PlannerSettings",
    "PLANNERS",
    "OMPL_PLANNERS",
    "Route",
    "ROUTE_STATUSES",
    "evaluate_route",
]

# --- mission helper; appended until the lead rewires this file
from .mission import MISSION_FORMAT_VERSION, MISSION_STATUSES, MissionResult, simulate_mission

__all__ += ["simulate_mission", "MissionResult", "MISSION_STATUSES", "MISSION_FORMAT_VERSION"]

# --- adaptive-mission helper (issue 4); appended until the lead rewires this file
from .adaptive import (
    ADAPTIVE_FORMAT_VERSION,
    ADAPTIVE_STATUSES,
    UPDATE_SCOPES,
    AdaptiveResult,
    AdaptiveSettings,
    LegRecord,
    ReplanRecord,
    UpdateRecord,
    run_adaptive_mission,
    validation_error,
)
from .learned_cost import DEFAULT_TABLE_OMEGAS_RADPS, DEFAULT_TABLE_SPEEDS_MPS, LearnedEnergyModel, LearnedModelTable

__all__ += [
    "LearnedEnergyModel",
    "LearnedModelTable",
    "DEFAULT_TABLE_SPEEDS_MPS",
    "DEFAULT_TABLE_OMEGAS_RADPS",
    "run_adaptive_mission",
    "AdaptiveSettings",
    "AdaptiveResult",
    "LegRecord",
    "UpdateRecord",
    "ReplanRecord",
    "ADAPTIVE_STATUSES",
    "ADAPTIVE_FORMAT_VERSION",
    "UPDATE_SCOPES",
    "validation_error",
]
