"""``--ros2-out``, ``--nav2-map``, ``--energy-costmap``: a planned route and its map for ROS 2 / Nav2, as plan options."""

from __future__ import annotations

import argparse
from collections.abc import Iterable
from pathlib import Path

from planner.edge_cost import EnergyCost
from planner.ros_outputs import check_ros_outputs, nav2_targets, write_ros_outputs
from planner.route import Route
from terrain import InvalidParameterError, TerrainMap

__all__ = ["ROS2_FLAGS", "add_ros2_arguments", "nav2_targets", "check_ros2_outputs", "write_ros2_outputs"]

#: The flags of :func:`planner.ros_outputs.check_ros_outputs`' parameters (its errors name them).
ROS2_FLAGS = {"bag": "--ros2-out", "nav2_map": "--nav2-map", "energy_geotiff": "--energy-costmap",
              "frame_origin_xy_m": "--map-frame-origin"}


def add_ros2_arguments(parser: argparse.ArgumentParser) -> None:
    """The ROS 2 / Nav2 output flags (checked by :func:`check_ros2_outputs`, written by :func:`write_ros2_outputs`)."""
    group = parser.add_argument_group("ROS 2 / Nav2 outputs")
    group.add_argument("--ros2-out", type=Path, default=None, metavar="FILE.mcap|DIR",
                       help="write the route as a ROS 2 bag, one MCAP file (FILE.mcap) or a bag directory (any other "
                            "name): nav_msgs/Path on /terrawatt/route, its energy, CRS and summary (topics: see the "
                            "README's outputs; needs the ros extra)")
    group.add_argument("--nav2-map", default=None, metavar="DIR/|PREFIX",
                       help="write Nav2 maps PREFIX.yaml/.pgm (trinary occupancy: obstacles and cells steeper than "
                            "--max-slope-deg) and PREFIX_energy.yaml/.pgm (raw costmap 0-99 proportional to J/m, 100 "
                            "blocked); a folder (trailing / or existing) gets map.* files")
    group.add_argument("--energy-costmap", type=Path, default=None, metavar="FILE.tif",
                       help="write each cell's mean energy per metre over headings (J/m at --speed) as a float32 "
                            "GeoTIFF in the map's CRS, NaN where blocked (needs the geo extra)")
    group.add_argument("--map-frame-origin", type=float, nargs=2, default=None, metavar=("X", "Y"),
                       help="with --ros2-out / --nav2-map: the ROS map frame's origin in map (CRS) coordinates, e.g. "
                            "the map's lower-left corner (default 0 0: map coordinates as they are)")


def check_ros2_outputs(args: argparse.Namespace, inputs: Iterable[Path | None] = (),
                       others: Iterable[Path] = ()) -> None:
    """Before any work, the outputs asked for (:func:`planner.ros_outputs.check_ros_outputs`; ``others``: the command's
    own files), which need the whole map."""
    given = [flag for flag in ("--ros2-out", "--nav2-map", "--energy-costmap")
             if getattr(args, flag[2:].replace("-", "_"), None) is not None]
    if given and (getattr(args, "coarse_factor", None) is not None or getattr(args, "windowed", False)):
        raise InvalidParameterError(f"{', '.join(given)} need the whole map: plan without --coarse-factor / --windowed")
    check_ros_outputs(bag=getattr(args, "ros2_out", None), nav2_map=getattr(args, "nav2_map", None),
                      energy_geotiff=getattr(args, "energy_costmap", None),
                      frame_origin_xy_m=getattr(args, "map_frame_origin", None), inputs=inputs, others=others)


def write_ros2_outputs(args: argparse.Namespace, route: Route, tmap: TerrainMap, cost: EnergyCost) -> list[Path]:
    """Write the outputs asked for and return the files written (:func:`planner.ros_outputs.write_ros_outputs`)."""
    bag, origin = getattr(args, "ros2_out", None), getattr(args, "map_frame_origin", None)
    if bag is not None and not route.found:
        print(f"no route (status {route.status!r}): --ros2-out {bag} not written")
    return write_ros_outputs(route, tmap, cost, bag=bag, nav2_map=getattr(args, "nav2_map", None),
                             energy_geotiff=getattr(args, "energy_costmap", None),
                             frame_origin_xy_m=(0.0, 0.0) if origin is None else (float(origin[0]), float(origin[1])))
