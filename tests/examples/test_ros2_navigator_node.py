"""examples/ros2_navigator_node.py, which no machine here can run (no ROS 2, no rclpy): it parses, names
only public terrawatt names that exist, and its plumbing drives a stand-in rclpy and navigator."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import inspect
import json
import math
import sys
import types
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import planner
import terrain

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "ros2_navigator_node.py"
MODEL = ROOT / "tests" / "fixtures" / "current_models_v1" / "constant.pt"
TERRAWATT = ("terrawatt_base", "terrain", "energy", "planner")
ROS = ("rclpy", "nav_msgs", "sensor_msgs", "std_msgs", "geometry_msgs")
#: Being written by other engineers as this example lands: their checks skip, naming them, until they exist.
PENDING = ("planner.Navigator", "energy.io.ros_messages")


def _tree() -> ast.Module:
    return ast.parse(EXAMPLE.read_text(encoding="utf-8"), filename=str(EXAMPLE))


def _aliases(tree: ast.Module) -> dict[str, str]:
    """Local name -> dotted terrawatt name, from the module's top-level imports."""
    out = {}
    for node in tree.body:
        if isinstance(node, ast.Import):
            out |= {(a.asname or a.name): a.name for a in node.names if a.name.split(".")[0] in TERRAWATT}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module.split(".")[0] in TERRAWATT:
            out |= {(a.asname or a.name): f"{node.module}.{a.name}" for a in node.names}
    return out


def _dotted(node: ast.AST, aliases: dict[str, str]) -> str | None:
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if isinstance(node, ast.Name) and node.id in aliases:
        return ".".join([aliases[node.id], *reversed(parts)])
    return None


