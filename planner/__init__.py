"""planner — where to drive: edge costs, OMPL, lattice and any-angle planners, replanning, routes, missions, exports."""

from __future__ import annotations

from .batch import plan_batch
from .batch_pairs import BatchPairs, read_pairs_csv
from .batch_result import BatchResult
from .coarse import CoarseOptions, CoarseToFine
from .cost_spec import CostSpec
from .edge_cost import EnergyCost
from .energy_costmap import energy_costmap
from .lattice import Lattice
from .learned_cost import LearnedEnergyModel
from .missions import (
    AdaptiveResult,
    AdaptiveSettings,
    MissionDistributions,
    MissionResult,
    MonteCarloResult,
    Navigator,
    run_adaptive_mission,
    simulate_mission,
    simulate_missions_mc,
)
from .nav2_map import write_nav2_map
from .planning import PLANNERS, RouteSearch, plan_coarse_to_fine, plan_route
from .problem import PlanningProblem
from .reachability import reachability
from .reachability_result import Reachability
from .replan import IncrementalPlanner
from .ros_export import write_route_bag
from .route import Route
from .route_geojson import write_geojson
from .route_price import RouteEnergyInterval, price_route
from .settings import PlannerSettings
from .tables import CostTables
from .warmup import warm_up_kernels

__all__ = [
    "CostSpec",
    "EnergyCost",
    "CostTables",
    "PlannerSettings",
    "PLANNERS",
    "plan_route",
    "RouteSearch",
    "PlanningProblem",
    "Route",
    "Lattice",
    "IncrementalPlanner",
    "warm_up_kernels",
    "LearnedEnergyModel",
    "price_route",
    "RouteEnergyInterval",
    "plan_coarse_to_fine",
    "CoarseOptions",
    "CoarseToFine",
    "reachability",
    "Reachability",
    "simulate_mission",
    "MissionResult",
    "simulate_missions_mc",
    "MissionDistributions",
    "MonteCarloResult",
    "run_adaptive_mission",
    "Navigator",
    "AdaptiveSettings",
    "AdaptiveResult",
    "plan_batch",
    "BatchPairs",
    "BatchResult",
    "read_pairs_csv",
    "write_geojson",
    "write_route_bag",
    "write_nav2_map",
    "energy_costmap",
]

