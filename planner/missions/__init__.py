"""Missions: drive a route against a battery (:func:`simulate_mission`), the ride-along loop (:class:`Navigator`; in simulation :func:`run_adaptive_mission`) and Monte Carlo studies (:func:`simulate_missions_mc`)."""

from .adaptive import run_adaptive_mission
from .adaptive_results import (
    ADAPTIVE_FORMAT_VERSION,
    ADAPTIVE_STATUSES,
    AdaptiveResult,
    LegRecord,
    ReplanRecord,
    UpdateRecord,
)
from .decisions import NAVIGATOR_ACTIONS, Decision, ManoeuvreRequest, RemainingForecast
from .manoeuvres import excitation_manoeuvre, excitation_profiles, fit_prior_model
from .monte_carlo import MissionSetup, simulate_missions_mc
from .monte_carlo_figure import plot_monte_carlo
from .monte_carlo_result import MONTE_CARLO_FORMAT_VERSION, MonteCarloResult
from .monte_carlo_sampling import MissionDistributions, MissionSample
from .navigator import Navigator
from .observations import CHUNK_FIELDS, observation_log
from .options import DEFAULT_MC_CURRENT_RATE_HZ, MissionAccounting, MissionDrive, MissionTruth, MonteCarloStudy
from .results import MISSION_FORMAT_VERSION, MISSION_STATUSES, MissionResult
from .settings import UPDATE_SCOPES, UPDATE_SOURCES, AdaptiveSettings, MissionGoal, NavigatorModels, ReplayFeed
from .simulate import simulate_mission
from .updates import adapted_model, validation_error

__all__ = [
    "simulate_mission",
    "MissionDrive",
    "MissionAccounting",
    "MissionResult",
    "MISSION_STATUSES",
    "MISSION_FORMAT_VERSION",
    "run_adaptive_mission",
    # the ride-along loop
    "Navigator",
    "MissionGoal",
    "NavigatorModels",
    "ReplayFeed",
    "Decision",
    "NAVIGATOR_ACTIONS",
    "RemainingForecast",
    "ManoeuvreRequest",
    "observation_log",
    "CHUNK_FIELDS",
    "UPDATE_SOURCES",
    "fit_prior_model",
    "excitation_manoeuvre",
    "excitation_profiles",
    "validation_error",
    "adapted_model",
    "AdaptiveSettings",
    "AdaptiveResult",
    "LegRecord",
    "UpdateRecord",
    "ReplanRecord",
    "ADAPTIVE_STATUSES",
    "ADAPTIVE_FORMAT_VERSION",
    "UPDATE_SCOPES",
    # Monte Carlo missions
    "simulate_missions_mc",
    "MonteCarloStudy",
    "MissionTruth",
    "MissionDistributions",
    "MissionSample",
    "MissionSetup",
    "MonteCarloResult",
    "MONTE_CARLO_FORMAT_VERSION",
    "DEFAULT_MC_CURRENT_RATE_HZ",
    "plot_monte_carlo",
]
