"""A planned route and its map for ROS 2 / Nav2 in one call: the route bag, the Nav2 maps, the J/m GeoTIFF."""

from __future__ import annotations

import importlib.util
import math
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from terrain import InvalidParameterError, OptionalDependencyError, TerrainMap
from terrain.georef import import_rasterio
from terrawatt_base.atomic import check_output_path, probe_writable, refuse_overwriting_inputs

from .edge_cost import EnergyCost
from .energy_costmap import energy_costmap, write_energy_geotiff
from .nav2_map import nav2_map_paths, write_nav2_costmap, write_nav2_map
from .ros_export import check_route_bag_path, write_route_bag
from .route import Route

__all__ = ["nav2_targets", "check_ros_outputs", "write_ros_outputs", "ROS_OUTPUTS"]

#: The outputs of :func:`write_ros_outputs`, as :func:`check_ros_outputs`' messages name them by default.
ROS_OUTPUTS = ("bag", "nav2_map", "energy_geotiff", "frame_origin_xy_m")


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


def check_ros_outputs(
    *,
    bag: str | os.PathLike[str] | None = None,
    nav2_map: str | os.PathLike[str] | None = None,
    energy_geotiff: str | os.PathLike[str] | None = None,
    frame_origin_xy_m: Any = None,
    inputs: Iterable[str | os.PathLike[str] | None] = (),
    others: Iterable[str | os.PathLike[str]] = (),
) -> None:
    """Before any work: the outputs :func:`write_ros_outputs` would write can be written, and their extras are installed.

    Parameters
    ----------
    bag, nav2_map, energy_geotiff, frame_origin_xy_m : optional
        As :func:`write_ros_outputs`; ``frame_origin_xy_m`` None when not given (it needs ``bag`` or ``nav2_map``).
    inputs : iterable of path-like
        The caller's input files (None for one not given): no output may replace one.
    others : iterable of path-like
        The other files the caller writes: no output may be one of them, nor two outputs one path.

    Raises
    ------
    InvalidParameterError
        ``frame_origin_xy_m`` alone or not two finite numbers; a path of the wrong kind or
        suffix; an output that would replace an input or another output; an unwritable folder.
    OptionalDependencyError
        ``bag`` without rosbags, ``energy_geotiff`` without rasterio.

    Each error names the parameter(s) of :data:`ROS_OUTPUTS` it is about
    (:attr:`~terrawatt_base.errors.TerrawattError.parameter`; in backticks, ```bag```, where the word is also prose
    or a path in the message may hold it).

    Examples
    --------
    >>> check_ros_outputs()  # nothing asked: nothing to check
    >>> check_ros_outputs(frame_origin_xy_m=(1.0, 2.0))
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.InvalidParameterError: frame_origin_xy_m applies to `bag` and nav2_map; give one of them
    """
    if frame_origin_xy_m is not None and bag is None and nav2_map is None:
        raise InvalidParameterError("frame_origin_xy_m applies to `bag` and nav2_map; give one of them",
                                    parameter=("frame_origin_xy_m", "bag", "nav2_map"))
    if frame_origin_xy_m is not None and not (len(frame_origin_xy_m) == 2 and all(
            isinstance(v, (int, float)) and math.isfinite(v) for v in frame_origin_xy_m)):
        raise InvalidParameterError(f"frame_origin_xy_m must be two finite numbers (m), got {list(frame_origin_xy_m)!r}",
                                    parameter="frame_origin_xy_m")
    outputs: list[tuple[str, Path]] = []
    if bag is not None:
        if importlib.util.find_spec("rosbags") is None:
            raise OptionalDependencyError("`bag` needs the optional dependency 'rosbags': pip install 'terrawatt[ros]'",
                                          parameter="bag")
        outputs.append(("bag", check_route_bag_path(bag, "`bag`")[0]))
    if nav2_map is not None:
        for yaml_path in nav2_targets(nav2_map):
            outputs += [("nav2_map", p) for p in nav2_map_paths(yaml_path, "`nav2_map`")]
    if energy_geotiff is not None:
        import_rasterio()
        target = check_output_path(energy_geotiff, "`energy_geotiff`")
        if target.suffix.lower() not in (".tif", ".tiff"):
            raise InvalidParameterError(f"`energy_geotiff` writes a GeoTIFF ending in '.tif' or '.tiff', got "
                                        f"{str(target)!r}", parameter="energy_geotiff")
        outputs.append(("energy_geotiff", target))
    ins = [Path(p) for p in inputs if p is not None]
    taken_by: dict[Path, str] = {}
    taken = {Path(os.path.abspath(p)): "the command's own output" for p in others}
    for param, path in outputs:
        said = f"`{param}`"  # marked: a path in the message may hold the word
        refuse_overwriting_inputs([path], ins, said)
        key = Path(os.path.abspath(path))
        if key in taken:
            raise InvalidParameterError(f"{said}: {str(path)!r} is also {taken[key]}; give another name",
                                        parameter=tuple(dict.fromkeys((param, taken_by.get(key, param)))))
        taken[key], taken_by[key] = f"written for {said}", param
    for param, path in outputs:
        probe_writable(path.parent if str(path.parent) else Path("."), f"`{param}`")
