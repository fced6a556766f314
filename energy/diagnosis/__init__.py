"""Sim-to-real gap diagnosis: where a current model's gap lies, which unmodelled effect causes it, how far it shrinks.

The withheld-effect scenarios that check it (truth-simulator logs with one effect left out
of the model) are experiment scaffolding and live with the benchmarks, in
``benchmarks/diagnosis_scenarios``.
"""

from .case import SPLITS, FitSettings, Fold, Split, make_split
from .corrected import CorrectedCurrentModel
from .diagnose import diagnose
from .effect_base import EFFECT_KINDS, BasisEffect, Effect, EffectParameter
from .effects import EFFECTS_CATALOGUE, NOT_IDENTIFIABLE_FROM_CURRENT, check_effect_names, effect, effect_from_spec
from .gap import GapShare, GapSummary, WaterfallStep, gap_summary, localise_gap, residual_currents_a
from .model_currents import DRIVE_EFFECTS
from .model_source import (
    MODEL_SOURCES,
    ModelUnderDiagnosis,
    check_model_source,
    model_under_diagnosis,
)
from .noise import ResidualNoise, residual_noise
from .plots import FIGURES, DiagnosisFigures, plot_diagnosis, plot_effect_ranking, plot_waterfall, skipped_figures
from .plots_gap import plot_gap_by_regime, plot_gap_map, plot_residual_time
from .quantity import CURRENT, POWER, Quantity
from .regimes import regime_labels
from .report import DIAGNOSIS_FILES, Diagnosis
from .result import EffectScore, Tie
from .separating import DriveCandidate, PairSeparation, SeparatingDrive, manoeuvre_library, separating_drive
from .stage import Stage

__all__ = [
    "CURRENT",
    "POWER",
    "Quantity",
    "Stage",
    "FitSettings",
    "DRIVE_EFFECTS",
    "FIGURES",
    "DiagnosisFigures",
    "plot_diagnosis",
    "skipped_figures",
    "MODEL_SOURCES",
    "ModelUnderDiagnosis",
    "check_model_source",
    "model_under_diagnosis",
    "DIAGNOSIS_FILES",
    "plot_effect_ranking",
    "plot_waterfall",
    "plot_gap_by_regime",
    "plot_gap_map",
    "plot_residual_time",
    "CorrectedCurrentModel",
    "Diagnosis",
    "EFFECTS_CATALOGUE",
    "EFFECT_KINDS",
    "BasisEffect",
    "Effect",
    "EffectParameter",
    "EffectScore",
    "Fold",
    "GapShare",
    "GapSummary",
    "NOT_IDENTIFIABLE_FROM_CURRENT",
    "SPLITS",
    "Split",
    "WaterfallStep",
    "Tie",
    "SeparatingDrive",
    "DriveCandidate",
    "PairSeparation",
    "ResidualNoise",
    "residual_noise",
    "manoeuvre_library",
    "separating_drive",
    "diagnose",
    "effect",
    "effect_from_spec",
    "check_effect_names",
    "gap_summary",
    "localise_gap",
    "make_split",
    "regime_labels",
    "residual_currents_a",
]
