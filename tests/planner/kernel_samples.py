"""A small procedural EnergyCost shared by the kernel tests."""

from __future__ import annotations

import numpy as np

from planner import CostTables, EnergyCost
from terrain.procedural import procedural_map


def kernel_cost() -> EnergyCost:
    tmap = procedural_map((30, 36), 1.0, seed=3, grounds=("a", "b"), obstacle_fraction=0.05)
    grades = np.linspace(-0.4, 0.4, 17)
    grade = np.vstack([40.0 + 300.0 * np.maximum(grades, 0.0), 60.0 + 200.0 * np.abs(grades)])
    turn = np.tile(np.linspace(0.0, 30.0, 9), (2, 1))
    return EnergyCost(tmap, np.asarray(tmap.ground), CostTables(grade, turn), speed_mps=0.5, max_slope_rad=np.arctan(0.4), battery_voltage_v=24.0, turn_rate_radps=0.5)
