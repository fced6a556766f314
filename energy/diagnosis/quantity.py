"""What a stage of the diagnosis explains: a :class:`Quantity`, the drive current (:data:`CURRENT`) or the battery
power (:data:`POWER`), with its units, its words and the keys ``diagnosis.json`` writes its figures under."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..battery import AS_PER_MAH
from ..logs import InteractionLog
from ..metrics import charge_mah

__all__ = ["AS_PER_MAH", "Quantity", "CURRENT", "POWER", "QUANTITIES"]



@dataclass(frozen=True)
class Quantity:
    """What a stage of the diagnosis explains: the drive current per side, or the battery power.

    Its units, its words and the keys ``diagnosis.json`` writes its figures under are data of
    the quantity: :class:`GapSummary` and :class:`WaterfallStep` hold the figures, their
    ``to_dict`` names them ``measured_mah`` or ``measured_wh``, ``rmse_a`` or ``rmse_w``.

    Attributes
    ----------
    name : str
        ``"current"`` or ``"power"`` (:data:`CURRENT`, :data:`POWER`).
    unit : str
        Unit of a sample and of the RMSE (``"A"``, ``"W"``).
    total_unit : str
        Unit of the integral over time (``"mAh"``, ``"Wh"``).
    total_name : str
        What the integral is called (``"charge"``, ``"energy"``): the error is ``{total_name}_error_pct``.
    unit_s_per_total : float
        Unit-seconds in one ``total_unit`` (3.6 A s per mAh, 3600 W s per Wh).
    columns : tuple of str
        The measured columns of a sample (``("left", "right")`` sides; ``("battery",)``).
    summary_fields : tuple of str
        The :class:`GapSummary` fields ``to_dict`` writes, in order.
    title : str
        The heading of its tables (``""`` for the current, the diagnosis' first quantity).
    rmse_digits, rmse_decimals : int
        The RMSE's significant digits in ``diagnosis.md``, its decimals in the printed table.
    """

    name: str
    unit: str
    total_unit: str
    total_name: str
    unit_s_per_total: float
    columns: tuple[str, ...]
    summary_fields: tuple[str, ...]
    title: str = ""
    rmse_digits: int = 3
    rmse_decimals: int = 3

    def key(self, field_name: str) -> str:
        """The ``diagnosis.json`` key of a :class:`GapSummary` / :class:`WaterfallStep` field."""
        if field_name in ("measured", "predicted", "gap"):
            return f"{field_name}_{self.total_unit.lower()}"
        if field_name == "error_pct":
            return f"{self.total_name}_error_pct"
        if field_name == "rmse":
            return f"rmse_{self.unit.lower()}"
        return field_name

    def measured(self, log: InteractionLog) -> np.ndarray:
        """The logged values of ``log``, ``(N, len(columns))`` (a new float64 array)."""
        if self.name == "current":
            return np.column_stack([log.current_left_a, log.current_right_a])
        return np.asarray(log.battery_power_w, dtype=np.float64)[:, None]

    def total(self, time_s: np.ndarray, values: np.ndarray, weights_s: np.ndarray) -> float:
        """The integral over time of ``values`` ``(N, C)``, summed over its columns, in ``total_unit``.

        Both quantities integrate by the trapezoid rule: the current as :func:`energy.metrics.charge_mah`
        per side, the power as the samples' trapezoid weights (:func:`~energy.diagnosis.gap.sample_weights_s`), each in its
        own order of sums, as ``diagnosis.json`` has always written them.
        """
        if self.name == "current":
            return sum(charge_mah(time_s, values[:, j]) for j in range(values.shape[1]))
        return float(weights_s @ values[:, 0]) / self.unit_s_per_total


#: The drive current of each side (A; its integral the charge, mAh).
CURRENT = Quantity("current", "A", "mAh", "charge", AS_PER_MAH, ("left", "right"),
                   ("measured", "predicted", "gap", "error_pct", "section_error_pct", "rmse", "n_runs", "n_samples",
                    "duration_s"))
#: The battery power, voltage x pack current (W; its integral the energy, Wh).
POWER = Quantity("power", "W", "Wh", "energy", 3600.0, ("battery",),
                 ("measured", "predicted", "gap", "error_pct", "section_error_pct", "rmse", "stopped_gap_pct",
                  "stopped_time_pct", "n_runs", "n_samples"), "battery power (voltage x pack current)", 4, 2)
#: The quantities by name.
QUANTITIES = {q.name: q for q in (CURRENT, POWER)}
