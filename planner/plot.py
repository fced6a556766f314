"""Plots of routes over a terrain map: hillshade, contours, ground classes, obstacles.

Where the figure goes (the rule of every terrawatt figure, :mod:`terrawatt_base.plot_target`): give
exactly one of ``path`` or ``ax=``. With ``path``, :func:`plot_routes` makes its own figure
(:func:`terrawatt_base.plot_target.new_figure`: matplotlib's object API on an Agg canvas, no
pyplot), writes a PNG atomically and returns the path; with ``ax`` it draws into the caller's
axes, writes nothing, leaves the caller's figure layout alone (no ``tight_layout``) and returns
``ax``, so a route map can be one panel of a larger figure.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrain import TerrainMap
from terrawatt_base import plot_target
from terrawatt_base.atomic import save_figure
from terrawatt_base.checks import check_choice, check_optional_real, check_real
from terrawatt_base.plot_target import check_ax, check_plot_target

__all__ = ["RouteLine", "plot_routes", "view_bounds", "PLOT_EXTENTS"]

#: What :func:`plot_routes` shows: the routes with a margin, or the whole map.
PLOT_EXTENTS = ("routes", "map")
#: Most raster samples drawn along a side: larger views are decimated for the background.
_MAX_PIXELS = 1600

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
    """One route to draw: a label, waypoints (m) and its energy (J).

    ``energy_band_j`` (optional): the central interval of the route energy (J, e.g. P10-P90
    of :class:`planner.RouteEnergyInterval`) and ``band_level`` its level; the legend then
    gives it and the route is drawn over a translucent halo marking that it is uncertain.
    """

    label: str
    waypoints_m: np.ndarray
    energy_j: float
    colour: str | None = None
    linestyle: str = "-"
    energy_band_j: tuple[float, float] | None = None
    band_level: float = 0.8


def view_bounds(
    tmap: TerrainMap,
    routes: Sequence[RouteLine],
    points_xy_m: Sequence[tuple[float, float]] = (),
    *,
    extent: str = "routes",
    margin_frac: float = 0.15,
) -> tuple[float, float, float, float]:
    """The ``(xmin, ymin, xmax, ymax)`` a route plot shows (m).

    ``extent="routes"``: the box of every route vertex and point, grown by ``margin_frac``
    of its larger side (at least 10 cells) on each side and clipped to the map; the whole
    map when there is nothing to show. ``extent="map"``: the map's bounds.

    Raises
    ------
    UnknownNameError
        ``extent`` not one of :data:`PLOT_EXTENTS`.
    InvalidParameterError
        ``margin_frac`` negative or not finite.
    """
    check_choice("extent", extent, PLOT_EXTENTS)
    margin_frac = check_real("margin_frac", margin_frac, low=0.0)
    bounds = tmap.bounds
    pts = [np.asarray(r.waypoints_m, float).reshape(-1, 2) for r in routes]
    pts += [np.asarray(p, float).reshape(1, 2) for p in points_xy_m]
    xy = np.vstack(pts) if pts else np.empty((0, 2))
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    if extent == "map" or xy.shape[0] == 0:
        return bounds
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    pad = max(margin_frac * float(np.max(hi - lo)), 10.0 * tmap.cell_size_m)
    return (max(bounds[0], lo[0] - pad), max(bounds[1], lo[1] - pad),
            min(bounds[2], hi[0] + pad), min(bounds[3], hi[1] + pad))


def plot_routes(
    tmap: TerrainMap,
    routes: Sequence[RouteLine],
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    path: str | os.PathLike[str] | None = None,
    *,
    ax: Any = None,
    title: str | None = None,
    dpi: int = 130,
    extent: str = "routes",
    margin_frac: float = 0.15,
    max_slope_rad: float | None = None,
) -> Path | Any:
    """Draw routes over the map and write a PNG (or draw into ``ax``).

    The background is a hillshade of the elevation with contour lines, the ground classes
    as a translucent colour layer (legend by name), obstacles in black, the cells steeper
    than ``max_slope_rad`` tinted and hatched, each route with its energy in the legend,
    and start / goal markers. By default the view zooms on the routes with a margin
    (:func:`view_bounds`), so a 7 km route on a 30 km DEM is not a speck; only the cells in
    view are drawn (decimated beyond 1,600 samples a side).

    Parameters
    ----------
    tmap : TerrainMap
        The map the routes were planned on.
    routes : sequence of RouteLine
        Routes to draw, in legend order.
    start_xy_m, goal_xy_m : (float, float)
        Start and goal (m).
    path : path-like, optional
        Output PNG file (written atomically); or give ``ax``.
    ax : matplotlib Axes, optional
        Draw into these axes instead of writing a file (the legend sits outside them, on
        the right).
    title : str, optional
        Axes title (default "terrawatt: minimum-energy route").
    dpi : int
        Resolution of the PNG (with ``path``).
    extent : {"routes", "map"}
        Zoom on the routes and points with a margin (default), or show the whole map.
    margin_frac : float
        Margin around the routes, as a fraction of their larger extent (>= 0).
    max_slope_rad : float, optional
        The cost's slope limit: cells steeper than it are drawn as a hatched layer.

    Returns
    -------
    Path or Axes
        The written file, or ``ax``.

    Raises
    ------
    InvalidParameterError
        Both or neither of ``path`` and ``ax``; ``path`` is a directory or lies under a file
        (checked before drawing); ``ax`` is not a matplotlib Axes; a bad ``margin_frac`` or
        ``max_slope_rad``.
    UnknownNameError
        ``extent`` not one of :data:`PLOT_EXTENTS`.
    """
    target = check_plot_target(path, ax)
    if target is None:
        ax = check_ax(ax)
    max_slope_rad = check_optional_real("max_slope_rad", max_slope_rad, low=0.0, low_inclusive=False)
    view = view_bounds(tmap, routes, [start_xy_m, goal_xy_m], extent=extent, margin_frac=margin_frac)
    if target is None:
        _draw_routes(ax, tmap, routes, start_xy_m, goal_xy_m, view, title, max_slope_rad)
        return ax

    fig, ax = plot_target.new_figure((10.5, 7.2))
    _draw_routes(ax, tmap, routes, start_xy_m, goal_xy_m, view, title, max_slope_rad)
    fig.tight_layout()
    return save_figure(fig, target, dpi=dpi, format="png")


def _draw_routes(ax: Any, tmap: TerrainMap, routes: Sequence[RouteLine], start_xy_m: tuple[float, float],
                 goal_xy_m: tuple[float, float], view: tuple[float, float, float, float], title: str | None,
                 max_slope_rad: float | None) -> None:
    """The route map of :func:`plot_routes`, drawn into ``ax`` over the ``view`` box (m)."""
    import matplotlib
    from matplotlib.colors import LightSource, ListedColormap
    from matplotlib.patches import Patch

    d = tmap.cell_size_m
    x0, y0 = tmap.origin_xy_m
    r0 = int(np.clip(np.floor((view[1] - y0) / d), 0, tmap.shape[0] - 2))
    c0 = int(np.clip(np.floor((view[0] - x0) / d), 0, tmap.shape[1] - 2))
    r1 = int(np.clip(np.ceil((view[3] - y0) / d), r0 + 2, tmap.shape[0]))
    c1 = int(np.clip(np.ceil((view[2] - x0) / d), c0 + 2, tmap.shape[1]))
    step = max(1, int(np.ceil(max(r1 - r0, c1 - c0) / _MAX_PIXELS)))
    window = (slice(r0, r1, step), slice(c0, c1, step))
    xmin, ymin = x0 + c0 * d, y0 + r0 * d
    xmax, ymax = x0 + c1 * d, y0 + r1 * d
    extent_xy = (xmin, xmax, ymin, ymax)
    z = tmap.elevation_m[window]
    light = LightSource(azdeg=315, altdeg=45)
    shade = light.hillshade(z[::-1], vert_exag=3.0, dx=d * step, dy=d * step)
    ax.imshow(shade, cmap="gray", extent=extent_xy, origin="upper", vmin=0, vmax=1, interpolation="bilinear")

    handles: list = []
    names = tmap.ground_names
    ground = tmap.ground[window]
    if names:
        ids = sorted(names)
        cycle = matplotlib.colormaps["tab10"]
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
            extent=extent_xy,
            origin="lower",
            interpolation="nearest",
        )
        handles += [Patch(facecolor=c, alpha=0.6, label=names[k]) for k, c in zip(ids, colours, strict=True)]

    xs, ys = tmap.cell_centres()
    xs, ys = xs[window[1]], ys[window[0]]
    levels = np.linspace(z.min(), z.max(), 12)[1:-1] if z.max() > z.min() else None
    if levels is not None:
        cs = ax.contour(xs, ys, z, levels=levels, colors="k", linewidths=0.4, alpha=0.5)
        ax.clabel(cs, fmt="%.0f m", fontsize=6)
    if max_slope_rad is not None:
        steep = tmap.slope_rad[window] > max_slope_rad
        if steep.any():
            ax.imshow(np.ma.masked_where(~steep, steep.astype(float)), cmap=ListedColormap(["#ff7043"]), alpha=0.35,
                      extent=extent_xy, origin="lower", interpolation="nearest")
            ax.contourf(xs, ys, steep.astype(float), levels=[0.5, 1.5], colors="none", hatches=["////"])
            label = f"steeper than {np.degrees(max_slope_rad):.0f} deg (blocked)"
            handles.append(Patch(facecolor="#ff7043", alpha=0.5, hatch="////", label=label))
    obstacle = tmap.obstacle[window]
    if obstacle.any():
        ax.imshow(
            np.ma.masked_where(~obstacle, obstacle.astype(float)),
            cmap=ListedColormap(["black"]),
            extent=extent_xy,
            origin="lower",
            interpolation="nearest",
        )
        handles.append(Patch(facecolor="black", label="obstacle"))

    default_colours = ["#d32f2f", "#1565c0", "#6a1b9a", "#ef6c00", "#00838f"]
    for i, route in enumerate(routes):
        wp = np.asarray(route.waypoints_m, float)
        colour = route.colour or default_colours[i % len(default_colours)]
        label = f"{route.label}: {route.energy_j:,.0f} J ({route.energy_j / 3600:.2f} Wh)"
        if route.energy_band_j is not None:
            lo, hi = route.energy_band_j
            label += (f"\n  energy mean {(lo + hi) / 2 / 3600:.2f} Wh, {100 * route.band_level:.0f} % interval "
                      f"{lo / 3600:.2f}-{hi / 3600:.2f} Wh")
            ax.plot(wp[:, 0], wp[:, 1], color=colour, linewidth=9.0, alpha=0.25, solid_capstyle="round")
        (line,) = ax.plot(wp[:, 0], wp[:, 1], color=colour, linestyle=route.linestyle, linewidth=2.2, label=label)
        handles.append(line)
    (s,) = ax.plot(*start_xy_m, marker="o", color="white", markeredgecolor="k", markersize=9, linestyle="", label="start")
    (g,) = ax.plot(*goal_xy_m, marker="*", color="gold", markeredgecolor="k", markersize=14, linestyle="", label="goal")
    handles += [s, g]
    ax.set_xlim(view[0], view[2])
    ax.set_ylim(view[1], view[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title or "terrawatt: minimum-energy route")
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, framealpha=0.9)
