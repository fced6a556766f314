"""``--ros2-out``, ``--nav2-map``, ``--energy-costmap``: a planned route and its map for ROS 2 / Nav2, as plan options."""

from __future__ import annotations

import argparse
import importlib.util
import math
import os
from collections.abc import Iterable
from pathlib import Path

from terrain import InvalidParameterError, OptionalDependencyError, TerrainMap
from terrawatt_base.atomic import check_output_path, probe_writable, refuse_overwriting_inputs
from terrain.georef import import_rasterio

from planner.edge_cost import EnergyCost
from planner.nav2_map import nav2_map_paths
from planner.ros_export import check_route_bag_path
from planner.ros_outputs import nav2_targets, write_ros_outputs
from planner.route import Route

__all__ = ["add_ros2_arguments", "nav2_targets", "check_ros2_outputs", "write_ros2_outputs"]

_FLAGS = ("ros2_out", "nav2_map", "energy_costmap")


def add_ros2_arguments(parser: argparse.ArgumentParser) -> None:
    """The ROS 2 / Nav2 output flags (checked by :func:`check_ros2_outputs`, written by :func:`write_ros2_outputs`)."""
    group = parser.add_argument_group("ROS 2 / Nav2 outputs")
    group.add_argument(
        "--ros2-out", type=Path, default=None, metavar="FILE.mcap|DIR",
        help="write the route as a ROS 2 bag: a single MCAP file (FILE.mcap) or a bag directory (any other name): "
             "nav_msgs/Path on /terrawatt/route (frame map, z the DEM elevation, yaw along the segments, poses "
             "stamped with the planned time), cumulative energy (J) per pose on /terrawatt/route_energy, the map's "
             "CRS and frame origin (JSON) on /terrawatt/map_crs, the route summary on /terrawatt/route_summary "
             "(needs the ros extra)",
    )
    group.add_argument(
        "--nav2-map", default=None, metavar="DIR/|PREFIX",
        help="write Nav2 maps: PREFIX.yaml + PREFIX.pgm (trinary occupancy: obstacles and cells steeper than "
             "--max-slope-deg occupied) and PREFIX_energy.yaml + PREFIX_energy.pgm (raw-mode costmap 0-99 "
             "proportional to the energy per metre, 100 blocked); a folder (trailing / or existing) gets map.* files",
    )
    group.add_argument(
        "--energy-costmap", type=Path, default=None, metavar="FILE.tif",
        help="write each cell's mean energy per metre over headings (J/m at --speed) as a float32 GeoTIFF in the "
             "map's CRS, NaN where blocked (needs the geo extra)",
    )
    group.add_argument(
        "--map-frame-origin", type=float, nargs=2, default=None, metavar=("X", "Y"),
        help="with --ros2-out / --nav2-map: the ROS map frame's origin in map (CRS) coordinates, e.g. the map's "
             "lower-left corner to keep UTM-sized numbers out of the poses (default 0 0: map coordinates as they are)",
    )


def _given(args: argparse.Namespace) -> list[str]:
    return ["--" + f.replace("_", "-") for f in _FLAGS if getattr(args, f, None) is not None]


def _frame_origin(args: argparse.Namespace) -> tuple[float, float]:
    origin = getattr(args, "map_frame_origin", None)
    return (0.0, 0.0) if origin is None else (float(origin[0]), float(origin[1]))


def check_ros2_outputs(args: argparse.Namespace, inputs: Iterable[Path | None] = (),
                       others: Iterable[Path] = ()) -> None:
    """Before any work: the ROS 2 / Nav2 outputs can be written, replace no input, and their extras are installed.

    ``inputs`` are the command's input paths, ``others`` the files it writes besides these
    (e.g. ``--out``'s route.json): no output may be one of them, nor two outputs one path.

    Raises
    ------
    InvalidParameterError
        A flag with coarse-to-fine planning (no whole map); ``--map-frame-origin`` alone; a
        path of the wrong kind or suffix; an output that would replace an input or another
        output; an unwritable folder.
    OptionalDependencyError
        ``--ros2-out`` without rosbags, ``--energy-costmap`` without rasterio.
    """
    given = _given(args)
    if getattr(args, "map_frame_origin", None) is not None and not {"--ros2-out", "--nav2-map"} & set(given):
        raise InvalidParameterError("--map-frame-origin applies to --ros2-out and --nav2-map; give one of them")
    if not given:
        return
    if getattr(args, "coarse_factor", None) is not None or getattr(args, "windowed", False):
        raise InvalidParameterError(f"{', '.join(given)} need the whole map: plan without --coarse-factor / --windowed")
    origin = getattr(args, "map_frame_origin", None)
    if origin is not None and not all(math.isfinite(v) for v in origin):
        raise InvalidParameterError(f"--map-frame-origin must be two finite numbers (m), got {list(origin)!r}")
    outputs: list[tuple[str, Path]] = []
    if getattr(args, "ros2_out", None) is not None:
        if importlib.util.find_spec("rosbags") is None:
            raise OptionalDependencyError("--ros2-out needs the optional dependency 'rosbags': pip install 'terrawatt[ros]'")
        target, _ = check_route_bag_path(args.ros2_out, "--ros2-out")
        outputs.append(("--ros2-out", target))
    if getattr(args, "nav2_map", None) is not None:
        for yaml_path in nav2_targets(args.nav2_map):
            outputs += [("--nav2-map", p) for p in nav2_map_paths(yaml_path, "--nav2-map")]
    if getattr(args, "energy_costmap", None) is not None:
        import_rasterio()
        target = check_output_path(args.energy_costmap, "--energy-costmap")
        if target.suffix.lower() not in (".tif", ".tiff"):
            raise InvalidParameterError(f"--energy-costmap writes a GeoTIFF ending in '.tif' or '.tiff', got {str(target)!r}")
        outputs.append(("--energy-costmap", target))
    ins = list(inputs)
    taken = {Path(os.path.abspath(p)): "the command's own output" for p in others}
    for flag, path in outputs:
        refuse_overwriting_inputs([path], ins, flag)
        key = Path(os.path.abspath(path))
        if key in taken:
            raise InvalidParameterError(f"{flag}: {str(path)!r} is also {taken[key]}; give another name")
        taken[key] = f"written for {flag}"
    for flag, path in outputs:
        probe_writable(path.parent if str(path.parent) else Path("."), flag)


def write_ros2_outputs(args: argparse.Namespace, route: Route, tmap: TerrainMap, cost: EnergyCost) -> list[Path]:
    """Write the outputs of the flags given, checked by :func:`check_ros2_outputs`, and return the files written
    (:func:`planner.ros_outputs.write_ros_outputs`); a route not found writes no bag (a line says so)."""
    bag = getattr(args, "ros2_out", None)
    if bag is not None and not route.found:
        print(f"no route (status {route.status!r}): --ros2-out {bag} not written")
    return write_ros_outputs(route, tmap, cost, bag=bag, nav2_map=getattr(args, "nav2_map", None),
                             energy_geotiff=getattr(args, "energy_costmap", None),
                             frame_origin_xy_m=_frame_origin(args))
