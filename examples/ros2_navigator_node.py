"""A ROS 2 node that rides along with a robot: terrawatt's Navigator on the robot's live topics.

NOT run in this project's CI: ROS 2 (rclpy) is not on these machines. The tests check that
this file parses, that every terrawatt name it uses exists, and drive its plumbing with a
stand-in rclpy and navigator (tests/examples/test_ros2_navigator_node.py).

Subscribes to /odom (nav_msgs/Odometry), /imu/data (sensor_msgs/Imu), /drive/current_left
and /drive/current_right (std_msgs/Float64), /battery (sensor_msgs/BatteryState); every
``chunk_s`` seconds it turns what arrived into an InteractionLog and asks the navigator what
to do. It publishes each decision as JSON (std_msgs/String) on /terrawatt/decision and each
new route (nav_msgs/Path) on /terrawatt/route, and saves the navigator's state every
``save_every`` chunks: restarted, it resumes from that state. See docs/ros2_node.md.

Run (in a sourced ROS 2 workspace, with terrawatt installed in the same Python):

    python examples/ros2_navigator_node.py --ros-args -p map:=site.tif -p model:=husky.zip \
        -p goal_x:=150.0 -p goal_y:=150.0

(floats with a decimal point: ROS parameters keep the type of their defaults, below).
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import energy
import planner
import planner.registry
import terrain
from energy.io.ros_messages import log_from_messages
from energy.params import robot_params

#: ROS parameters and their defaults ("" map: the bundled example map).
PARAMETERS = {
    "map": "", "model": "", "goal_x": 150.0, "goal_y": 150.0, "robot": "husky", "battery_capacity_ah": 20.0,
    "min_reserve_pct": 20.0, "initial_soc": 1.0, "speed_mps": 0.5, "chunk_s": 0.5, "save_every": 20,
    "state": "navigator_state", "frame_id": "map", "frame_origin_x": 0.0, "frame_origin_y": 0.0,
}
SOURCES = ("odom", "imu", "current_left", "current_right", "battery")


class NavigatorNode:
    """The navigator between the robot's topics and terrawatt's (rclpy passed in: imported by ``main``)."""

    def __init__(self, rclpy) -> None:
        from nav_msgs.msg import Odometry
        from nav_msgs.msg import Path as PathMsg
        from sensor_msgs.msg import BatteryState, Imu
        from std_msgs.msg import Float64, String

        self.node = rclpy.create_node("terrawatt_navigator")
        self.p = {name: self.node.declare_parameter(name, value).value for name, value in PARAMETERS.items()}
        self.log = self.node.get_logger()
        self.tmap = terrain.read_map(self.p["map"]) if self.p["map"] else terrain.example_map()
        self.origin_xy_m = (self.p["frame_origin_x"], self.p["frame_origin_y"])
        self.state = Path(self.p["state"])
        if self.state.exists():  # a restart: resume the drive where the last save left it
            self.nav = planner.Navigator.load(self.state, self.tmap)
            self.log.info(f"navigator state restored from {self.state}")
        else:
            registry = planner.registry.CellModelRegistry.from_terrain(self.tmap, energy.load_current_model(self.p["model"]))
            robot = robot_params(self.p["robot"])
            battery = energy.Battery(capacity_ah=self.p["battery_capacity_ah"], voltage_v=robot.battery_voltage_v,
                                     min_reserve_pct=self.p["min_reserve_pct"], initial_soc=self.p["initial_soc"])
            self.nav = planner.Navigator(self.tmap, registry, robot, battery, (self.p["goal_x"], self.p["goal_y"]),
                                         settings=planner.AdaptiveSettings(speed_mps=self.p["speed_mps"]))
        self.planned, self.done, self.chunks = self.state.exists(), False, 0
        self.buffers: dict[str, list] = {name: [] for name in SOURCES}
        self.msg_types = {"path": PathMsg, "string": String}
        self.decision_pub = self.node.create_publisher(String, "/terrawatt/decision", 10)
        self.route_pub = self.node.create_publisher(PathMsg, "/terrawatt/route", 10)
        subscriptions = [(Odometry, "/odom", "odom"), (Imu, "/imu/data", "imu"), (BatteryState, "/battery", "battery"),
                         (Float64, "/drive/current_left", "current_left"),
                         (Float64, "/drive/current_right", "current_right")]
        for msg_type, topic, name in subscriptions:
            self.node.create_subscription(msg_type, topic, lambda msg, name=name: self.on_message(name, msg), 50)
        self.node.create_timer(float(self.p["chunk_s"]), self.on_chunk)

    def on_message(self, name: str, msg) -> None:
        """Buffer ``(receive time in ns, msg)``, as a bag records it (the headers' stamps are read later)."""
        ns = self.node.get_clock().now().nanoseconds
        self.buffers[name].append((ns, msg))
        if name == "odom" and not self.planned:  # the first pose: plan from where the robot stands
            position = msg.pose.pose.position
            self.planned = True
            self.on_decision(self.nav.plan((position.x + self.origin_xy_m[0], position.y + self.origin_xy_m[1])), ns)

    def on_chunk(self) -> None:
        """Every ``chunk_s``: the buffered messages as one InteractionLog, observed; the decision published."""
        if self.done or not self.planned or not self.buffers["odom"]:
            return
        chunk = {name: self.buffers[name] for name in SOURCES}
        self.buffers = {name: [] for name in SOURCES}
        try:
            log = log_from_messages(**chunk)
        except terrain.DataError as exc:  # too few samples, a gap: this chunk is dropped
            self.log.warning(f"chunk dropped: {exc}")
            return
        self.on_decision(self.nav.observe(log), chunk["odom"][-1][0])
        self.chunks += 1
        if self.done or self.chunks % int(self.p["save_every"]) == 0:
            self.nav.save(self.state)

    def on_decision(self, decision, ns: int) -> None:
        """Publish a decision (JSON) and its route, if it brings one; a manoeuvre request is declined (this node drives none)."""
        self.decision_pub.publish(self.msg_types["string"](data=json.dumps(decision.to_dict())))
        if decision.route is not None:
            self.publish_route(decision.route, ns)
        if decision.action != "continue":
            self.log.info(f"{decision.action}: {decision.reason}")
        self.done = decision.action in ("stop", "arrived")
        if decision.action == "manoeuvre":  # this node drives no manoeuvre: the navigator learns from the driving
            self.on_decision(self.nav.decline_manoeuvre("this node does not drive manoeuvres"), ns)

    def publish_route(self, route: planner.Route, ns: int) -> None:
        """A route as a nav_msgs/Path in ``frame_id``: z on the DEM, each pose heading along its segment."""
        from geometry_msgs.msg import PoseStamped

        msg = self.msg_types["path"]()
        msg.header.frame_id = self.p["frame_id"]
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(ns, 1_000_000_000)
        pts = route.waypoints_m
        z = self.tmap.sample("elevation", pts[:, 0], pts[:, 1], method="bilinear")
        for i, ((x, y), h) in enumerate(zip(pts.tolist(), z.tolist(), strict=True)):
            j = min(i, len(pts) - 2)  # the last pose keeps the last segment's heading
            yaw = math.atan2(pts[j + 1, 1] - pts[j, 1], pts[j + 1, 0] - pts[j, 0]) if len(pts) > 1 else 0.0
            pose = PoseStamped(header=msg.header)
            pose.pose.position.x, pose.pose.position.y = x - self.origin_xy_m[0], y - self.origin_xy_m[1]
            pose.pose.position.z = h
            pose.pose.orientation.z, pose.pose.orientation.w = math.sin(yaw / 2.0), math.cos(yaw / 2.0)
            msg.poses.append(pose)
        self.route_pub.publish(msg)


def main(argv: list[str] | None = None) -> None:
    """Start ROS 2, run the node until shut down (Ctrl-C), saving the navigator's state last."""
    import rclpy

    rclpy.init(args=sys.argv if argv is None else argv)
    node = NavigatorNode(rclpy)
    try:
        rclpy.spin(node.node)
    except KeyboardInterrupt:
        pass
    finally:
        node.nav.save(node.state)
        node.node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
