"""Toy current models and registries shared by the tests of planner.registry."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from planner.registry import CellModelRegistry


class GainModel:
    """Toy current model: current_a = gain_a * v_mps + offset_a."""

    def __init__(self, gain_a: float = 1.0, offset_a: float = 0.0) -> None:
        self.gain_a = gain_a
        self.offset_a = offset_a

    def fit(self, v_mps: np.ndarray, current_a: np.ndarray) -> GainModel:
        self.gain_a, self.offset_a = np.polyfit(v_mps, current_a, 1)
        return self

    def predict(self, v_mps: np.ndarray) -> np.ndarray:
        return self.gain_a * np.asarray(v_mps, float) + self.offset_a


def save_gain(model: GainModel, path: Path) -> None:
    with open(path, "wb") as fh:
        np.save(fh, np.array([model.gain_a, model.offset_a]))


def load_gain(path: Path) -> GainModel:
    with open(path, "rb") as fh:
        gain, offset = np.load(fh, allow_pickle=False)
    return GainModel(float(gain), float(offset))


def registry(shape: tuple[int, int] = (4, 5)) -> CellModelRegistry:
    return CellModelRegistry(shape, GainModel(1.0), prior_name="physics", prior_meta={"kind": "physics"})


def record_error(reg: CellModelRegistry, row: int, col: int, n: int, predicted_a: float,
                  measured_a: float = 1.0) -> None:
    """Record ``n`` one-second samples at one cell."""
    reg.evidence.record(np.full(n, row), np.full(n, col), np.full(n, measured_a), np.full(n, predicted_a), 1.0)


def cell_predictions(reg: CellModelRegistry, v_mps: float = 0.7) -> np.ndarray:
    rows, cols = reg.shape
    return np.array([[float(reg.model_for(r, c).predict(v_mps)) for c in range(cols)] for r in range(rows)])
