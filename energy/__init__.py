"""energy — what a motion costs: physics and learned current models, logs, metrics."""

from .params import (
    DRIVE_KINDS,
    GROUND_PRESETS,
    ROBOT_PRESETS,
    GroundParams,
    MotorParams,
    RobotParams,
    ground_preset,
    robot_preset,
)
from .physics import EFFECTS, PhysicsEnergyModel, PowerBreakdown

__all__ = [
    "MotorParams",
    "RobotParams",
    "GroundParams",
    "DRIVE_KINDS",
    "ROBOT_PRESETS",
    "GROUND_PRESETS",
    "robot_preset",
    "ground_preset",
    "EFFECTS",
    "PhysicsEnergyModel",
    "PowerBreakdown",
]

from .logs import DEFAULT_GAP_FACTOR, InteractionLog, LogMeta
from .readers import read_borealtc, read_borealtc_run, read_csv_log, read_rosbag, write_csv_log

__all__ += [
    "InteractionLog",
    "LogMeta",
    "DEFAULT_GAP_FACTOR",
    "read_borealtc_run",
    "read_borealtc",
    "read_csv_log",
    "write_csv_log",
    "read_rosbag",
]
