"""Mission budgets: predicted vs actual energy against a battery, and the battery power of a driven log.

:func:`energy_budget` compares a :class:`~energy.battery.Discharge` with a prediction and
gives an :class:`EnergyBudget` (predicted vs actual energy, reserve at arrival,
feasibility, where the pack runs out, per-segment breakdown). :func:`log_battery_power_w`
is the battery power of a log: the drive power of its two sides, derived from the logged
currents, plus the electronics (sensor and control board) of the robot's parameters,
computed exactly as the physics model does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from terrawatt_base.checks import check_bool, check_choice, check_int, check_real, readonly
from terrawatt_base.errors import InvalidParameterError

from .battery import AS_PER_MAH, S_PER_H, Battery, Discharge
from .ground import GroundParams
from .logs import InteractionLog
from .physics import PhysicsEnergyModel
from .robot import RobotParams

__all__ = ["EnergyBudget", "energy_budget", "log_battery_power_w", "CURRENT_CONVENTIONS"]

#: What the drive currents of a log measure (see :func:`log_battery_power_w`).
CURRENT_CONVENTIONS = ("motor", "battery")


@dataclass(frozen=True, eq=False, repr=False)
class EnergyBudget:
    """Predicted vs actual energy of a mission against a battery.

    Derived: ``predicted_energy_wh``, ``actual_energy_wh``, ``error_pct``, ``depleted``,
    ``predicted_depleted``, ``arrival_soc_pct``, ``arrival_energy_wh``, ``reserve_margin_pct``,
    ``reserve_margin_wh``, ``segment_error_pct``; :meth:`to_json_dict`.

    Attributes
    ----------
    battery : Battery
    predicted_energy_j, actual_energy_j : float
        Load energy (J) predicted before driving and measured (or simulated) while driving.
    predicted_charge_mah, actual_charge_mah : float
        Battery charge (mAh). The predicted charge draws the predicted energy at a constant
        power over the mission's duration (so it includes internal resistance and Peukert
        like the actual one).
    predicted_arrival_soc, arrival_soc : float
        State of charge at the end (fraction, never below 0), predicted and actual.
    duration_s : float
        Duration of the driven series (s).
    feasible : bool
        The actual SoC never went below the reserve.
    predicted_feasible : bool
        The predicted arrival SoC is at or above the reserve.
    reserve_crossed_time_s : float or None
        When the actual SoC reached the reserve (interpolated), or None.
    reserve_crossed_index : int or None
        First sample of the series below the reserve, or None.
    depleted_time_s, depleted_index : float or None, int or None
        When (interpolated) and at which sample the actual SoC reached 0 — the pack ran
        out and the series could not be driven on it (then ``feasible`` is False and
        ``arrival_soc`` is 0) — or None.
    predicted_depleted_time_s : float or None
        When the predicted draw (constant power) would run the pack out, or None.
    segment_predicted_j, segment_actual_j : ndarray, shape (S,)
        Per-segment breakdown (J); empty when no segments were given. The actual energy
        of a segment is the integral over the sample intervals that start in it, so the
        segments add up to ``actual_energy_j``.
    """

    battery: Battery
    predicted_energy_j: float
    actual_energy_j: float
    predicted_charge_mah: float
    actual_charge_mah: float
    predicted_arrival_soc: float
    arrival_soc: float
    duration_s: float
    feasible: bool
    predicted_feasible: bool
    reserve_crossed_time_s: float | None = None
    reserve_crossed_index: int | None = None
    segment_predicted_j: np.ndarray = field(default_factory=lambda: np.empty(0))
    segment_actual_j: np.ndarray = field(default_factory=lambda: np.empty(0))
    depleted_time_s: float | None = None
    depleted_index: int | None = None
    predicted_depleted_time_s: float | None = None

    def __post_init__(self) -> None:
        own = "EnergyBudget"
        if not isinstance(self.battery, Battery):
            raise InvalidParameterError(f"battery must be a Battery, got {type(self.battery).__name__!r}")
        for name in ("predicted_energy_j", "actual_energy_j", "predicted_charge_mah", "actual_charge_mah"):
            object.__setattr__(self, name, check_real(name, getattr(self, name), owner=own))
        for name in ("predicted_arrival_soc", "arrival_soc", "duration_s"):
            object.__setattr__(self, name, check_real(name, getattr(self, name), low=0.0, owner=own))
        for name in ("feasible", "predicted_feasible"):
            object.__setattr__(self, name, check_bool(f"{own}.{name}", getattr(self, name)))
        for time_name, index_name in (("reserve_crossed_time_s", "reserve_crossed_index"),
                                      ("depleted_time_s", "depleted_index")):
            when, idx = getattr(self, time_name), getattr(self, index_name)
            if (when is None) != (idx is None):
                raise InvalidParameterError(
                    f"{own}.{time_name} and {index_name} must both be set or both None, got {when!r} and {idx!r}"
                )
            if when is not None:
                object.__setattr__(self, time_name, check_real(time_name, when, owner=own))
                object.__setattr__(self, index_name, check_int(index_name, idx, low=0, owner=own))
        if self.predicted_depleted_time_s is not None:
            object.__setattr__(self, "predicted_depleted_time_s",
                               check_real("predicted_depleted_time_s", self.predicted_depleted_time_s, owner=own))
        if self.feasible == (self.reserve_crossed_index is not None):
            raise InvalidParameterError(
                f"{own}.feasible={self.feasible!r} contradicts reserve_crossed_index={self.reserve_crossed_index!r}"
            )
        if self.feasible and self.depleted_index is not None:
            raise InvalidParameterError(f"{own}.feasible=True contradicts depleted_index={self.depleted_index!r}")
        seg_p = readonly(self.segment_predicted_j, np.float64)
        seg_a = readonly(self.segment_actual_j, np.float64)
        if seg_p.ndim != 1 or seg_p.shape != seg_a.shape:
            raise InvalidParameterError(
                f"{own}.segment_predicted_j and segment_actual_j must be 1-D of equal length, got "
                f"{seg_p.shape!r} and {seg_a.shape!r}"
            )
        if not (np.all(np.isfinite(seg_p)) and np.all(np.isfinite(seg_a))):
            raise InvalidParameterError(f"{own} segment energies must be finite")
        object.__setattr__(self, "segment_predicted_j", seg_p)
        object.__setattr__(self, "segment_actual_j", seg_a)

    # ------------------------------------------------------------------ derived
    @property
    def predicted_energy_wh(self) -> float:
        """Predicted load energy (Wh)."""
        return self.predicted_energy_j / S_PER_H

    @property
    def actual_energy_wh(self) -> float:
        """Actual load energy (Wh)."""
        return self.actual_energy_j / S_PER_H

    @property
    def error_pct(self) -> float:
        """Prediction error ``100 (predicted - actual) / actual`` (%; positive: overestimate).
        NaN when the actual energy is 0."""
        if self.actual_energy_j == 0.0:
            return math.nan
        return 100.0 * (self.predicted_energy_j - self.actual_energy_j) / self.actual_energy_j

    @property
    def depleted(self) -> bool:
        """Whether the pack ran out while driving (see ``depleted_time_s``)."""
        return self.depleted_index is not None

    @property
    def predicted_depleted(self) -> bool:
        """Whether the predicted energy is more than the pack holds."""
        return self.predicted_depleted_time_s is not None

    @property
    def arrival_soc_pct(self) -> float:
        """Actual state of charge at the end (%)."""
        return 100.0 * self.arrival_soc

    @property
    def arrival_energy_wh(self) -> float:
        """Nominal energy left in the battery at the end, ``SoC C V`` (Wh)."""
        return self.arrival_soc * self.battery.energy_capacity_wh

    @property
    def reserve_margin_pct(self) -> float:
        """Arrival SoC minus the minimum reserve (percentage points; negative: reserve used)."""
        return self.arrival_soc_pct - self.battery.min_reserve_pct

    @property
    def reserve_margin_wh(self) -> float:
        """Nominal energy above the reserve at the end (Wh; negative: reserve used)."""
        return (self.arrival_soc - self.battery.reserve_soc) * self.battery.energy_capacity_wh

    @property
    def segment_error_pct(self) -> np.ndarray:
        """Per-segment ``100 (predicted - actual) / actual`` (%; NaN where actual is 0)."""
        a = self.segment_actual_j
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(a != 0.0, 100.0 * (self.segment_predicted_j - a) / np.where(a != 0.0, a, 1.0), np.nan)

    def to_json_dict(self) -> dict[str, Any]:
        """Plain JSON-ready values (units in the keys; NaN written as None)."""

        def num(x: float) -> float | None:
            return None if not math.isfinite(x) else float(x)

        b = self.battery
        return {
            "battery": {
                "capacity_ah": b.capacity_ah,
                "voltage_v": b.voltage_v,
                "min_reserve_pct": b.min_reserve_pct,
                "initial_soc": b.initial_soc,
                "internal_resistance_ohm": b.internal_resistance_ohm,
                "peukert_exponent": b.peukert_exponent,
                "peukert_reference_duration_s": b.peukert_reference_duration_s,
            },
            "predicted_energy_j": self.predicted_energy_j,
            "predicted_energy_wh": self.predicted_energy_wh,
            "predicted_charge_mah": self.predicted_charge_mah,
            "actual_energy_j": self.actual_energy_j,
            "actual_energy_wh": self.actual_energy_wh,
            "actual_charge_mah": self.actual_charge_mah,
            "error_pct": num(self.error_pct),
            "duration_s": self.duration_s,
            "predicted_arrival_soc_pct": 100.0 * self.predicted_arrival_soc,
            "arrival_soc_pct": self.arrival_soc_pct,
            "arrival_energy_wh": self.arrival_energy_wh,
            "reserve_margin_pct": self.reserve_margin_pct,
            "reserve_margin_wh": self.reserve_margin_wh,
            "feasible": self.feasible,
            "predicted_feasible": self.predicted_feasible,
            "reserve_crossed_time_s": self.reserve_crossed_time_s,
            "reserve_crossed_index": self.reserve_crossed_index,
            "depleted_time_s": self.depleted_time_s,
            "depleted_index": self.depleted_index,
            "predicted_depleted_time_s": self.predicted_depleted_time_s,
            "segment_predicted_j": self.segment_predicted_j.tolist(),
            "segment_actual_j": self.segment_actual_j.tolist(),
            "segment_error_pct": [num(x) for x in self.segment_error_pct.tolist()],
        }

    def __repr__(self) -> str:
        return (
            f"EnergyBudget(predicted_wh={self.predicted_energy_wh:.3f}, actual_wh={self.actual_energy_wh:.3f}, "
            f"error_pct={self.error_pct:.2f}, arrival_soc_pct={self.arrival_soc_pct:.2f}, "
            f"feasible={self.feasible}, reserve_crossed_time_s={self.reserve_crossed_time_s!r}"
            + (f", depleted_time_s={self.depleted_time_s!r})" if self.depleted else ")")
        )


def energy_budget(
    discharge: Discharge,
    predicted_energy_j: float,
    *,
    segment_index: Any = None,
    segment_predicted_j: Any = None,
) -> EnergyBudget:
    """Compare a discharge with a prediction: errors, reserve at arrival, feasibility, segments.

    Parameters
    ----------
    discharge : Discharge
        The driven (actual) series, from :func:`discharge_from_power`.
    predicted_energy_j : float
        Predicted load energy of the whole series (J), >= 0.
    segment_index : array_like of int, shape (N,), optional
        Segment of each sample (``0 .. S-1``, non-decreasing not required). The interval
        ``[t_i, t_{i+1}]`` belongs to the segment of sample ``i``.
    segment_predicted_j : array_like, shape (S,), optional
        Predicted energy of each segment (J); required with ``segment_index``.

    Returns
    -------
    EnergyBudget

    Raises
    ------
    InvalidParameterError
        ``discharge`` not a Discharge; negative or non-finite prediction; segment arrays of
        wrong shape, negative, or an index outside ``0 .. S-1``; only one of the two
        segment arguments given.

    Examples
    --------
    >>> from energy import discharge_from_power
    >>> b = Battery(capacity_ah=1.0, voltage_v=10.0, min_reserve_pct=50.0)
    >>> d = discharge_from_power(b, [0.0, 3600.0], [6.0, 6.0])   # 6 Wh of 10 Wh
    >>> budget = energy_budget(d, predicted_energy_j=4.0 * 3600.0)
    >>> budget.feasible, budget.predicted_feasible, round(budget.reserve_crossed_time_s, 6)
    (False, True, 3000.0)
    """
    if not isinstance(discharge, Discharge):
        raise InvalidParameterError(f"discharge must be a Discharge, got {type(discharge).__name__!r}")
    pred = check_real("predicted_energy_j", predicted_energy_j, low=0.0)
    battery = discharge.battery
    t = discharge.time_s
    duration = float(t[-1] - t[0])
    # Predicted charge: the predicted energy at constant power over the same duration.
    p_mean = pred / duration if duration > 0 else 0.0
    i_mean = float(battery.current_a(p_mean))
    pred_charge_as = i_mean * duration
    pred_eff_as = float(battery.effective_current_a(i_mean)) * duration
    pred_soc = battery.initial_soc - pred_eff_as / (battery.capacity_ah * S_PER_H)
    # The constant draw empties the pack (linearly in time) before the end: when?
    pred_depleted = (float(t[0]) + duration * battery.initial_soc / (battery.initial_soc - pred_soc)
                     if pred_soc <= 0.0 else None)

    if (segment_index is None) != (segment_predicted_j is None):
        raise InvalidParameterError(
            "segment_index and segment_predicted_j must be given together, got "
            f"segment_index={'None' if segment_index is None else 'array'}, "
            f"segment_predicted_j={'None' if segment_predicted_j is None else 'array'}"
        )
    seg_pred = np.empty(0)
    seg_act = np.empty(0)
    if segment_index is not None:
        seg_pred = np.asarray(segment_predicted_j, dtype=np.float64)
        if seg_pred.ndim != 1 or not np.all(np.isfinite(seg_pred)) or np.any(seg_pred < 0):
            raise InvalidParameterError(
                f"segment_predicted_j must be a 1-D array of finite energies >= 0, got {seg_pred!r:.120}"
            )
        idx = np.asarray(segment_index)
        if idx.shape != t.shape or idx.dtype.kind not in "iu":
            raise InvalidParameterError(
                f"segment_index must be integers of shape {t.shape!r}, got dtype {idx.dtype!s} shape {idx.shape!r}"
            )
        s = seg_pred.size
        if np.any((idx < 0) | (idx >= s)):
            bad = idx[(idx < 0) | (idx >= s)][:3]
            raise InvalidParameterError(f"segment_index must lie in [0, {s - 1}], got {bad!r}")
        step_j = np.diff(discharge.energy_j)
        seg_act = np.bincount(idx[:-1].astype(np.intp), weights=step_j, minlength=s).astype(np.float64)

    return EnergyBudget(
        battery=battery,
        predicted_energy_j=pred,
        actual_energy_j=discharge.total_energy_j,
        predicted_charge_mah=pred_charge_as / AS_PER_MAH,
        actual_charge_mah=discharge.total_charge_mah,
        predicted_arrival_soc=max(pred_soc, 0.0),
        arrival_soc=discharge.final_soc,
        duration_s=duration,
        feasible=not discharge.reserve_crossed,
        predicted_feasible=pred_soc >= battery.reserve_soc,
        reserve_crossed_time_s=discharge.reserve_crossed_time_s,
        reserve_crossed_index=discharge.reserve_crossed_index,
        segment_predicted_j=seg_pred,
        segment_actual_j=seg_act,
        depleted_time_s=discharge.depleted_time_s,
        depleted_index=discharge.depleted_index,
        predicted_depleted_time_s=pred_depleted,
    )


# A ground for electronics-only power: with every force effect off its coefficients are unused.
_NO_GROUND = GroundParams(name="electronics_only", static_friction_coef=1.0, coulomb_friction_coef=1.0,
                          rolling_resistance_coef=0.0)


def log_battery_power_w(
    log: InteractionLog,
    robot: RobotParams,
    *,
    current_convention: str = "motor",
    electronics: bool = True,
    current_offset_a: float | None = None,
) -> np.ndarray:
    """Battery-side power (W) of every drive sample of a log: drive sides plus electronics.

    The same bookkeeping as :class:`~energy.physics.PhysicsEnergyModel`'s
    ``total_power_w``, so an energy predicted with that model (e.g. a planner's edge
    costs) and the energy of a driven log compare like with like.

    ``current_convention`` says what the logged side currents are:

    - ``"motor"`` (default; the Husky driver, BorealTC, :class:`~energy.sim.TruthSimulator`):
      the *motoring* armature current ``I_m`` of each side (positive while the motor drives
      its wheels in either direction, negative while back-driven). The side's electrical
      power is ``V_m I_m`` with the terminal voltage ``V_m = Ke |omega_m| + Ra I_m``; the
      motor speed comes from the log's speeds through the ICR kinematics,
      ``omega_m = N |v -/+ omega chi B / 2| / r``, capped at ``motor.max_speed_radps``
      (wheel slip is not observable in a log and is neglected: a slipping wheel spins a
      little faster, so this slightly underestimates). Negative side power counts times
      ``robot.regen_efficiency``, as in the physics model.
    - ``"battery"`` (e.g. Jackal's bridge feedback): battery-side bridge currents; the drive
      power is ``battery_voltage_v * (I_left + I_right)``, with the log's measured
      ``battery_voltage_v`` where it has one (e.g. read from a status message), else the
      robot's nominal voltage.

    With ``electronics`` the robot's sensor power (``sensor_power_w`` plus
    ``sensor_power_per_mps_w * |v|``) and control-board power (standby / start-up / stable,
    from the log's speeds and times) are added; the logged drive currents do not hold them.

    The current sensor's rest offset (``current_offset_a``, default the robot's
    ``rest_current_a``) is a measurement, never paid by the battery: it is subtracted from
    the logged currents first (a clamped side that logged 0 then counts as back-driven,
    i.e. nothing without regeneration).

    Parameters
    ----------
    log : InteractionLog
    robot : RobotParams
        The robot that drove the log (motor constants, geometry, electronics).
    current_convention : {"motor", "battery"}
    electronics : bool
        Add the sensor and control-board power.
    current_offset_a : float, optional
        What the sensor logs at rest (A, >= 0); ``None``: ``robot.rest_current_a``.

    Returns
    -------
    numpy.ndarray, shape (N,)

    Raises
    ------
    InvalidParameterError
        ``log`` or ``robot`` of the wrong type.
    UnknownNameError
        ``current_convention`` not in :data:`CURRENT_CONVENTIONS`.

    Examples
    --------
    >>> from energy import InteractionLog, robot_preset
    >>> robot = robot_preset("husky")
    >>> log = InteractionLog([0.0, 1.0], [0.0, 0.0], [0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [0.0, 1.0], [9.8, 9.8])
    >>> p = log_battery_power_w(log, robot, current_convention="battery", electronics=False)
    >>> bool(np.allclose(p, (3.0 - 2 * robot.rest_current_a) * robot.battery_voltage_v))  # the rest offset is not paid
    True
    """
    if not isinstance(log, InteractionLog):
        raise InvalidParameterError(f"log must be an InteractionLog, got {type(log).__name__!r}")
    if not isinstance(robot, RobotParams):
        raise InvalidParameterError(f"robot must be a RobotParams, got {type(robot).__name__!r}")
    check_choice("current_convention", current_convention, CURRENT_CONVENTIONS)
    log.require_currents("log_battery_power_w")
    offset = robot.rest_current_a if current_offset_a is None else check_real("current_offset_a", current_offset_a,
                                                                              low=0.0)
    currents = np.column_stack([log.current_left_a, log.current_right_a]) - offset  # (N, 2) [left, right]
    if current_convention == "battery":
        volts = robot.battery_voltage_v if log.battery_voltage_v is None else log.battery_voltage_v
        drive = volts * currents.sum(axis=1)
    else:
        mo = robot.motor
        half = robot.track_width_multiplier * robot.track_width_m / 2.0
        v_side = log.v_mps[:, None] + log.omega_radps[:, None] * half * np.array([-1.0, 1.0])
        omega_m = np.minimum(mo.gear_ratio * np.abs(v_side) / robot.wheel_radius_m, mo.max_speed_radps)
        side = (mo.back_emf_v_s_per_rad * omega_m + mo.armature_resistance_ohm * currents) * currents
        drive = np.where(side >= 0.0, side, robot.regen_efficiency * side).sum(axis=1)
    if not electronics:
        return drive
    model = PhysicsEnergyModel(robot, effects=("sensor", "control"))
    extra = model.power(log.v_mps, log.omega_radps, _NO_GROUND, time_s=log.time_s).total_power_w
    return drive + extra
