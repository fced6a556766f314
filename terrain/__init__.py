"""terrain — where the robot drives: a georeferenced stack of raster layers.

Public API: :class:`TerrainMap`, its builders (procedural, GeoTIFF, vector) and the library's
exception hierarchy (the per-cell current-model registry lives beside its users, in
:mod:`planner.registry`).
"""

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

from .georef import WGS84, lonlat_to_xy, transform_xy, utm_crs, xy_to_lonlat
from .geotiff import read_geotiff, write_geotiff
from .grid import Grid
from .io import read_map
from .landcover import LandcoverClasses, ground_classes_from_landcover, read_landcover_classes
from .procedural import (
    EXAMPLE_GOAL_XY_M,
    EXAMPLE_START_XY_M,
    example_map,
    flat_map,
    procedural_map,
    ramp_map,
    wall_map,
)
from .surface import surface_layers
from .terrain_map import MAP_FORMAT_VERSION, UNKNOWN_GROUND, TerrainMap
from .vector import (
    apply_geojson,
    rasterize_polygons,
    read_geojson,
    set_ground_from_polygons,
    set_obstacles_from_polygons,
)
from .windows import DemWindows, ElevationWindow, SurfaceWindow, iter_surface_windows, windowed_surface

__all__ = [
    # the map
    "TerrainMap",
    "Grid",
    "MAP_FORMAT_VERSION",
    "UNKNOWN_GROUND",
    # builders
    "procedural_map",
    "flat_map",
    "ramp_map",
    "wall_map",
    "example_map",
    "EXAMPLE_START_XY_M",
    "EXAMPLE_GOAL_XY_M",
    "read_map",
    "read_geotiff",
    "write_geotiff",
    "transform_xy",
    "lonlat_to_xy",
    "xy_to_lonlat",
    "utm_crs",
    "WGS84",
    "surface_layers",
    "iter_surface_windows",
    "windowed_surface",
    "SurfaceWindow",
    "DemWindows",
    "ElevationWindow",
    "rasterize_polygons",
    "set_ground_from_polygons",
    "set_obstacles_from_polygons",
    "read_geojson",
    "apply_geojson",
    "ground_classes_from_landcover",
    "read_landcover_classes",
    "LandcoverClasses",
    # errors and warnings
    "TerrawattError",
    "InvalidParameterError",
    "NodataError",
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
    "RecoveryWarning",
    "ImplausibleDataWarning",
    "FigureWarning",
]
