"""planner — where to drive: edge costs, OMPL, lattice and any-angle planners, replanning, routes, missions, exports."""

from energy import DEFAULT_ACCEL_MPS2, DEFAULT_YAW_ACCEL_RADPS2, drive_profile
from terrawatt_base.dask_client import dask_client
from terrawatt_base.errors import (
    BlockedPositionError,
    DataError,
    DataRepairWarning,
    FigureWarning,
    FileFormatError,
    FormatVersionError,
    GridMismatchError,
    ImplausibleDataWarning,
    InvalidParameterError,
    NodataError,
    NotFittedError,
    OptionalDependencyError,
    OutOfBoundsError,
    PlanningError,
    RecoveryWarning,
    TerrawattError,
    TerrawattWarning,
    UnitError,
    UnknownNameError,
)

from .batch import plan_batch
from .batch_pairs import BatchPairs, read_pairs_csv, read_sites_csv
from .batch_result import BATCH_FORMAT_VERSION, BATCH_STATUSES, BatchResult, BatchRow
from .coarse import COARSE_FALLBACKS, CoarseToFine, downsample_cost, plan_coarse_to_fine
from .coarse_geotiff import plan_coarse_to_fine_geotiff
from .edge_cost import DEFAULT_MAX_SLOPE_RAD, EnergyCost
from .energy_costmap import COSTMAP_STATISTICS, EnergyCostmap, energy_costmap, read_energy_geotiff, write_energy_geotiff
from .kernels import CostArrays
from .lattice import Lattice, LatticePath
from .learned_cost import (
    DEFAULT_TABLE_OMEGAS_RADPS,
    DEFAULT_TABLE_SPEEDS_MPS,
    LearnedEnergyModel,
    LearnedModelTable,
)
from .missions import (
    ADAPTIVE_FORMAT_VERSION,
    ADAPTIVE_STATUSES,
    MISSION_FORMAT_VERSION,
    MISSION_STATUSES,
    MONTE_CARLO_FORMAT_VERSION,
    UPDATE_SCOPES,
    AdaptiveResult,
    AdaptiveSettings,
    LegRecord,
    MissionDistributions,
    MissionResult,
    MonteCarloResult,
    ReplanRecord,
    UpdateRecord,
    adapted_model,
    fit_prior_model,
    run_adaptive_mission,
    simulate_mission,
    simulate_missions_mc,
    validation_error,
)
from .model_cost import (
    ModelCompatibilityWarning,
    ModelGrounds,
    check_model_robot,
    model_energy_cost,
    model_energy_model,
    model_grounds,
    robot_matches,
)
from .nav2_map import Nav2Map, read_nav2_map, write_nav2_costmap, write_nav2_map
from .planning import OMPL_PLANNERS, PLANNERS, compare_route, plan_route, shortest_route
from .reachability import lattice_move_energies, reachability
from .reachability_result import REACH_FORMAT_VERSION, REACH_LAYERS, Reachability
from .refine import refine_route, relax_path, string_pull
from .replan import IncrementalPlanner
from .risk import RouteEnergyInterval, risk_cost, route_energy_interval
from .ros_export import RouteBag, read_route_bag, route_pose_times_s, write_route_bag
from .route import ROUTE_STATUSES, Route, RouteComparison, evaluate_route
from .route_geojson import GEOJSON_FORMAT_VERSION, routes_geojson, write_geojson
from .settings import PlannerSettings
from .warmup import warm_up_kernels

__all__ = [
    # edge costs
    "EnergyCost",
    "CostArrays",
    "DEFAULT_MAX_SLOPE_RAD",
    "warm_up_kernels",
    "LearnedEnergyModel",
    "LearnedModelTable",
    # saved current models as edge costs, route intervals and risk
    "model_energy_cost",
    "model_energy_model",
    "model_grounds",
    "ModelGrounds",
    "check_model_robot",
    "robot_matches",
    "ModelCompatibilityWarning",
    "RouteEnergyInterval",
    "route_energy_interval",
    "risk_cost",
    "DEFAULT_TABLE_SPEEDS_MPS",
    "DEFAULT_TABLE_OMEGAS_RADPS",
    # planners and routes
    "Lattice",
    "LatticePath",
    "IncrementalPlanner",
    "string_pull",
    "plan_route",
    "refine_route",
    "relax_path",
    "compare_route",
    "shortest_route",
    "PlannerSettings",
    "PLANNERS",
    "OMPL_PLANNERS",
    "Route",
    "RouteComparison",
    "ROUTE_STATUSES",
    "evaluate_route",
    # big maps
    "plan_coarse_to_fine",
    "plan_coarse_to_fine_geotiff",
    "CoarseToFine",
    "downsample_cost",
    "COARSE_FALLBACKS",
    "routes_geojson",
    "write_geojson",
    "GEOJSON_FORMAT_VERSION",
    # ROS 2 and Nav2 out: the route as a bag, Nav2 maps, energy costmaps
    "write_route_bag",
    "read_route_bag",
    "RouteBag",
    "route_pose_times_s",
    "write_nav2_map",
    "write_nav2_costmap",
    "read_nav2_map",
    "Nav2Map",
    "energy_costmap",
    "EnergyCostmap",
    "COSTMAP_STATISTICS",
    "write_energy_geotiff",
    "read_energy_geotiff",
    # energy reachability
    "reachability",
    "Reachability",
    "lattice_move_energies",
    "REACH_FORMAT_VERSION",
    "REACH_LAYERS",
    # missions
    "simulate_mission",
    "drive_profile",
    "DEFAULT_ACCEL_MPS2",
    "DEFAULT_YAW_ACCEL_RADPS2",
    "MissionResult",
    "MISSION_STATUSES",
    "MISSION_FORMAT_VERSION",
    # batches and Monte Carlo missions (dask.distributed optional)
    "plan_batch",
    "BatchPairs",
    "read_pairs_csv",
    "read_sites_csv",
    "BatchResult",
    "BatchRow",
    "BATCH_STATUSES",
    "BATCH_FORMAT_VERSION",
    "dask_client",
    "simulate_missions_mc",
    "MissionDistributions",
    "MonteCarloResult",
    "MONTE_CARLO_FORMAT_VERSION",
    # the adaptive loop
    "run_adaptive_mission",
    "fit_prior_model",
    "validation_error",
    "adapted_model",
    "AdaptiveSettings",
    "AdaptiveResult",
    "LegRecord",
    "UpdateRecord",
    "ReplanRecord",
    "ADAPTIVE_STATUSES",
    "ADAPTIVE_FORMAT_VERSION",
    "UPDATE_SCOPES",
    # errors and warnings its users meet (defined in terrawatt_base.errors, the one hierarchy)
    "TerrawattError",
    "TerrawattWarning",
    "InvalidParameterError",
    "UnknownNameError",
    "DataError",
    "UnitError",
    "FileFormatError",
    "FormatVersionError",
    "NotFittedError",
    "GridMismatchError",
    "OutOfBoundsError",
    "NodataError",
    "OptionalDependencyError",
    "PlanningError",
    "BlockedPositionError",
    "DataRepairWarning",
    "FigureWarning",
    "RecoveryWarning",
    "ImplausibleDataWarning",
]
