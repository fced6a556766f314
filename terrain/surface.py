"""Surface derivatives of an elevation raster: gradients, slope and aspect (the one formula)."""

from __future__ import annotations

import numpy as np

__all__ = ["SURFACE_LAYERS", "surface_layers"]

#: The layers :func:`surface_layers` derives, in order.
SURFACE_LAYERS = ("slope", "aspect", "grad_x", "grad_y")


def surface_layers(elevation_m: np.ndarray, cell_size_m: float) -> dict[str, np.ndarray]:
    """Slope, aspect and gradients of an elevation raster (rows grow with y, columns with x).

    Central differences inside, one-sided at the raster's edges (:func:`numpy.gradient`);
    so a window read with a halo of one cell on each side that is not a raster edge gives,
    once the halo is cropped, exactly the values of the whole raster
    (:mod:`terrain.windows` relies on it).

    Parameters
    ----------
    elevation_m : ndarray, shape (rows, cols), rows and cols >= 2
        Elevation (m).
    cell_size_m : float
        Cell side (m).

    Returns
    -------
    dict
        ``slope`` (rad), ``aspect`` (downslope direction, rad counter-clockwise from +x),
        ``grad_x`` and ``grad_y`` (dz/dx, dz/dy); float64 arrays of the input's shape.

    Examples
    --------
    >>> import numpy as np
    >>> z = np.add.outer(np.zeros(3), np.arange(4.0))  # rises 1 m per 1 m cell eastwards
    >>> layers = surface_layers(z, 1.0)
    >>> float(layers["grad_x"][1, 1]), round(float(np.degrees(layers["slope"][1, 1])), 1)
    (1.0, 45.0)
    """
    gy, gx = np.gradient(np.asarray(elevation_m, dtype=np.float64), cell_size_m, cell_size_m)
    return {"slope": np.arctan(np.hypot(gx, gy)), "aspect": np.arctan2(-gy, -gx), "grad_x": gx, "grad_y": gy}
