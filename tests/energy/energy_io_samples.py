"""Shared samples of the energy.io tests: fixture paths, file editors, a ROS bag writer, fuzz settings."""

from __future__ import annotations

import csv
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

__all__ = [
    "FIXTURES", "BOREALTC_FIX", "GENERIC", "FUZZ_WRITTEN", "SHARED_BOREALTC", "GENERIC_COLUMNS", "GENERIC_UNITS",
    "read_rows", "copy_run", "edit_lines", "shared_data_or_skip", "HAVE_ROSBAGS", "requires_rosbags",
    "BASE_NS", "MS", "bag_content", "write_bag", "fuzz_examples", "fuzz_settings", "mutate_bytes",
]

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
BOREALTC_FIX = FIXTURES / "borealtc"
GENERIC = FIXTURES / "generic_ma.csv"
FUZZ_WRITTEN = FIXTURES / "written_log.csv"  # a log written by write_csv_log, header included
SHARED_BOREALTC = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "borealtc"
GENERIC_COLUMNS = {
    "time": "stamp_ms",
    "v": "cmd_v",
    "omega": "cmd_w",
    "current_left": "left_mA",
    "current_right": "right_mA",
    "accel_z": "acc_z",
    "ground": "label",
}
GENERIC_UNITS = {"time": "ms", "current_left": "mA", "current_right": "mA", "omega": "deg/s"}


