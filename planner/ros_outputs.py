"""A planned route and its map for ROS 2 / Nav2 in one call: the route bag, the Nav2 maps, the J/m GeoTIFF."""

from __future__ import annotations

import os
from pathlib import Path

from terrain import TerrainMap

from .edge_cost import EnergyCost
from .energy_costmap import energy_costmap, write_energy_geotiff
from .nav2_map import write_nav2_costmap, write_nav2_map
from .ros_export import write_route_bag
from .route import Route

__all__ = ["nav2_targets", "write_ros_outputs"]


def nav2_targets(value: str | os.PathLike[str]) -> tuple[Path, Path]:
    """The YAML files of a Nav2 map pair named by ``value``: the occupancy map and the energy costmap.

    ``DIR/`` (a trailing separator) or an existing folder: ``DIR/map.yaml`` and
    ``DIR/map_energy.yaml``; ``NAME.yaml``: that file and ``NAME_energy.yaml``; any other
    ``PREFIX``: ``PREFIX.yaml`` and ``PREFIX_energy.yaml``. Each PGM lies beside its YAML.

    Examples
    --------
    >>> [p.name for p in nav2_targets("maps/site.yaml")]
    ['site.yaml', 'site_energy.yaml']
    """
    text = os.fspath(value)
    if text.endswith(("/", os.sep)) or Path(text).is_dir():
        base = Path(text) / "map"
    else:
        base = Path(text)
        if base.suffix.lower() in (".yaml", ".yml"):
            base = base.with_suffix("")
    return base.with_name(base.name + ".yaml"), base.with_name(base.name + "_energy.yaml")


def write_ros_outputs(
    route: Route,
    terrain: TerrainMap,
    cost: EnergyCost,
    *,
    bag: str | os.PathLike[str] | None = None,
    nav2_map: str | os.PathLike[str] | None = None,
    energy_geotiff: str | os.PathLike[str] | None = None,
    frame_origin_xy_m: tuple[float, float] = (0.0, 0.0),
) -> list[Path]:
    """Write the ROS 2 / Nav2 outputs asked for; return the files written, in that order.

    Parameters
    ----------
    route : Route
        The planned route; one not found writes no bag (the maps are written all the same).
    terrain : TerrainMap
        Its map.
    cost : EnergyCost
        The cost it was planned with (the poses' times, the occupied cells, the J/m costmap).
    bag : path, optional
        The route as a ROS 2 bag (:func:`planner.write_route_bag`: an ``.mcap`` file or a bag folder).
    nav2_map : str or path, optional
        Nav2 maps (:func:`nav2_targets`): the occupancy map (:func:`planner.write_nav2_map`) and
        the raw-mode energy costmap (:func:`planner.nav2_map.write_nav2_costmap`), YAML + PGM each.
    energy_geotiff : path, optional
        Each cell's mean energy per metre as a GeoTIFF (:func:`planner.energy_costmap.write_energy_geotiff`).
    frame_origin_xy_m : (float, float)
        The ROS map frame's origin in map coordinates (bag and Nav2 maps).

    Raises
    ------
    TerrawattError, OptionalDependencyError
        As the writers (e.g. rosbags or rasterio missing).
    """
    written: list[Path] = []
    if bag is not None and route.found:
        written.append(write_route_bag(bag, route, terrain, cost=cost, frame_origin_xy_m=frame_origin_xy_m))
    costmap = energy_costmap(cost) if nav2_map is not None or energy_geotiff is not None else None
    if nav2_map is not None and costmap is not None:
        occupancy_yaml, energy_yaml = nav2_targets(nav2_map)
        for yaml_path in (write_nav2_map(occupancy_yaml, terrain, cost=cost, frame_origin_xy_m=frame_origin_xy_m),
                          write_nav2_costmap(energy_yaml, costmap, frame_origin_xy_m=frame_origin_xy_m)):
            written += [yaml_path, yaml_path.with_suffix(".pgm")]
    if energy_geotiff is not None and costmap is not None:
        written.append(write_energy_geotiff(energy_geotiff, costmap))
    return written
