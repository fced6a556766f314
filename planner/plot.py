"""Plots of routes over a terrain map: hillshade, contours, ground classes, obstacles."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from terrain import TerrainMap
from terrain.atomic import check_output_path, save_figure

__all__ = ["RouteLine", "plot_routes"]

# Colours for ground classes by name; other names get colours from a qualitative map.
_GROUND_COLOURS = {
    "asphalt": "#4d4d4d",
    "concrete": "#9e9e9e",
    "stone": "#8d6e63",
    "gravel": "#a1887f",
    "grass": "#66bb6a",
    "sand": "#fdd835",
    "snow": "#e3f2fd",
    "coated_wood": "#bcaaa4",
    "flooring": "#d7ccc8",
}


@dataclass(frozen=True)
class RouteLine:
    """One route to draw: a label, waypoints (m) and its energy (J)."""

    label: str
    waypoints_m: np.ndarray
    energy_j: float
    colour: str | None = None
    linestyle: str = "-"


def plot_routes(
    tmap: TerrainMap,
    routes: Sequence[RouteLine],
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    path: str | os.PathLike[str],
    *,
    title: str | None = None,
    dpi: int = 130,
) -> Path:
    """Draw routes over the map and write a PNG.

    The background is a hillshade of the elevation with contour lines, the ground classes
    as a translucent colour layer (legend by name), obstacles in black, each route with its
    energy in the legend, and start / goal markers.

    Parameters
    ----------
    tmap : TerrainMap
        The map the routes were planned on.
    routes : sequence of RouteLine
        Routes to draw, in legend order.
    start_xy_m, goal_xy_m : (float, float)
        Start and goal (m).
    path : path-like
        Output PNG file (written atomically).

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    InvalidParameterError
        ``path`` is a directory or lies under a file (checked before drawing).
    """
    path = check_output_path(path, "path")
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.colors import LightSource, ListedColormap
    from matplotlib.patches import Patch

    xmin, ymin, xmax, ymax = tmap.bounds
    extent = (xmin, xmax, ymin, ymax)
    z = tmap.elevation_m
    fig, ax = plt.subplots(figsize=(10.5, 7.2))
    light = LightSource(azdeg=315, altdeg=45)
    shade = light.hillshade(z[::-1], vert_exag=3.0, dx=tmap.cell_size_m, dy=tmap.cell_size_m)
    ax.imshow(shade, cmap="gray", extent=extent, origin="upper", vmin=0, vmax=1, interpolation="bilinear")

    handles: list = []
    names = tmap.ground_names
    ground = tmap.ground
    if names:
        ids = sorted(names)
        cycle = plt.get_cmap("tab10")
        colours = [_GROUND_COLOURS.get(names[k], cycle(i % 10)) for i, k in enumerate(ids)]
        index = np.full(ground.shape, np.nan)
        for i, k in enumerate(ids):
            index[ground == k] = i
        ax.imshow(
            np.ma.masked_invalid(index),
            cmap=ListedColormap(colours),
            vmin=-0.5,
            vmax=len(ids) - 0.5,
            alpha=0.35,
            extent=extent,
            origin="lower",
            interpolation="nearest",
        )
        handles += [Patch(facecolor=c, alpha=0.6, label=names[k]) for k, c in zip(ids, colours, strict=True)]

    xs, ys = tmap.cell_centres()
    levels = np.linspace(z.min(), z.max(), 12)[1:-1] if z.max() > z.min() else None
    if levels is not None:
        cs = ax.contour(xs, ys, z, levels=levels, colors="k", linewidths=0.4, alpha=0.5)
        ax.clabel(cs, fmt="%.0f m", fontsize=6)
    if tmap.obstacle.any():
        ax.imshow(
            np.ma.masked_where(~tmap.obstacle, tmap.obstacle.astype(float)),
            cmap=ListedColormap(["black"]),
            extent=extent,
            origin="lower",
            interpolation="nearest",
        )
        handles.append(Patch(facecolor="black", label="obstacle"))

    default_colours = ["#d32f2f", "#1565c0", "#6a1b9a", "#ef6c00", "#00838f"]
    for i, route in enumerate(routes):
        wp = np.asarray(route.waypoints_m, float)
        (line,) = ax.plot(
            wp[:, 0],
            wp[:, 1],
            color=route.colour or default_colours[i % len(default_colours)],
            linestyle=route.linestyle,
            linewidth=2.2,
            label=f"{route.label}: {route.energy_j:,.0f} J ({route.energy_j / 3600:.2f} Wh)",
        )
        handles.append(line)
    (s,) = ax.plot(*start_xy_m, marker="o", color="white", markeredgecolor="k", markersize=9, linestyle="", label="start")
    (g,) = ax.plot(*goal_xy_m, marker="*", color="gold", markeredgecolor="k", markersize=14, linestyle="", label="goal")
    handles += [s, g]
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title or "terrawatt: minimum-energy route")
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, framealpha=0.9)
    fig.tight_layout()

    try:
        return save_figure(fig, path, dpi=dpi, format="png")
    finally:
        plt.close(fig)
