"""A fitted current model's predictions on logs that may lack measured currents: charge and battery energy per run."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrawatt_base.errors import InvalidParameterError

from .logs import InteractionLog
from .metrics import charge_mah
from .models import CurrentModel
from .power import trapezoid

__all__ = ["RunPrediction", "predict_runs"]


@dataclass(frozen=True)
class RunPrediction:
    """What a model predicts for one run, beside what was measured when the log has it.

    Attributes
    ----------
    run : str
        ``<ground>/<source stem>`` (``#k`` added to repeats).
    ground : str
        The run's ground label (``"None"`` when unknown).
    duration_s : float
    charge_predicted_left_mah, charge_predicted_right_mah : float
        Predicted charge per side (mAh).
    charge_measured_left_mah, charge_measured_right_mah : float
        Measured charge per side (mAh); NaN for a log without currents.
    energy_predicted_wh : float
        The integral of the log's ``battery_voltage_v * (I_left + I_right)`` over the
        predicted currents (Wh): the battery energy when the currents are battery-side, as
        :func:`~energy.budget.log_battery_power_w` with ``current_convention="battery"`` and no
        electronics; NaN for a log without battery voltage.
    has_currents : bool
    """

    run: str
    ground: str
    duration_s: float
    charge_predicted_left_mah: float
    charge_predicted_right_mah: float
    charge_measured_left_mah: float
    charge_measured_right_mah: float
    energy_predicted_wh: float
    has_currents: bool

    def to_dict(self) -> dict[str, Any]:
        """The fields as a JSON-ready dict (NaN written as ``None``)."""
        return {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in dataclasses.asdict(self).items()}


def predict_runs(model: CurrentModel, logs: Sequence[InteractionLog]) -> list[RunPrediction]:
    """Predict every run of ``logs`` with a fitted ``model``; the logs need no measured currents.

    Parameters
    ----------
    model : CurrentModel
        A fitted model.
    logs : sequence of InteractionLog
        Runs of at least 2 drive samples each.

    Returns
    -------
    list of RunPrediction

    Raises
    ------
    InvalidParameterError
        Not a CurrentModel, no logs, an element that is not an InteractionLog.
    NotFittedError, DataError
        As ``model.predict`` (an unfitted model, an IMU that does not serve its band, ...).
    """
    if not isinstance(model, CurrentModel):
        raise InvalidParameterError(f"model must be a CurrentModel, got {model!r:.80}")
    items = [logs] if isinstance(logs, InteractionLog) else list(logs)
    if not items or not all(isinstance(log, InteractionLog) for log in items):
        raise InvalidParameterError("logs must be one InteractionLog or a non-empty sequence of them")
    stems = [f"{log.meta.ground_label}/{Path(log.meta.source).stem if log.meta.source else 'run'}" for log in items]
    seen: dict[str, int] = {}
    out = []
    for stem, log in zip(stems, items):
        k = seen.get(stem, 0)
        seen[stem] = k + 1
        pred = np.asarray(model.predict(log), dtype=np.float64)
        measured = (
            (charge_mah(log.time_s, log.current_left_a), charge_mah(log.time_s, log.current_right_a))
            if log.has_currents else (math.nan, math.nan)
        )
        energy = math.nan
        if log.battery_voltage_v is not None:
            energy = float(trapezoid(log.battery_voltage_v * pred.sum(axis=1), log.time_s)) / 3600.0
        out.append(RunPrediction(
            run=stem if stems.count(stem) == 1 else f"{stem}#{k}",
            ground=str(log.meta.ground_label),
            duration_s=log.duration_s,
            charge_predicted_left_mah=charge_mah(log.time_s, pred[:, 0]),
            charge_predicted_right_mah=charge_mah(log.time_s, pred[:, 1]),
            charge_measured_left_mah=measured[0],
            charge_measured_right_mah=measured[1],
            energy_predicted_wh=energy,
            has_currents=log.has_currents,
        ))
    return out
