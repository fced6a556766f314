"""The pitch of a logged run read off a map: the slope along the heading under each logged pose."""

from __future__ import annotations

import numpy as np

from terrain.terrain_map import TerrainMap
from terrawatt_base.errors import DataError, InvalidParameterError

from .interaction_log import InteractionLog

__all__ = ["log_slope_rad"]


def log_slope_rad(terrain: TerrainMap, log: InteractionLog) -> np.ndarray:
    """Pitch along the heading at each pose of ``log`` on ``terrain`` (rad, positive nose-up).

    The map's elevation gradient, interpolated bilinearly under each logged ``(x, y)``, taken
    along the logged heading — as the truth simulator drives and the planner prices a move.

    Parameters
    ----------
    terrain : TerrainMap
        The map the run drove on.
    log : InteractionLog
        A run with poses (``pose_xyh``, map metres and heading).

    Returns
    -------
    numpy.ndarray, shape (N,)

    Raises
    ------
    InvalidParameterError
        ``terrain`` is not a TerrainMap.
    DataError
        The log has no poses.
    OutOfBoundsError
        A pose off the map.
    """
    if not isinstance(terrain, TerrainMap):
        raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
    if log.pose_xyh is None:
        raise DataError(f"the slope under a run needs its poses; {log.meta.source!r} has none")
    pose = log.pose_xyh
    x, y, h = pose[:, 0], pose[:, 1], pose[:, 2]
    gx = np.asarray(terrain.sample("grad_x", x, y, method="bilinear"), dtype=np.float64)
    gy = np.asarray(terrain.sample("grad_y", x, y, method="bilinear"), dtype=np.float64)
    return np.arctan(gx * np.cos(h) + gy * np.sin(h))