def _uses(tree: ast.Module) -> dict[str, ast.AST]:
    """Every terrawatt name the file uses (the longest dotted chain), with a node that uses it."""
    aliases = _aliases(tree)
    inner = {id(n.value) for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
    return {name: n for n in ast.walk(tree) if isinstance(n, (ast.Attribute, ast.Name)) and id(n) not in inner
            and (name := _dotted(n, aliases)) is not None}


def _resolve(dotted: str):
    """The object a dotted name names; LookupError naming the first part that does not exist or is not public."""
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ModuleNotFoundError:
            continue
        for j, part in enumerate(parts[i:]):
            if part.startswith("_") or (j == 0 and part not in getattr(obj, "__all__", ())):
                raise LookupError(f"{part!r} is not in {'.'.join(parts[:i])}.__all__")
            if not hasattr(obj, part):
                raise LookupError(f"{'.'.join(parts[:i + j])} has no {part!r}")
            obj = getattr(obj, part)
        return obj
    raise LookupError(f"no module {parts[0]!r}")


def test_it_parses_says_it_is_not_run_here_and_imports_ros_only_when_run():
    tree = _tree()
    doc = ast.get_docstring(tree)
    assert "not run in this project's ci" in doc.lower() and "--ros-args -p map:=" in doc
    top = {a.name.split(".")[0] for n in tree.body if isinstance(n, ast.Import) for a in n.names}
    top |= {n.module.split(".")[0] for n in tree.body if isinstance(n, ast.ImportFrom)}
    assert not top & set(ROS), "ROS 2 is imported at module level: importing the file needs ROS 2"
    inside = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    assert "rclpy" in inside


def test_it_names_only_public_terrawatt_names_that_exist():
    uses, pending, problems = _uses(_tree()), set(), []
    for name, node in sorted(uses.items()):
        try:
            obj = _resolve(name)
        except LookupError as exc:
            if name.startswith(PENDING):
                pending.add(name)
            else:
                problems.append(f"line {node.lineno}: {name}: {exc}")
            continue
        calls = [c for c in ast.walk(_tree()) if isinstance(c, ast.Call) and _dotted(c.func, _aliases(_tree())) == name]
        params = inspect.signature(obj).parameters if callable(obj) and calls else {}
        if params and not any(p.kind is p.VAR_KEYWORD for p in params.values()):
            problems += [f"line {c.lineno}: {name}() has no parameter {k.arg!r}" for c in calls for k in c.keywords
                         if k.arg is not None and k.arg not in params]
    assert {"terrain.read_map", "energy.load_current_model", "planner.Navigator.load"} <= set(uses)
    assert not problems, problems
    convert = "energy.io.ros_messages.log_from_messages"
    if convert not in pending:  # called with **chunk: one keyword per source
        sources = ast.literal_eval(next(n.value for n in _tree().body if isinstance(n, ast.Assign)
                                        and n.targets[0].id == "SOURCES"))
        assert set(sources) <= set(inspect.signature(_resolve(convert)).parameters)
    if pending:
        pytest.skip(f"not written yet (other engineers' work in progress): {sorted(pending)}")


# ------------------------------------------------------------------ a stand-in ROS 2 and navigator
def _module(name: str, **attrs) -> types.ModuleType:
    module = types.ModuleType(name)
    module.__dict__.update(attrs)
    return module


def _header(ns: int = 0) -> SimpleNamespace:
    return SimpleNamespace(stamp=SimpleNamespace(sec=ns // 10**9, nanosec=ns % 10**9), frame_id="")


class _PathMsg:
    def __init__(self):
        self.header, self.poses = _header(), []


class _PoseStamped:
    def __init__(self, header):
        self.header = header
        self.pose = SimpleNamespace(position=SimpleNamespace(x=0.0, y=0.0, z=0.0),
                                    orientation=SimpleNamespace(x=0.0, y=0.0, z=0.0, w=1.0))


class _Node:
    def __init__(self, params):
        self.params, self.subs, self.pubs, self.timers, self.logged, self.clock_ns = params, {}, {}, [], [], 7

    def declare_parameter(self, name, value):
        return SimpleNamespace(value=self.params.get(name, value))

    def get_logger(self):
        return SimpleNamespace(info=self.logged.append, warning=self.logged.append)

    def create_publisher(self, msg_type, topic, depth):
        self.pubs[topic] = []
        return SimpleNamespace(publish=self.pubs[topic].append)

    def create_subscription(self, msg_type, topic, callback, depth):
        self.subs[topic] = callback

    def create_timer(self, period_s, callback):
        self.timers.append((period_s, callback))

    def get_clock(self):
        return SimpleNamespace(now=lambda: SimpleNamespace(nanoseconds=self.clock_ns))


WAYPOINTS_M = np.array([[10.0, 10.0], [20.0, 10.0], [20.0, 30.0]])


def _decision(action: str, route=None, time_s: float = 0.0) -> SimpleNamespace:
    return SimpleNamespace(action=action, reason="test", route=route,
                           to_dict=lambda: {"action": action, "reason": "test", "time_s": time_s})


class _Navigator:
    """Plans; then answers continue, new_route, arrived; records what it is given."""

    def __init__(self, terrain_map, registry, robot, battery, goal_xy_m, *, settings=None):
        self.registry, self.goal_xy_m, self.settings, self.starts, self.logs, self.saves = (
            registry, goal_xy_m, settings, [], [], [])

    @classmethod
    def load(cls, path, terrain_map):
        nav = cls(terrain_map, None, None, None, None)
        nav.loaded_from = Path(path)
        return nav

    def plan(self, start_xy_m):
        self.starts.append(start_xy_m)
        return _decision("new_route", SimpleNamespace(waypoints_m=WAYPOINTS_M))

    def observe(self, log):
        self.logs.append(log)
        action = {2: "new_route", 3: "arrived"}.get(len(self.logs), "continue")
        route = SimpleNamespace(waypoints_m=WAYPOINTS_M[::-1]) if action == "new_route" else None
        return _decision(action, route, len(self.logs) * 0.5)

    def save(self, path):
        Path(path).write_text("state")
        self.saves.append(Path(path))


@pytest.fixture
def ros(monkeypatch, tmp_path):
    """The example's module on a stand-in rclpy (``node(params)`` builds a NavigatorNode) and its log calls."""
    msgs = {"nav_msgs.msg": {"Odometry": object, "Path": _PathMsg}, "sensor_msgs.msg": {"Imu": object, "BatteryState": object},
            "std_msgs.msg": {"Float64": object, "String": lambda data: SimpleNamespace(data=data)},
            "geometry_msgs.msg": {"PoseStamped": _PoseStamped}}
    for name, attrs in msgs.items():
        monkeypatch.setitem(sys.modules, name.split(".")[0], _module(name.split(".")[0]))
        monkeypatch.setitem(sys.modules, name, _module(name, **attrs))
    try:
        importlib.import_module("energy.io.ros_messages")
    except ModuleNotFoundError:
        monkeypatch.setitem(sys.modules, "energy.io.ros_messages", _module("energy.io.ros_messages",
                                                                           log_from_messages=None))
    monkeypatch.setattr(planner, "Navigator", _Navigator, raising=False)
    spec = importlib.util.spec_from_file_location("ros2_navigator_node_example", EXAMPLE)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    calls = []

    def log_from_messages(**chunk):
        calls.append(chunk)
        if len(calls) == 2:
            raise terrain.DataError("2 odometry samples; a chunk needs 3")
        return f"log{len(calls)}"

    monkeypatch.setattr(example, "log_from_messages", log_from_messages)
    defaults = {"model": str(MODEL), "state": str(tmp_path / "nav_state"), "save_every": 2,
                "frame_origin_x": 5.0, "frame_origin_y": -2.0}

    def node(**params):
        rclpy = SimpleNamespace(create_node=lambda name: _Node(defaults | params))
        return example.NavigatorNode(rclpy)

    return SimpleNamespace(example=example, node=node, calls=calls, state=tmp_path / "nav_state")


def _odom(x, y):
    return SimpleNamespace(header=_header(), pose=SimpleNamespace(pose=SimpleNamespace(position=SimpleNamespace(x=x, y=y))))


def test_the_node_buffers_observes_publishes_saves_and_resumes(ros):
    n = ros.node()
    node, nav = n.node, n.nav
    assert set(node.subs) == {"/odom", "/imu/data", "/drive/current_left", "/drive/current_right", "/battery"}
    assert set(node.pubs) == {"/terrawatt/decision", "/terrawatt/route"} and node.timers[0][0] == 0.5
    assert nav.goal_xy_m == (150.0, 150.0) and nav.settings.speed_mps == 0.5 and nav.registry.shape == (160, 160)
    tick = node.timers[0][1]
    tick()  # nothing yet: no observation
    node.clock_ns = 10**9  # messages are buffered at their receive time, as a bag records them
    node.subs["/odom"](_odom(5.0, 12.0))  # the first pose: plan from it, in map coordinates
    assert nav.starts == [(10.0, 10.0)] and json.loads(node.pubs["/terrawatt/decision"][0].data)["action"] == "new_route"
    path = node.pubs["/terrawatt/route"][0]
    assert (path.header.stamp.sec, path.header.frame_id, len(path.poses)) == (1, "map", 3)
    assert [(p.pose.position.x, p.pose.position.y) for p in path.poses] == [(5.0, 12.0), (15.0, 12.0), (15.0, 32.0)]
    z = n.tmap.sample("elevation", *WAYPOINTS_M.T, method="bilinear")
    np.testing.assert_allclose([p.pose.position.z for p in path.poses], z)
    yaw = [2 * math.atan2(p.pose.orientation.z, p.pose.orientation.w) for p in path.poses]
    np.testing.assert_allclose(yaw, [0.0, math.pi / 2, math.pi / 2], atol=1e-12)
    node.clock_ns = 1_100_000_000
    node.subs["/drive/current_left"](SimpleNamespace(data=3.5))
    node.subs["/imu/data"](SimpleNamespace(header=_header(1_000_000_000)))
    tick()
    assert ros.calls[0]["odom"][0][0] == 10**9 and ros.calls[0]["imu"][0][0] == 1_100_000_000
    assert set(ros.calls[0]) == set(ros.example.SOURCES) and ros.calls[0]["battery"] == []
    assert ros.calls[0]["current_left"][0][1].data == 3.5 and nav.logs == ["log1"]
    for second in (2, 3, 4, 5):  # a chunk refused (DataError: dropped, logged), new_route, arrived, then done
        node.clock_ns = second * 10**9
        node.subs["/odom"](_odom(6.0, 12.0))
        tick()
    assert any("chunk dropped" in str(m) for m in node.logged)
    assert nav.logs == ["log1", "log3", "log4"]
    assert [json.loads(p.data)["action"] for p in node.pubs["/terrawatt/decision"]] == [
        "new_route", "continue", "new_route", "arrived"]
    assert len(node.pubs["/terrawatt/route"]) == 2 and node.pubs["/terrawatt/route"][1].header.stamp.sec == 3
    assert nav.saves == [ros.state, ros.state] and n.done  # every 2nd chunk, and on arriving; then nothing more
    again = ros.node()
    assert again.nav.loaded_from == ros.state and again.planned
    again.node.subs["/odom"](_odom(6.0, 12.0))
    assert again.nav.starts == []  # resumed with its route: no new plan
