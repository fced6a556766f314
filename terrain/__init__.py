"""terrain — where the robot drives: a georeferenced stack of raster layers.

Public API: :class:`TerrainMap` and the library's exception hierarchy.
"""

from .errors import (
    BlockedPositionError,
    DataError,
    DataRepairWarning,
    FileFormatError,
    FormatVersionError,
    GridMismatchError,
    InvalidParameterError,
    NotFittedError,
    OptionalDependencyError,
    OutOfBoundsError,
    PlanningError,
    TerrawattError,
    TerrawattWarning,
    UnitError,
    UnknownNameError,
)
from .grid import MAP_FORMAT_VERSION, UNKNOWN_GROUND, TerrainMap

__all__ = [
    "TerrainMap",
    "MAP_FORMAT_VERSION",
    "UNKNOWN_GROUND",
    "TerrawattError",
    "InvalidParameterError",
    "GridMismatchError",
    "OutOfBoundsError",
    "UnknownNameError",
    "FileFormatError",
    "FormatVersionError",
    "NotFittedError",
    "DataError",
    "UnitError",
    "PlanningError",
    "BlockedPositionError",
    "OptionalDependencyError",
    "TerrawattWarning",
    "DataRepairWarning",
]

# --- terrain helper (procedural, vector, geotiff); appended until the lead rewires this file
from .procedural import (
    EXAMPLE_GOAL_XY_M,
    EXAMPLE_START_XY_M,
    example_map,
    flat_map,
    procedural_map,
    ramp_map,
    wall_map,
)

__all__ += [
    "procedural_map",
    "flat_map",
    "ramp_map",
    "wall_map",
    "example_map",
    "EXAMPLE_START_XY_M",
    "EXAMPLE_GOAL_XY_M",
]
from .geotiff import read_geotiff, write_geotiff
from .vector import (
    apply_geojson,
    rasterize_polygons,
    read_geojson,
    set_ground_from_polygons,
    set_obstacles_from_polygons,
)

__all__ += [
    "rasterize_polygons",
    "set_ground_from_polygons",
    "set_obstacles_from_polygons",
    "read_geojson",
    "apply_geojson",
    "read_geotiff",
    "write_geotiff",
]
from .registry import (
    PRIOR_MODEL_ID,
    REGISTRY_FORMAT_VERSION,
    CellModelRegistry,
    CurrentModelProtocol,
    FlaggedRegion,
    ModelRecord,
    RegistryVersion,
    UpdateDecision,
    UpdatePolicy,
)

__all__ += [
    "CellModelRegistry",
    "CurrentModelProtocol",
    "UpdatePolicy",
    "FlaggedRegion",
    "RegistryVersion",
    "UpdateDecision",
    "ModelRecord",
    "REGISTRY_FORMAT_VERSION",
    "PRIOR_MODEL_ID",
]