def read_rows(path: Path) -> tuple[list[str], np.ndarray]:
    """Independent reference parse of a numeric CSV with the csv module."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array([[float(x) for x in r] for r in rows[1:]])


def copy_run(tmp_path: Path, ground: str = "ASPHALT", nn: str = "00") -> tuple[Path, Path]:
    dst = tmp_path / ground
    dst.mkdir(parents=True, exist_ok=True)
    imu = shutil.copy(BOREALTC_FIX / ground / f"imu_{nn}.csv", dst)
    pro = shutil.copy(BOREALTC_FIX / ground / f"pro_{nn}.csv", dst)
    return Path(imu), Path(pro)


def edit_lines(path: Path, fn) -> None:
    lines = path.read_text().splitlines()
    path.write_text("\n".join(fn(lines)) + "\n")



def shared_data_or_skip() -> Path:
    if not SHARED_BOREALTC.is_dir():
        pytest.skip("shared BorealTC data not found at ../shared/data/borealtc (beside the repository)")
    return SHARED_BOREALTC



try:
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_typestore
except ImportError:  # the 'ros' extra is optional
    HAVE_ROSBAGS = False
else:
    HAVE_ROSBAGS = True
requires_rosbags = pytest.mark.skipif(not HAVE_ROSBAGS, reason="rosbags (the 'ros' extra) is not installed")

BASE_NS = 1_700_000_000_000_000_000
MS = 1_000_000


def bag_content() -> dict:
    """Known streams (integer ns): IMU 100 Hz 0..2 s with header stamps; currents 10 Hz at
    50..1950 ms (receive time only); commands 5 Hz at 300..1100 ms."""
    imu_ns = [BASE_NS + k * 10 * MS for k in range(201)]
    cur_ns = [BASE_NS + (50 + 100 * k) * MS for k in range(20)]
    cmd_ns = [BASE_NS + (300 + 200 * k) * MS for k in range(5)]
    return {
        "imu_ns": imu_ns,
        "az": [9.81 + 0.001 * k for k in range(201)],
        "cur_ns": cur_ns,
        "left": [1.0 + 0.25 * k for k in range(20)],
        "right": [2.0 + 0.5 * k for k in range(20)],
        "cmd_ns": cmd_ns,
        "v": [0.1 * (k + 1) for k in range(5)],
        "w": [-0.2 * k for k in range(5)],
    }


def write_bag(path: Path, kind: str, content: dict, multiarray: bool = False, odom: bool = False,
              scale: float = 1.0, imu_stamp_ns: list[int] | None = None, empty_topics: tuple[str, ...] = ()) -> Path:
    """Write ``content`` to a bag. IMU messages are received 1 ms after ``content["imu_ns"]``
    and stamped with ``imu_stamp_ns`` (default: ``content["imu_ns"]``); ``empty_topics`` get
    a connection but no messages."""
    ros1 = kind == "ros1"
    if imu_stamp_ns is None:
        imu_stamp_ns = content["imu_ns"]
    ts = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    T = ts.types
    ser = ts.serialize_ros1 if ros1 else ts.serialize_cdr

    def vec(x=0.0, y=0.0, z=0.0):
        return T["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)

    def header(ns):
        stamp = T["builtin_interfaces/msg/Time"](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)
        return T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id="base") if ros1 else T["std_msgs/msg/Header"](
            stamp=stamp, frame_id="base")

    if ros1:
        writer = Writer1(path)
    else:
        plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=9, storage_plugin=plugin)
    quat = T["geometry_msgs/msg/Quaternion"]
    with writer:
        conns = {}

        def conn(topic, typ):
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, typ, typestore=ts)
            return conns[topic]

        msgs = []
        for ns, stamp_ns, az in zip(content["imu_ns"], imu_stamp_ns, content["az"]):
            m = T["sensor_msgs/msg/Imu"](
                header=header(stamp_ns), orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0), orientation_covariance=np.zeros(9),
                angular_velocity=vec(), angular_velocity_covariance=np.zeros(9),
                linear_acceleration=vec(z=az), linear_acceleration_covariance=np.zeros(9))
            msgs.append((ns + MS, "/imu/data", "sensor_msgs/msg/Imu", m))  # received 1 ms after the stamp
        for ns, left, right in zip(content["cur_ns"], content["left"], content["right"]):
            if multiarray:
                lay = T["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0)
                arr = T["std_msgs/msg/Float64MultiArray"](layout=lay, data=np.array([left, right]) * scale)
                msgs.append((ns, "/drive/current", "std_msgs/msg/Float64MultiArray", arr))
            else:
                msgs.append((ns, "/drive/current_left", "std_msgs/msg/Float64", T["std_msgs/msg/Float64"](data=left * scale)))
                msgs.append((ns, "/drive/current_right", "std_msgs/msg/Float64", T["std_msgs/msg/Float64"](data=right * scale)))
        for i, (ns, v, w) in enumerate(zip(content["cmd_ns"], content["v"], content["w"])):
            twist = T["geometry_msgs/msg/Twist"](linear=vec(x=v), angular=vec(z=w))
            if odom:
                pose = T["geometry_msgs/msg/PoseWithCovariance"](
                    pose=T["geometry_msgs/msg/Pose"](
                        position=T["geometry_msgs/msg/Point"](x=float(i), y=2.0 * i, z=0.0),
                        orientation=quat(x=0.0, y=0.0, z=np.sin(0.1 * i), w=np.cos(0.1 * i))),
                    covariance=np.zeros(36))
                tw = T["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36))
                m = T["nav_msgs/msg/Odometry"](header=header(ns), child_frame_id="base", pose=pose, twist=tw)
                msgs.append((ns, "/odom", "nav_msgs/msg/Odometry", m))
            else:
                msgs.append((ns, "/cmd_vel", "geometry_msgs/msg/Twist", twist))
        for ns, topic, typ, m in sorted(msgs, key=lambda x: x[0]):
            if topic in empty_topics:
                conn(topic, typ)
            else:
                writer.write(conn(topic, typ), ns, ser(m, typ))
    return path



def fuzz_examples(default: int) -> int:
    """Examples per fuzz test: ``default`` times ``TERRAWATT_FUZZ_EXAMPLES`` (a scale, default 1).

    The default suite runs a few hundred examples in all; for the long run (thousands)::

        TERRAWATT_FUZZ_EXAMPLES=20 python -m pytest -q tests/energy -k fuzz
    """
    scale = float(os.environ.get("TERRAWATT_FUZZ_EXAMPLES", "1"))
    return max(1, int(round(default * scale)))


def fuzz_settings(default: int) -> settings:
    """Hypothesis settings of the reader fuzz tests: derandomised (the same examples on every
    run), no deadline, no example database, scaled by :func:`fuzz_examples`."""
    return settings(
        max_examples=fuzz_examples(default),
        deadline=None,
        derandomize=True,
        database=None,
        suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
    )


def mutate_bytes(data: bytes, edits: list[tuple[int, int, int]]) -> bytes:
    """Apply (kind, position, byte) edits: 0 replaces, 1 inserts, 2 deletes a byte."""
    out = bytearray(data)
    for kind, pos, byte in edits:
        if not out:
            break
        i = pos % len(out)
        if kind == 0:
            out[i] = byte
        elif kind == 1:
            out.insert(i, byte)
        else:
            del out[i]
    return bytes(out)
