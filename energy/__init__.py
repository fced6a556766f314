"""energy — what a motion costs: physics and learned current models, logs, metrics."""

from terrain.errors import (
    DataError,
    FileFormatError,
    FormatVersionError,
    InvalidParameterError,
    NotFittedError,
    UnknownNameError,
)

from .battery import Battery, Discharge, discharge_from_current, discharge_from_power
from .budget import CURRENT_CONVENTIONS, EnergyBudget, energy_budget, log_battery_power_w
from .models import (  # torch-free: the contract, its file format, the baselines, the loader
    CURRENT_MODEL_FORMAT_VERSION,
    PHYSICS_FIT_PARAMETERS,
    ConstantCurrentModel,
    CurrentModel,
    LinearCurrentModel,
    PhysicsCurrentModel,
    load_current_model,
)
from .models import __getattr__  # the torch names (estimator, net, data, training) load on first use
from .commands import CommandProfile
from .evaluation import (
    EvaluationResult,
    RunScore,
    ScoreSummary,
    evaluate_current_models,
)
from .excitation import excitation_commands
from .features import (
    DEFAULT_T_INTERVAL_S,
    SOURCE_CURRENT_RANGE_A,
    SOURCE_OMEGA_RANGE_RADPS,
    SOURCE_SPEED_RANGE_MPS,
    MinMaxNormaliser,
    WindowSpec,
    band_rms_spectra,
    log_band_edges_hz,
    sliding_windows,
    whole_run_band_spectrum,
    whole_run_spectrum,
    window_starts,
)
from .logs import DEFAULT_GAP_FACTOR, InteractionLog, LogMeta
from .metrics import (
    CurrentErrors,
    charge_mah,
    compare_currents,
    cumulative_charge_mah,
    error_rate_pct,
    moving_median,
    rmse_a,
    section_charges_mah,
    section_error_pct,
)
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
from .profiles import (
    DEFAULT_ACCEL_MPS2,
    DEFAULT_YAW_ACCEL_RADPS2,
    drivable_waypoints,
    drive_profile,
    planned_durations_s,
    waypoint_commands,
)
from .plots import ground_spectra, plot_current_estimate, plot_vibration_spectra
from .io import (
    read_borealtc,
    read_borealtc_run,
    read_csv_log,
    read_rosbag,
    write_csv_log,
)
from .sim import (
    PAPER_GROUNDS,
    PAPER_VARIATION,
    VIBRATION_PRESETS,
    GroundVariation,
    NoiseModel,
    TruthRun,
    TruthSimulator,
    VibrationSignature,
    vibration_preset,
)

__all__ = [
    # parameters and the physics model
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
    # interaction logs and readers
    "InteractionLog",
    "LogMeta",
    "DEFAULT_GAP_FACTOR",
    "read_borealtc_run",
    "read_borealtc",
    "read_csv_log",
    "write_csv_log",
    "read_rosbag",
    # battery and budgets
    "Battery",
    "Discharge",
    "EnergyBudget",
    "CURRENT_CONVENTIONS",
    "discharge_from_power",
    "discharge_from_current",
    "energy_budget",
    "log_battery_power_w",
    # truth simulator and command profiles
    "CommandProfile",
    "excitation_commands",
    "waypoint_commands",
    "drive_profile",
    "DEFAULT_ACCEL_MPS2",
    "DEFAULT_YAW_ACCEL_RADPS2",
    "drivable_waypoints",
    "planned_durations_s",
    "TruthSimulator",
    "TruthRun",
    "NoiseModel",
    "VibrationSignature",
    "GroundVariation",
    "PAPER_GROUNDS",
    "PAPER_VARIATION",
    "VIBRATION_PRESETS",
    "vibration_preset",
    # current models (estimator, baselines) and their evaluation
    "CurrentModel",
    "load_current_model",
    "CURRENT_MODEL_FORMAT_VERSION",
    "VibrationCurrentEstimator",
    "EstimatorConfig",
    "ESTIMATOR_PRESETS",
    "estimator_preset",
    "CurrentNet",
    "CurrentNetConfig",
    "WindowDataset",
    "TrainConfig",
    "TrainingHistory",
    "train_network",
    "ConstantCurrentModel",
    "LinearCurrentModel",
    "PhysicsCurrentModel",
    "PHYSICS_FIT_PARAMETERS",
    "evaluate_current_models",
    "EvaluationResult",
    "RunScore",
    "ScoreSummary",
    # figures
    "plot_current_estimate",
    "plot_vibration_spectra",
    "ground_spectra",
    # vibration features
    "DEFAULT_T_INTERVAL_S",
    "WindowSpec",
    "window_starts",
    "sliding_windows",
    "whole_run_spectrum",
    "whole_run_band_spectrum",
    "band_rms_spectra",
    "log_band_edges_hz",
    "MinMaxNormaliser",
    "SOURCE_SPEED_RANGE_MPS",
    "SOURCE_OMEGA_RANGE_RADPS",
    "SOURCE_CURRENT_RANGE_A",
    # metrics
    "charge_mah",
    "cumulative_charge_mah",
    "section_charges_mah",
    "error_rate_pct",
    "section_error_pct",
    "rmse_a",
    "moving_median",
    "compare_currents",
    "CurrentErrors",
    # errors the models raise (re-exported for convenience; defined in terrain.errors)
    "DataError",
    "FileFormatError",
    "FormatVersionError",
    "InvalidParameterError",
    "NotFittedError",
    "UnknownNameError",
]
