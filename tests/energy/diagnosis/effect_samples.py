"""Shared samples of the effect tests: a noiseless Husky drive on coated wood and a physics model of it."""

from __future__ import annotations

import numpy as np

from energy import InteractionLog, PhysicsCurrentModel, TruthSimulator, robot_preset
from energy.diagnosis import EFFECTS_CATALOGUE
from energy.sim import PAPER_GROUNDS, NoiseModel

__all__ = ["coated_wood_log", "coated_wood_model"]


def coated_wood_log() -> InteractionLog:
    """4 s at 100 Hz: an arc for 2 s, then a pivot."""
    sim = TruthSimulator(robot_preset("husky"), PAPER_GROUNDS, noise=NoiseModel.off(), velocity_time_constant_s=0.0)
    t = np.arange(400) * 0.01
    v = np.where(t < 2, 0.4, 0.0)
    w = np.where(t < 2, 0.3, 0.8)
    return sim.simulate_commands(t, v, w, ground="coated_wood", seed=1)


def coated_wood_model(log: InteractionLog) -> PhysicsCurrentModel:
    """A physics model of coated wood without slope and turning resistance, not clipped at zero, fitted on ``log``."""
    effects = [e for e in EFFECTS_CATALOGUE[:12] if e not in ("slope", "turning_resistance")]
    return PhysicsCurrentModel(ground=PAPER_GROUNDS["coated_wood"], fit_parameters=(), effects=effects,
                               clip_negative=False).fit([log])
