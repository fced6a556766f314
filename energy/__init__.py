"""energy — what a motion costs: physics and learned current models, logs, metrics."""

from __future__ import annotations

from typing import Any

from .battery import Battery, discharge_from_power
from .budget import EnergyBudget, energy_budget
from .commands import CommandProfile
from .diagnosis import CorrectedCurrentModel, Diagnosis, diagnose
from .drivetrain import EFFECTS
from .energy_model import EnergyModel, IntervalEnergyModel
from .evaluation import EvaluationResult, evaluate_adaptation, evaluate_current_models, evaluate_few_shot
from .excitation import excitation_commands
from .ground import GroundParams
from .io import BagTopics, read_borealtc, read_csv_log, read_logs, read_rosbag, write_csv_log
from .logs import InteractionLog, LogMeta
from .metrics import charge_mah, compare_currents
from .models import (  # torch-free: the contract, the baselines, the loader
    AdaptedCurrentModel,
    ConstantCurrentModel,
    CurrentModel,
    LinearCurrentModel,
    PhysicsCurrentModel,
    load_current_model,
    new_current_model,
)
from .params import GROUND_PRESETS, ROBOT_PRESETS, ground_preset, robot_preset
from .physics import PhysicsEnergyModel
from .plots import plot_current_estimate, plot_vibration_spectra
from .prediction import predict_runs
from .profiles import drive_profile
from .robot import MotorParams, RobotParams
from .sim import NoiseModel, TruthSimulator

__all__ = [
    "RobotParams",
    "MotorParams",
    "GroundParams",
    "robot_preset",
    "ground_preset",
    "ROBOT_PRESETS",
    "GROUND_PRESETS",
    "PhysicsEnergyModel",
    "EFFECTS",
    "EnergyModel",
    "IntervalEnergyModel",
    "InteractionLog",
    "LogMeta",
    "read_logs",
    "read_borealtc",
    "read_csv_log",
    "write_csv_log",
    "read_rosbag",
    "BagTopics",
    "CurrentModel",
    "ConstantCurrentModel",
    "LinearCurrentModel",
    "PhysicsCurrentModel",
    "VibrationCurrentEstimator",
    "EstimatorConfig",
    "estimator_preset",
    "new_current_model",
    "load_current_model",
    "AdaptedCurrentModel",
    "evaluate_current_models",
    "evaluate_adaptation",
    "evaluate_few_shot",
    "EvaluationResult",
    "predict_runs",
    "TruthSimulator",
    "NoiseModel",
    "CommandProfile",
    "excitation_commands",
    "drive_profile",
    "Battery",
    "energy_budget",
    "EnergyBudget",
    "discharge_from_power",
    "diagnose",
    "Diagnosis",
    "CorrectedCurrentModel",
    "charge_mah",
    "compare_currents",
    "plot_current_estimate",
    "plot_vibration_spectra",
]

#: The torch-backed names: imported on first use (PEP 562), so ``import energy`` never imports torch.
_TORCH_NAMES = ("VibrationCurrentEstimator", "EstimatorConfig", "estimator_preset")


def __getattr__(name: str) -> Any:
    if name in _TORCH_NAMES:
        from . import models

        value = getattr(models, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'energy' has no attribute {name!r}")
