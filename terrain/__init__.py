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
